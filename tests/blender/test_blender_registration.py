"""Enable, disable, enable: everything registers and unregisters cleanly."""

import addon_utils
import bpy
from blender_scene import ADDON

OPERATOR_TYPES = ("OBJECT_OT_hc_smooth", "MESH_OT_hc_smooth")


def test_enable_disable_enable(addon):
    assert all(hasattr(bpy.types, name) for name in OPERATOR_TYPES)
    bpy.ops.preferences.addon_disable(module=ADDON)
    assert not any(hasattr(bpy.types, name) for name in OPERATOR_TYPES)
    assert not hasattr(bpy.types.Scene, "hc_smooth")
    bpy.ops.preferences.addon_enable(module=ADDON)
    assert all(hasattr(bpy.types, name) for name in OPERATOR_TYPES)
    assert addon_utils.check(ADDON)[1]  # loaded
