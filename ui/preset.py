"""Presets of the scene settings through Blender's own preset system.

Shipped presets live in ``ui/presets/hc_smooth/*.py`` and are found through
``bpy.utils.register_preset_path`` (Blender treats extension folders as read-only, so they cannot be
overwritten or deleted from the menu); presets the user adds go to the user's
``scripts/presets/hc_smooth`` folder, as for any Blender preset.
"""

import os

import bpy
from bl_operators.presets import AddPresetBase

from .settings import PRESET_SETTINGS

PRESET_SUBDIR = "hc_smooth"
# The folder that holds ``presets/hc_smooth`` (the layout register_preset_path expects).
PRESET_ROOT = os.path.dirname(os.path.abspath(__file__))


class HC_SMOOTH_MT_presets(bpy.types.Menu):
    bl_label = "HC Smooth Presets"
    bl_description = "Apply stored HC Smooth settings"
    preset_subdir = PRESET_SUBDIR
    preset_operator = "script.execute_preset"
    draw = bpy.types.Menu.draw_preset


class HC_SMOOTH_OT_preset_add(AddPresetBase, bpy.types.Operator):
    """Store the current HC Smooth settings as a preset, or remove the active one"""

    bl_idname = "hc_smooth.preset_add"
    bl_label = "Add HC Smooth Preset"
    preset_menu = "HC_SMOOTH_MT_presets"
    preset_subdir = PRESET_SUBDIR
    preset_defines = ["settings = bpy.context.scene.hc_smooth"]
    preset_values = [f"settings.{name}" for name in PRESET_SETTINGS]


classes = (HC_SMOOTH_MT_presets, HC_SMOOTH_OT_preset_add)


def register():
    bpy.utils.register_preset_path(PRESET_ROOT)


def unregister():
    bpy.utils.unregister_preset_path(PRESET_ROOT)
