"""The command line: `blender -b -c hc_smooth INPUT... -o OUTDIR` (see docs/command_line.md).

register() hands ``command.main`` to Blender's command registry (bpy.utils.register_cli_command,
Blender 4.2+), so the command exists while the extension is enabled.
"""

import bpy

from .command import main

COMMAND = "hc_smooth"
_handle = None


def register():
    global _handle
    _handle = bpy.utils.register_cli_command(COMMAND, main)


def unregister():
    global _handle
    if _handle is not None:
        bpy.utils.unregister_cli_command(_handle)
        _handle = None
