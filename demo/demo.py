"""The main job: a headless demo of HC Smooth on a built-in default (run with a Python that has bpy).

    python demo/demo.py [--output-dir demo_output] [--iterations 30] [--noise 0.004] [--alpha 0.05] [--beta 0.6] [--no-render]

Builds the extension zip with Blender's own tool and installs it into a throw-away Blender user
folder, exactly as a user would. Then it takes Blender's Suzanne, subdivided (Catmull-Clark, level 3),
adds Gaussian noise along the normals (σ = --noise × bounding-box diagonal, fixed seed), and smooths
three copies with the installed operator: plain Laplacian, HC, and HC in sequential mode, the same
number of iterations each. It prints a table of volume change and error to the clean shape, saves
the scene as a .blend and renders noisy / Laplacian / HC side by side with Cycles on the CPU.
"""

import argparse
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "scripts"), str(ROOT / "demo")]

from extension_session import install_extension, run_and_exit  # noqa: E402  (before bpy: user folder)

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import core  # noqa: E402  (the same code the extension carries; used here for the metrics only)
import scene_setup  # noqa: E402

SEED = 7


def smooth_copy(source, name, location, **operator_args):
    """A copy of ``source`` smoothed by bpy.ops.object.hc_smooth; returns (object, seconds)."""
    obj = scene_setup.copy_object(source, name, location)
    scene_setup.select_only(obj)
    start = time.perf_counter()
    result = bpy.ops.object.hc_smooth(**operator_args)
    seconds = time.perf_counter() - start
    if result != {"FINISHED"}:
        raise SystemExit(f"object.hc_smooth({operator_args}) returned {result}")
    return obj, seconds


def error_to_clean(positions, clean, diagonal):
    """RMS and max distance of each vertex to its own clean position, in % of the diagonal."""
    distance = np.linalg.norm(positions.astype(np.float64) - clean, axis=1)
    return 100 * np.sqrt(np.mean(distance**2)) / diagonal, 100 * distance.max() / diagonal


def print_table(rows, clean_volume):
    header = ("shape", "iterations", "volume", "volume change", "RMS error", "max error", "time")
    lines = [header]
    for name, iterations, volume, rms, worst, seconds in rows:
        change = "" if volume is None else f"{100 * (volume / clean_volume - 1):+.2f} %"
        lines.append((name, str(iterations), f"{volume:.5f}", change, f"{rms:.3f} %", f"{worst:.3f} %",
                      "" if seconds is None else f"{seconds:.2f} s"))
    widths = [max(len(line[i]) for line in lines) for i in range(len(header))]
    for index, line in enumerate(lines):
        print("  ".join(cell.ljust(width) if i == 0 else cell.rjust(width)
                        for i, (cell, width) in enumerate(zip(line, widths))))
        if index == 0:
            print("  ".join("-" * width for width in widths))
    print("volume change: against the clean shape's volume; errors: distance of each vertex to its clean "
          "position, in % of the bounding-box diagonal")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output-dir", default=str(ROOT / "demo_output"))
    parser.add_argument("--iterations", type=int, default=30)
    parser.add_argument("--alpha", type=float, default=0.05, help="HC alpha")
    parser.add_argument("--beta", type=float, default=0.6, help="HC beta")
    parser.add_argument("--noise", type=float, default=0.004, help="σ as a fraction of the bbox diagonal")
    parser.add_argument("--samples", type=int, default=16, help="Cycles samples per pixel")
    parser.add_argument("--no-render", action="store_true", help="skip the picture (the table only)")
    args = parser.parse_args()
    output = pathlib.Path(args.output_dir).resolve()
    output.mkdir(parents=True, exist_ok=True)

    zip_path = install_extension(output / "build")
    print(f"installed {pathlib.Path(zip_path).name} into a clean Blender {bpy.app.version_string} user folder")

    bpy.ops.wm.read_homefile(use_empty=True)
    clean_obj = scene_setup.subdivided_suzanne(level=3)
    clean = scene_setup.positions(clean_obj.data).astype(np.float64)
    faces = scene_setup.faces(clean_obj.data)
    diagonal = float(np.linalg.norm(clean.max(axis=0) - clean.min(axis=0)))
    # The clean shape is kept as arrays; the object itself becomes the noisy scan.
    noisy = scene_setup.add_normal_noise(clean_obj, args.noise * diagonal, np.random.default_rng(SEED))
    noisy.name = noisy.data.name = "Noisy"
    print(f"Suzanne, subdivided: {len(clean)} vertices, {len(faces[0]) - 1} faces; noise σ = {args.noise:.2%} of the "
          f"diagonal along the normals (seed {SEED})")

    spacing = 2.9
    common = dict(iterations=args.iterations, mode="SIMULTANEOUS")
    laplacian, t_lap = smooth_copy(noisy, "Laplacian", (spacing, 0, 0), method="LAPLACIAN", **common)
    hc, t_hc = smooth_copy(noisy, "HC", (2 * spacing, 0, 0), method="HC", alpha=args.alpha, beta=args.beta,
                          **common)
    hc_seq, t_seq = smooth_copy(noisy, "HC sequential", (3 * spacing, 0, 0), method="HC", alpha=args.alpha,
                                beta=args.beta, iterations=args.iterations, mode="SEQUENTIAL")
    hc_seq.hide_render = True  # the picture shows three: noisy, Laplacian, HC

    triangles = core.metrics.fan_triangles(faces)
    if not core.topology.closed_from_triangles(triangles):
        print("(Suzanne is not watertight: volumes are the signed volumes of its faces, which still show shrinkage)")

    def volume(points):
        return core.metrics.enclosed_volume(points.astype(np.float64), triangles)

    clean_volume = volume(clean)
    rows = [("clean", 0, clean_volume, 0.0, 0.0, None)]
    for obj, iterations, seconds in ((noisy, 0, None), (laplacian, args.iterations, t_lap),
                                     (hc, args.iterations, t_hc), (hc_seq, args.iterations, t_seq)):
        points = scene_setup.positions(obj.data)
        rows.append((obj.name, iterations, volume(points), *error_to_clean(points, clean, diagonal), seconds))
    print()
    print_table(rows, clean_volume)

    blend_path = output / "hc_smooth_demo.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend_path), check_existing=False)
    print(f"\nscene: {blend_path}")
    if not args.no_render:
        image = output / "comparison.png"
        start = time.perf_counter()
        volume_of = {row[0]: row[2] for row in rows}
        labels = [f"{obj.name}\nvolume {100 * (volume_of[obj.name] / clean_volume - 1):+.1f} %"
                  for obj in (noisy, laplacian, hc)]
        scene_setup.render_side_by_side([noisy, laplacian, hc], labels, image, samples=args.samples)
        print(f"picture: {image} ({time.perf_counter() - start:.0f} s, Cycles CPU)")


if __name__ == "__main__":
    run_and_exit(main)
