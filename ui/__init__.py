"""Scene settings, the N-panel, menu entries and presets (no algorithm: the buttons call the operators), and
draw.py: how every panel draws the settings, the operators' redo panels too.

Nothing is imported here: the operators import ui.draw, and the modules that register (settings, preset,
fixed, panel) import operators/; the add-on's __init__ registers them.
"""
