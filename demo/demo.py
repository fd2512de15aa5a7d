"""The main job: a headless demo of HC Smooth on a built-in default (run with a Python that has bpy).

    python demo/demo.py [--output-dir demo_output] [--iterations 30] [--noise 0.004] [--samples 8]
                        [--scale 100] [--no-render]

Builds the extension zip with Blender's own tool and installs it into a throw-away Blender user
folder, exactly as a user would. Then it takes Blender's Suzanne with its four holes capped (a closed
surface: the operator and this table both measure its volume), subdivided (Catmull-Clark, level 3),
adds Gaussian noise along the normals (σ = --noise × bounding-box diagonal, fixed seed), and smooths
copies with the installed operator:

- Laplacian, --iterations steps (30: until the noise is gone from sight);
- Laplacian at the step count that leaves it closest to the clean surface (its best case);
- HC at the same --iterations, α and β at the operator's defaults, a fixed amount;
- HC with all of the operator's defaults (with the Automatic Amount: iterations chosen from the noise).

It prints the operator's reports and a table of volume change and distance to the clean surface,
saves the scene as a .blend and renders clean / noisy / Laplacian / HC (defaults) side by side with
Cycles on the CPU, coloured by signed distance to the clean surface on one scale with a legend, the
clean shape's outline drawn over both results.
"""

import argparse
import dataclasses
import pathlib
import re
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "scripts"), str(ROOT / "demo")]

# isort: off
from extension_session import install_extension, run_and_exit  # noqa: E402  (before bpy: user folder)

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import console_capture as console  # noqa: E402  (the add-on's own, plain Python)
import core  # noqa: E402  (the same code the extension carries; used here for metrics and the best count)
import scene_setup  # noqa: E402
# isort: on

SEED = 7
COLOUR_LIMIT = 1.0  # the colour scale spans ±1 % of the diagonal: about 2.5 σ of the default noise


def operator_defaults():
    return {
        prop.identifier: getattr(prop, "default", None) for prop in bpy.ops.object.hc_smooth.get_rna_type().properties
    }


def smooth_copy(source, name, location, **operator_args):
    """A copy of ``source`` smoothed by bpy.ops.object.hc_smooth; returns (object, seconds, report lines)."""
    obj = scene_setup.copy_object(source, name, location)
    scene_setup.select_only(obj)
    with console.captured() as printed:
        start = time.perf_counter()
        result = bpy.ops.object.hc_smooth(**operator_args)
        seconds = time.perf_counter() - start
    if result != {"FINISHED"}:
        raise SystemExit(f"object.hc_smooth({operator_args}) returned {result}:\n" + "\n".join(printed))
    return obj, seconds, [re.sub(r"^(Info|Warning): ", "", line) for line in printed]


def iterations_of(report):
    """How many iterations the operator says it ran."""
    return int(re.search(r"(\d+) iterations?\b", report).group(1))


def least_error_count(noisy, mesh_edges, surface, most):
    """The Laplacian step count (1..most) whose result is closest to the clean surface (RMS)."""
    best, best_error, worse = 1, np.inf, 0
    current = noisy
    for count in range(1, most + 1):
        current = core.laplacian_smooth(current, mesh_edges, iterations=1)
        error = float(np.sqrt(np.mean(surface.signed_distance(current) ** 2)))
        if error < best_error:
            best, best_error, worse = count, error, 0
        else:
            worse += 1
            if worse == 3:  # past the minimum: smoothing further only shrinks
                break
    return best


def distances(signed, diagonal):
    """RMS, mean (signed: negative = inside) and max distance to the clean surface, in % of the diagonal."""
    scale = 100 / diagonal
    return (
        scale * float(np.sqrt(np.mean(signed**2))),
        scale * float(signed.mean()),
        scale * float(np.abs(signed).max()),
    )


def signed(value, digits):
    """``value`` with its sign, a value that rounds to zero as +0 (never "-0.00")."""
    text = f"{value:+.{digits}f}"
    return "+" + text[1:] if float(text) == 0 else text


