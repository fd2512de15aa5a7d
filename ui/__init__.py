"""Scene settings, the N-panel, menu entries and presets (no algorithm: the buttons call the operators; the
settings are drawn by operators/draw.py, as the operators' redo panels are).

Nothing is imported here: the modules that register (settings, preset, fixed, panel) import operators/,
which imports nothing from ui/; the add-on's __init__ registers them.
"""
