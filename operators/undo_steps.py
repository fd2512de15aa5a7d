"""Which undo step Ctrl+Z takes back next, by its name.

Blender keeps its undo history out of the Python API; ``WindowManager.print_undo_steps()`` prints it
(BKE_undosys_print: one line per step, the active one marked ``*``), so the name is read from that print.
"""

import re

from ..console_capture import captured

# [*#MS]  index {address} type='Global Undo', name='HC Smooth'  (the marks: active, applied, memfile, skip)
_STEP = re.compile(r"^\[(?P<active>.)...\]\s+\d+\s+\{[^}]*\}\s+type='.*?', name='(?P<name>.*)'$")


def active_step_name(window_manager):
    """The name of the active undo step (what Ctrl+Z takes back), or None where it cannot be read (no undo
    history, or no console output to read it from)."""
    with captured() as lines:
        window_manager.print_undo_steps()
    return parse_active_step(lines)


def parse_active_step(lines):
    """The active step's name in the lines of print_undo_steps(), or None."""
    for line in lines:
        match = _STEP.match(line.strip())
        if match and match["active"] == "*":
            return match["name"]
    return None
