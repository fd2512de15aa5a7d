"""Scene-level settings (``scene.hc_smooth``) that the panel and menu entries hand to the operators.

Built from the same declarations as the operators' properties (settings_spec.MESH, through
operators/properties.py), so a button copies them one to one.
"""

import bpy

from .. import settings_spec
from ..operators.properties import annotations

# The settings a button passes on (all of them) and those a preset stores: the strength of the smoothing,
# not the choices that belong to one mesh (vertex group, boundary, output).
OPERATOR_SETTINGS = tuple(setting.name for setting in settings_spec.MESH)
PRESET_SETTINGS = tuple(setting.name for setting in settings_spec.MESH_SMOOTHING)
MODIFIER_SETTINGS = tuple(setting.name for setting in settings_spec.MODIFIER)  # what an Add Modifier button takes


class HCSmoothSettings(bpy.types.PropertyGroup):
    __annotations__ = annotations(settings_spec.MESH)

    def copy_to(self, properties, names=OPERATOR_SETTINGS):
        """Set these settings on an operator's properties (a button's OperatorProperties). What the
        operator takes as set it uses as given, so with the Automatic Amount on, the settings it chooses
        are passed only where the user changed them, and Alpha and Iterations (greyed out) never."""
        changed = [name for name in settings_spec.CHOSEN if self.is_property_set(name)]
        passed = settings_spec.passed_by_panel(settings_spec.values_of(self, settings_spec.MESH), changed)
        for name in names:
            if name in passed:
                setattr(properties, name, getattr(self, name))


classes = (HCSmoothSettings,)


def register():
    bpy.types.Scene.hc_smooth = bpy.props.PointerProperty(type=HCSmoothSettings, name="HC Smooth")


def unregister():
    del bpy.types.Scene.hc_smooth
