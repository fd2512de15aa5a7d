"""The default on noisy coarse meshes: Blender's primitives and CAD-like parts with noise added.

Scans are fine meshes; a user also runs the add-on on what Blender makes: a Cone of 33 vertices, a UV
Sphere of 482, a Cylinder whose sides are single quads. There the shape itself can read as noise. Each
primitive of tests/core/primitives.py (as Blender builds it at its defaults; with faces) and each CAD-like
part gets isotropic noise of 0.1 / 0.3 / 0.5 median edge lengths, two seeds, and is smoothed by the
add-on's default (``core.smooth_mesh`` with nothing set, split vertices welded) with Keep Sharp Edges off
and on. Measured: the RMS distance of the vertices to the clean primitive's surface over the input's
(below 1: nearer the shape than the noisy input; above 1: farther; a vertex sliding along the surface
costs nothing), the RMS radius over the clean part's, the correlation between neighbours of what the
run took away along the normals (core.mesh.collapse.residual_correlation: above 0, shape went with the noise),
and the parts the Automatic Amount left as they were because the run would have changed their shape
(core.mesh.collapse).

    python bench/bench_primitives.py               # ~20 s
    python bench/bench_primitives.py --no-guard    # core.mesh.collapse off: what the runs do to the parts it holds

The report goes to stdout and bench/results/.
"""

import argparse
import pathlib
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "bench"), str(ROOT / "tests" / "core")]
import bench_quality_inputs as inputs  # noqa: E402
import primitives  # noqa: E402
from report import Report  # noqa: E402

import core  # noqa: E402

RATIOS = (0.1, 0.3, 0.5)
SEEDS = (0, 3)


def rms(surface, points):
    return float(np.sqrt(np.mean(surface.distance(points) ** 2)))


def radius(points):
    return float(np.sqrt(np.mean(np.sum((points - points.mean(axis=0)) ** 2, axis=1))))


def run(part, surface, noisy, sharp):
    """(surface error over the input's, RMS radius over the clean part's, parts held, residual correlation)."""
    result, report = core.smooth_mesh(
        noisy, part.edges, faces=part.faces, weld=True, keep_sharp_edges=sharp, return_report=True
    )
    error = rms(surface, result) / rms(surface, noisy)
    operator = core.umbrella_operator(part.edges, len(noisy))
    one_part = np.zeros(len(noisy), dtype=np.int64)  # each shape is one part
    correlation = core.mesh.collapse.residual_correlation(noisy, result, part.triangles(), operator, one_part, 1)[0]
    return error, radius(result) / radius(part.positions), report.held_parts, correlation


def table(out, rows, pick, title):
    out(f"\n{title}\n")
    out("| shape | vertices | " + " | ".join(f"HC {r} | sharp {r}" for r in RATIOS) + " |")
    out("|---|---:|" + "---:|" * (2 * len(RATIOS)))
    for name, count, cells in rows:
        text = [" / ".join(pick(run) + (f" ({run[2]})" if run[2] else "") for run in runs) for runs in cells]
        out(f"| {name} | {count} | " + " | ".join(text) + " |")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--no-guard", action="store_true", help="core.mesh.collapse off (parts never held)")
    args = parser.parse_args()
    if args.no_guard:
        core.mesh.collapse.KEEP, core.mesh.collapse.SMOOTH_RESIDUAL, core.mesh.collapse.MOVED_IN_NOISE = (
            0.0,
            np.inf,
            np.inf,
        )
    rows, worse, shrunk = [], {False: [], True: []}, {False: [], True: []}
    for name, make in {**primitives.PRIMITIVES, **primitives.CAD}.items():
        part = make()
        if not part.faces:
            continue
        surface = inputs.Surface(part.positions, part.triangles())
        cells = []
        for ratio in RATIOS:
            for sharp in (False, True):
                runs = []
                for seed in SEEDS:
                    noisy = primitives.with_noise(part, ratio, "isotropic", seed=seed)[0].positions
                    runs.append(run(part, surface, noisy, sharp))
                    label = f"{name} {ratio} s{seed}"
                    if runs[-1][0] > 1.0:
                        worse[sharp].append(f"{label} {runs[-1][0]:.2f}")
                    if runs[-1][1] < 0.9:
                        shrunk[sharp].append(f"{label} {runs[-1][1]:.2f}")
                cells.append(runs)
        rows.append((name, len(part.positions), cells))
    with Report("bench_primitives") as out:
        out("# The default on noisy primitives (bench_primitives.py)\n")
        out(f"Command: `python bench/bench_primitives.py {' '.join(sys.argv[1:])}`, {time.strftime('%Y-%m-%d')}; ")
        guard = "off" if args.no_guard else "on"
        out(f"core.mesh.collapse {guard}. Isotropic noise in median edge lengths, seeds {SEEDS[0]} / {SEEDS[1]};")
        out("in brackets the parts left as they were (core.mesh.collapse).")
        table(out, rows, lambda r: f"{r[0]:.2f}", "RMS distance to the clean surface over the input's:")
        table(out, rows, lambda r: f"{r[1]:.2f}", "RMS radius (about the centroid) over the clean part's:")
        table(out, rows, lambda r: f"{r[3]:+.2f}", "Neighbour correlation of what the run took away along the normals:")
        for sharp in (False, True):
            label = "Keep Sharp Edges" if sharp else "HC default"
            runs = len(SEEDS) * len(RATIOS) * len(rows)
            out(
                f"\n{label}: farther from the surface than the input in {len(worse[sharp])} runs of {runs}: "
                + ", ".join(worse[sharp])
            )
            out(
                f"{label}: radius under 0.9 of the clean part's in {len(shrunk[sharp])} runs: "
                + ", ".join(shrunk[sharp])
            )


if __name__ == "__main__":
    main()