def print_table(rows):
    header = ("", "iterations", "volume change", "vs clean", "RMS distance", "mean distance", "max distance", "time")
    lines = [header]
    for row in rows:
        rms, mean, worst = row["distances"]
        lines.append(
            (
                row["name"],
                str(row["iterations"]),
                "" if row["change"] is None else f"{signed(100 * row['change'], 2)} %",
                f"{signed(100 * row['vs_clean'], 2)} %",
                f"{rms:.3f} %",
                f"{signed(mean, 3)} %",
                f"{worst:.3f} %",
                "" if row["seconds"] is None else f"{row['seconds']:.2f} s",
            )
        )
    widths = [max(len(line[i]) for line in lines) for i in range(len(header))]
    for index, line in enumerate(lines):
        print(
            "  ".join(
                cell.ljust(width) if i == 0 else cell.rjust(width)
                for i, (cell, width) in enumerate(zip(line, widths, strict=True))
            ).rstrip()
        )
        if index == 0:
            print("  ".join("-" * width for width in widths))
    print(
        "volume change: against the noisy input, as the operator reports it; vs clean: against the clean shape.\n"
        "distance: from each vertex to the clean surface (what the picture colours), in % of the bounding-box\n"
        "diagonal; the mean is signed: negative = inside the clean surface (shrinkage)."
    )


def arguments():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output-dir", default=str(ROOT / "demo_output"))
    parser.add_argument(
        "--iterations", type=int, default=30, help="Laplacian and fixed-amount HC iterations (default 30)"
    )
    parser.add_argument("--noise", type=float, default=0.004, help="σ as a fraction of the bbox diagonal (0.004)")
    parser.add_argument("--samples", type=int, default=8, help="Cycles samples per pixel, denoised (8)")
    parser.add_argument("--scale", type=int, default=100, help="picture size in %% of 1300 x 471 (100)")
    parser.add_argument("--no-render", action="store_true", help="skip the picture (the table only)")
    return parser.parse_args()


@dataclasses.dataclass
class Scene:
    """The clean Suzanne, its noisy copy and what the measures need of them."""

    noisy: object  # the noisy object (every run smooths a copy of it)
    clean_obj: object
    clean: np.ndarray  # (n, 3) float64 clean positions
    noisy_points: np.ndarray
    faces: tuple  # Blender's face layout (offsets, corner_verts)
    mesh_edges: np.ndarray
    diagonal: float
    surface: object  # scene_setup.CleanSurface


def make_scene(noise):
    bpy.ops.wm.read_homefile(use_empty=True)
    noisy = scene_setup.closed_suzanne(level=3)
    clean = scene_setup.positions(noisy.data).astype(np.float64)
    clean_obj = scene_setup.object_from_mesh(noisy.data.copy(), "Clean", (0, 0, 0))
    faces = scene_setup.faces(noisy.data)
    diagonal = float(np.linalg.norm(clean.max(axis=0) - clean.min(axis=0)))
    scene_setup.add_normal_noise(noisy, noise * diagonal, np.random.default_rng(SEED))
    noisy.name = noisy.data.name = "Noisy"
    noisy.location = (scene_setup.SPACING, 0, 0)
    surface = scene_setup.CleanSurface(clean, faces)
    print(
        f"Suzanne, holes capped (closed), subdivided: {len(clean)} vertices, {len(faces[0]) - 1} faces; noise "
        f"σ = {noise:.2%} of the diagonal along the normals (seed {SEED})\n"
    )
    points = scene_setup.positions(noisy.data)
    edges = scene_setup.edges(noisy.data)
    return Scene(noisy, clean_obj, clean, points, faces, edges, diagonal, surface)


def smooth_all(scene, iterations, defaults):
    """Each run's smoothed copy: [(name, object, iterations, seconds)], the noisy input first; ``defaults``:
    the operator's (operator_defaults)."""
    x = scene_setup.SPACING
    fixed = dict(iterations=iterations, mode="SIMULTANEOUS")
    hc_fixed = dict(method="HC", alpha=defaults["alpha"], beta=defaults["beta"], **fixed)
    if "auto_amount" in defaults:
        hc_fixed["auto_amount"] = False
    best = least_error_count(scene.noisy_points, scene.mesh_edges, scene.surface, max(iterations, 1))
    runs = [
        ("Laplacian", dict(method="LAPLACIAN", **fixed), (2 * x, 0, 0)),
        ("Laplacian, least error", dict(method="LAPLACIAN", iterations=best, mode="SIMULTANEOUS"), (5 * x, 0, 0)),
        (f"HC, α {defaults['alpha']:g}, β {defaults['beta']:g}", hc_fixed, (6 * x, 0, 0)),
        ("HC, operator defaults", dict(method="HC"), (3 * x, 0, 0)),
    ]
    rows = [("Noisy", scene.noisy, 0, None)]
    print("the operator reports:")
    for name, operator_args, location in runs:
        obj, seconds, said = smooth_copy(scene.noisy, name, location, **operator_args)
        for line in said:
            print(f"  {line}")
        rows.append((name, obj, iterations_of(said[0]), seconds))
    print()
    return rows


