"""The default on noisy coarse meshes: Blender's primitives and CAD-like parts with noise added.

Scans are fine meshes; a user also runs the add-on on what Blender makes: a Cone of 33 vertices, a UV
Sphere of 482, a Cylinder whose sides are single quads. There the shape itself can read as noise. Each
primitive of bench/primitives.py (as Blender builds it at its defaults; with faces) and each CAD-like
part gets isotropic noise of 0.1 / 0.3 / 0.5 median edge lengths, two seeds, and is smoothed by the
add-on's default (``core.smooth_mesh`` with nothing set, split vertices welded) with Keep Sharp Edges off
and on. Measured: the RMS distance of the vertices to the clean primitive's surface over the input's
(below 1: nearer the shape than the noisy input; above 1: farther; a vertex sliding along the surface
costs nothing), the RMS radius over the clean part's, the correlation between neighbours of what the
run took away along the normals (core.mesh.collapse.residual_correlation: above 0, shape went with the noise),
and the parts the Automatic Amount left as they were because the run would have changed their shape
(core.mesh.collapse).

    python bench/run.py primitives               # ~20 s
    python bench/run.py primitives --no-guard    # core.mesh.collapse off: what the runs do to the parts it holds
"""

import numpy as np

import core
from bench import bench_quality_inputs as inputs
from bench import primitives
from bench.common import Parameter

RATIOS = (0.1, 0.3, 0.5)
SEEDS = (0, 3)


def rms(surface, points):
    return float(np.sqrt(np.mean(surface.distance(points) ** 2)))


def radius(points):
    return float(np.sqrt(np.mean(np.sum((points - points.mean(axis=0)) ** 2, axis=1))))


def smoothed_part(part, surface, noisy, sharp, hold_parts):
    """(surface error over the input's, RMS radius over the clean part's, parts held, residual correlation)."""
    result, report = core.smooth_mesh(
        noisy,
        part.edges,
        faces=part.faces,
        weld=True,
        keep_sharp_edges=sharp,
        hold_parts=hold_parts,
        return_report=True,
    )
    error = rms(surface, result) / rms(surface, noisy)
    operator = core.umbrella_operator(part.edges, len(noisy))
    one_part = np.zeros(len(noisy), dtype=np.int64)  # each shape is one part
    correlation = core.mesh.collapse.residual_correlation(noisy, result, part.triangles(), operator, one_part, 1)[0]
    return error, radius(result) / radius(part.positions), report.held_parts, correlation


def write_table(out, rows, pick, title):
    out(f"\n{title}\n")
    table = out.table("shape", "vertices", *[f"{m} {r}" for r in RATIOS for m in ("HC", "sharp")], align="lr" + "r" * 6)
    for name, count, cells in rows:
        text = [" / ".join(pick(run) + (f" ({run[2]})" if run[2] else "") for run in runs) for runs in cells]
        table.row(name, count, *text)


PARAMETERS = (
    Parameter("no_guard", False, "core.mesh.collapse off: parts never held (hold_parts=False)"),
    Parameter("shapes", "", "only these primitives and parts (default all)"),
)
QUICK = {"shapes": "cube,cone_trifan"}


def run(args, out):
    rows, worse, shrunk = [], {False: [], True: []}, {False: [], True: []}
    wanted = set(inputs.parse_list(args.shapes))
    for name, make in {**primitives.PRIMITIVES, **primitives.CAD}.items():
        if wanted and name not in wanted:
            continue
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
                    runs.append(smoothed_part(part, surface, noisy, sharp, not args.no_guard))
                    label = f"{name} {ratio} s{seed}"
                    if runs[-1][0] > 1.0:
                        worse[sharp].append(f"{label} {runs[-1][0]:.2f}")
                    if runs[-1][1] < 0.9:
                        shrunk[sharp].append(f"{label} {runs[-1][1]:.2f}")
                cells.append(runs)
        rows.append((name, len(part.positions), cells))
    out("# The default on noisy primitives\n")
    guard = "off (hold_parts=False)" if args.no_guard else "on"
    out(f"core.mesh.collapse {guard}. Isotropic noise in median edge lengths, seeds {SEEDS[0]} / {SEEDS[1]};")
    out("in brackets the parts left as they were (core.mesh.collapse).")
    write_table(out, rows, lambda r: f"{r[0]:.2f}", "RMS distance to the clean surface over the input's:")
    write_table(out, rows, lambda r: f"{r[1]:.2f}", "RMS radius (about the centroid) over the clean part's:")
    write_table(
        out, rows, lambda r: f"{r[3]:+.2f}", "Neighbour correlation of what the run took away along the normals:"
    )
    for sharp in (False, True):
        label = "Keep Sharp Edges" if sharp else "HC default"
        runs = len(SEEDS) * len(RATIOS) * len(rows)
        out(
            f"\n{label}: farther from the surface than the input in {len(worse[sharp])} runs of {runs}: "
            + ", ".join(worse[sharp])
        )
        out(f"{label}: radius under 0.9 of the clean part's in {len(shrunk[sharp])} runs: " + ", ".join(shrunk[sharp]))
    return out.rows
