"""Call HC Smooth's core directly on NumPy arrays from a `blender -b --python` script.

    blender -b scene.blend --python examples/smooth_arrays_with_core.py -- Scan
    blender -b --python examples/smooth_arrays_with_core.py          (a noisy sphere, for a try)

With Blender as a Python module (`pip install bpy`; HC Smooth installed with
`python scripts/hc_smooth_bpy.py install ZIP`, see docs/python_api.md), the same two runs:

    python scripts/hc_smooth_bpy.py run scene.blend examples/smooth_arrays_with_core.py -- Scan
    python scripts/hc_smooth_bpy.py run examples/smooth_arrays_with_core.py

The core (hc_smooth, laplacian_smooth, measure_change) needs only NumPy and SciPy: read positions
and edges in bulk, smooth, write back. It is importable from the installed extension, whose
module name depends on the repository it was installed into (bl_ext.<repository>.hc_smooth).
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


def main():
    core = hc_smooth_package().core
    args = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    if args:
        mesh = bpy.data.objects[args[0]].data
    else:
        bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=4)
        mesh = bpy.context.active_object.data

    positions = np.empty((len(mesh.vertices), 3), dtype=np.float32)
    mesh.vertices.foreach_get("co", positions.ravel())
    edges = np.empty((len(mesh.edges), 2), dtype=np.int32)
    mesh.edges.foreach_get("vertices", edges.ravel())
    faces = [tuple(polygon.vertices) for polygon in mesh.polygons]
    if not args:  # the try-out sphere: make it noisy
        positions += np.random.default_rng(0).normal(scale=0.02, size=positions.shape).astype(np.float32)

    # What the operator runs: the Automatic Amount chooses the iterations from the noise (numbers given
    # to smooth_mesh, as to the operator, are used exactly instead).
    automatic, report = core.smooth_mesh(positions, edges, faces=faces, return_report=True)
    print(f"Automatic Amount: {report.iterations} iterations, alpha {report.alpha:g}, beta {report.beta:g}")
    hc = core.hc_smooth(positions, edges, alpha=0.1, beta=0.6, iterations=10)
    laplacian = core.laplacian_smooth(positions, edges, iterations=10)
    for label, result in (("Automatic", automatic), ("HC", hc), ("Laplacian", laplacian)):
        print(f"{label:10s} {core.measure_change(positions, result, faces=faces).summary()}")

    mesh.vertices.foreach_set("co", automatic.ravel())
    mesh.update()


if __name__ == "__main__":
    main()