def measure_all(scene, rows):
    """The table's rows: each run's volume change and distances to the clean surface (also painted on the
    objects as the attribute the picture colours)."""
    triangles = core.fan_triangles(scene.faces)
    clean_volume = core.enclosed_volume(scene.clean, triangles)
    table = []
    for name, obj, iterations, seconds in rows:
        points = scene_setup.positions(obj.data)
        signed = scene.surface.signed_distance(points)
        scene_setup.set_point_attribute(obj, scene_setup.ERROR_ATTRIBUTE, 100 * signed / scene.diagonal)
        # The operator's own measure on the same arrays: its input (the noisy mesh) against its result.
        change = (
            core.measure_change(scene.noisy_points, points, faces=scene.faces).volume_change if iterations else None
        )
        table.append(
            {
                "name": name,
                "object": obj,
                "iterations": iterations,
                "seconds": seconds,
                "change": change,
                "vs_clean": core.enclosed_volume(points.astype(np.float64), triangles) / clean_volume - 1,
                "distances": distances(signed, scene.diagonal),
            }
        )
    scene_setup.set_point_attribute(scene.clean_obj, scene_setup.ERROR_ATTRIBUTE, np.zeros(len(scene.clean)))
    return table


def render(args, scene, table, image):
    """The picture: clean, noisy, Laplacian and HC's default side by side, coloured by the distance."""
    image.unlink(missing_ok=True)  # a picture left by an earlier run must not pass for this one's
    start = time.perf_counter()
    row = {r["name"]: r for r in table}

    def label(title, name):
        volume = f"{100 * row[name]['vs_clean']:+.1f}".replace("-", "\u2212")
        return f"{title}\nvolume {volume} %\nRMS distance {row[name]['distances'][0]:.2f} %"

    shown = [row["Laplacian"]["object"], row["HC, operator defaults"]["object"]]
    for obj in [r["object"] for r in table] + [scene.clean_obj]:
        obj.hide_render = obj not in shown + [scene.clean_obj, scene.noisy]
    hc_iterations = row["HC, operator defaults"]["iterations"]
    panels = [
        (scene.clean_obj, "Clean\nthe reference\n "),
        (scene.noisy, label(f"Noisy, σ = {100 * args.noise:.2g} %", "Noisy")),
        (shown[0], label(f"Laplacian, {row['Laplacian']['iterations']} iterations", "Laplacian")),
        (shown[1], label(f"HC, defaults: {hc_iterations} iterations", "HC, operator defaults")),
    ]
    outline = scene_setup.outline_segments(scene.surface, scene.clean, scene.faces)
    error = None
    with console.captured() as printed:
        try:
            scene_setup.render_error_figure(
                panels,
                outline,
                shown,
                image,
                limit=COLOUR_LIMIT,
                samples=args.samples,
                percentage=args.scale,
                legend_title="signed distance to the clean surface, % of the bounding-box diagonal; "
                "yellow line: outline of the clean shape",
            )
        except Exception as raised:  # noqa: BLE001 - shown below with what Blender printed
            error = raised
    if error is not None or not image.exists():
        print("\n".join(printed[-20:]), file=sys.stderr)
        raise error or SystemExit(f"the render did not write {image}")
    print(f"picture: {image} ({time.perf_counter() - start:.0f} s, Cycles CPU, {args.samples} samples)")


def main():
    args = arguments()
    output = pathlib.Path(args.output_dir).resolve()
    output.mkdir(parents=True, exist_ok=True)
    with console.captured():
        zip_path = install_extension(output / "build")
    print(
        f"HC Smooth {pathlib.Path(zip_path).stem.rpartition('-')[2]} installed into a throw-away Blender "
        f"{bpy.app.version_string} user folder"
    )
    defaults = operator_defaults()
    scene = make_scene(args.noise)
    table = measure_all(scene, smooth_all(scene, args.iterations, defaults))
    print_table(table)
    blend_path = output / "hc_smooth_demo.blend"
    with console.captured():
        bpy.ops.wm.save_as_mainfile(filepath=str(blend_path), check_existing=False)
    print(f"\nscene: {blend_path}")
    if not args.no_render:
        render(args, scene, table, output / "comparison.png")


if __name__ == "__main__":
    run_and_exit(main)
