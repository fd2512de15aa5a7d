"""Blender operators: thin adapters between meshes and ``core``."""

import importlib.util

import bpy

from . import mesh_smooth

_modules = [mesh_smooth]
# Point-cloud smoothing lives in its own module; register it when it is part of this build.
if importlib.util.find_spec(__name__ + ".point_cloud") is not None:
    from . import point_cloud

    _modules.append(point_cloud)

classes = tuple(cls for module in _modules for cls in module.classes)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
