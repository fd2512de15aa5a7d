"""Smooth meshes from a `blender -b --python` script with the HC Smooth operators.

    blender -b scene.blend --python examples/smooth_with_operators.py -- Scan smoothed.blend
    blender -b --python examples/smooth_with_operators.py          (a noisy sphere, for a try)

With Blender as a Python module (`pip install bpy`; HC Smooth installed with
`python scripts/hc_smooth_bpy.py install ZIP`, see docs/python_api.md), the same two runs:

    python scripts/hc_smooth_bpy.py run scene.blend examples/smooth_with_operators.py -- Scan smoothed.blend
    python scripts/hc_smooth_bpy.py run examples/smooth_with_operators.py

Arguments: the object to smooth (default: a noisy try-out sphere) and, optionally, a .blend file
to save a copy of the result to.

Shows: object.hc_smooth on chosen objects through bpy.context.temp_override (a background
Blender has no selection you can rely on), a fixed vertex group, output into a new shape key,
and mesh.hc_smooth in Edit mode on the selected vertices only.
"""

import importlib
import os
import sys

import bpy
import numpy as np


def hc_smooth_package():
    """The installed HC Smooth package, bl_ext.<repository>.hc_smooth, enabled if it is not yet:
    Blender enables installed extensions at start-up, the bpy module does not."""
    for name in bpy.context.preferences.addons.keys():
        if name.startswith("bl_ext.") and name.endswith(".hc_smooth"):
            return importlib.import_module(name)
    for repo in bpy.context.preferences.extensions.repos:
        if repo.enabled and os.path.isdir(os.path.join(repo.directory, "hc_smooth")):
            bpy.ops.preferences.addon_enable(module=f"bl_ext.{repo.module}.hc_smooth")
            return importlib.import_module(f"bl_ext.{repo.module}.hc_smooth")
    raise SystemExit(
        f"HC Smooth is not installed in this Blender's user folder ({bpy.utils.resource_path('USER')}): "
        "install the zip (Preferences > Get Extensions > Install from Disk, or "
        "`python scripts/hc_smooth_bpy.py install ZIP` for the bpy module)"
    )


def script_arguments():
    return sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []


def noisy_sphere(name="Scan"):
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=4, radius=1.0)
    obj = bpy.context.active_object
    obj.name = name
    co = np.empty(len(obj.data.vertices) * 3, dtype=np.float32)
    obj.data.vertices.foreach_get("co", co)
    co += np.random.default_rng(0).normal(scale=0.02, size=co.shape).astype(np.float32)
    obj.data.vertices.foreach_set("co", co)
    obj.data.update()
    return obj


def main():
    hc_smooth_package()  # registers bpy.ops.object.hc_smooth and bpy.ops.mesh.hc_smooth
    args = script_arguments()
    obj = bpy.data.objects[args[0]] if args else noisy_sphere()

    # 1. Object mode: the operator smooths every *selected* mesh object, so say which ones.
    with bpy.context.temp_override(
        active_object=obj, object=obj, selected_objects=[obj], selected_editable_objects=[obj]
    ):
        bpy.ops.object.hc_smooth(method="HC", alpha=0.1, beta=0.6, iterations=10)

    # 2. Keep the top of the object in place: vertices of a group stay fixed (to the bit).
    group = obj.vertex_groups.get("Fixed") or obj.vertex_groups.new(name="Fixed")
    top = [v.index for v in obj.data.vertices if v.co.z > 0.5]
    group.add(top, 1.0, "REPLACE")
    # ... and write the result into a new shape key instead of moving the mesh.
    with bpy.context.temp_override(
        active_object=obj, object=obj, selected_objects=[obj], selected_editable_objects=[obj]
    ):
        bpy.ops.object.hc_smooth(iterations=20, vertex_group="Fixed", output="SHAPE_KEY")
    print("shape keys:", [key.name for key in obj.data.shape_keys.key_blocks])
    obj.shape_key_clear()

    # 3. Edit mode: only the selected, visible vertices move.
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.mesh.hc_smooth(iterations=5, pin_boundary=True)
    bpy.ops.object.mode_set(mode="OBJECT")

    if len(args) > 1:
        bpy.ops.wm.save_as_mainfile(filepath=args[1], copy=True)
    print(f"smoothed '{obj.name}' ({len(obj.data.vertices)} vertices)")


if __name__ == "__main__":
    main()
