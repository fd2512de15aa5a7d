"""Render docs/images/modifier.png: a noisy closed Suzanne before and after the HC Smooth modifier (default
settings), coloured by the signed distance to the clean surface (Cycles, headless bpy).

    .envs/bpy45/bin/python docs/render_modifier_picture.py [--output docs/images/modifier.png]

The scene, the colour map and the legend are the demo's (demo/scene_setup.py). The modifier stays live: the
picture is what Blender evaluates, with the distance computed from the evaluated positions.
"""

import argparse
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "scripts"), str(ROOT / "demo"), str(ROOT)]  # scene_setup imports core

from extension_session import ADDON, install_extension, run_and_exit  # noqa: E402  (before bpy)

# isort: split

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import scene_setup  # noqa: E402

ITERATIONS = 10
NOISE = 0.004  # of the bounding-box diagonal, along the normals
COLOUR_LIMIT = 1.0  # % of the diagonal at the ends of the colour scale
SEED = 7


def evaluated_positions(obj):
    depsgraph = bpy.context.evaluated_depsgraph_get()
    depsgraph.update()
    return scene_setup.positions(obj.evaluated_get(depsgraph).data).astype(np.float64)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default=str(ROOT / "docs" / "images" / "modifier.png"))
    parser.add_argument("--samples", type=int, default=16)
    args = parser.parse_args()
    install_extension(ROOT / "build" / "docs")
    core = sys.modules[ADDON + ".core"]

    bpy.ops.wm.read_homefile(use_empty=True)
    noisy = scene_setup.closed_suzanne(level=3)
    clean = scene_setup.positions(noisy.data).astype(np.float64)
    faces = scene_setup.faces(noisy.data)
    triangles = core.fan_triangles(faces)
    diagonal = float(np.linalg.norm(clean.max(axis=0) - clean.min(axis=0)))
    scene_setup.add_normal_noise(noisy, NOISE * diagonal, np.random.default_rng(SEED))
    noisy.name = noisy.data.name = "Noisy"

    # Farther apart than the demo's heads: the legend's end labels need the width.
    hc = scene_setup.copy_object(noisy, "HC Smooth modifier", (1.35 * scene_setup.SPACING, 0, 0))
    scene_setup.select_only(hc)
    assert bpy.ops.object.hc_smooth_modifier_add(iterations=ITERATIONS) == {"FINISHED"}

    surface = scene_setup.CleanSurface(clean, faces)
    clean_volume = core.enclosed_volume(clean, triangles)
    labels = {}
    for obj, title in ((noisy, f"Noisy, \u03c3 {NOISE:.1%}"), (hc, f"HC Smooth, {ITERATIONS} iterations")):
        points = evaluated_positions(obj)
        signed = surface.signed_distance(points)
        # On the original mesh: the modifiers pass point attributes through to what is rendered.
        scene_setup.set_point_attribute(obj, scene_setup.ERROR_ATTRIBUTE, 100 * signed / diagonal)
        volume = core.enclosed_volume(points, triangles) / clean_volume - 1
        rms = 100 * float(np.sqrt(np.mean(signed**2))) / diagonal
        labels[obj] = f"{title}\nvolume {100 * volume:+.1f} %\nRMS distance {rms:.2f} %"
        print(labels[obj].replace("\n", ", "))
    outline = scene_setup.outline_segments(surface, clean, faces)  # the clean shape's contour, over the result
    bpy.context.scene.render.image_settings.compression = 100  # the smallest PNG: it goes into the repository
    scene_setup.render_error_figure(
        [(obj, labels[obj]) for obj in (noisy, hc)],
        outline,
        [hc],
        args.output,
        limit=COLOUR_LIMIT,
        samples=args.samples,
        resolution=(820, 520),
        legend_title="signed distance to the clean surface, % of the diagonal; yellow: the clean outline",
    )
    print(f"picture: {args.output}")


if __name__ == "__main__":
    run_and_exit(main)
