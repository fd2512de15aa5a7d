"""Scene settings, the N-panel, menu entries and presets (no algorithm: the buttons call the operators)."""

import bpy

from . import fixed, panel, preset, settings

classes = (settings.HCSmoothSettings, *preset.classes, *fixed.classes, *panel.classes)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    settings.register()
    preset.register()
    fixed.register()
    panel.register()


def unregister():
    panel.unregister()
    fixed.unregister()
    preset.unregister()
    settings.unregister()
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
