"""Blender operators: thin adapters between meshes and ``core``."""

import bpy

from . import mesh_smooth, modifier, point_cloud

classes = (*mesh_smooth.classes, *point_cloud.classes, *modifier.classes)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
