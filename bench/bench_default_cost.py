"""What the default costs on a big scan: core.smooth_mesh with the Automatic Amount, as the core's
defaults and as the add-on runs it (``weld=True``), against the fixed 10-iteration HC
run (alpha 0.1, beta 0.6), on the same noisy mesh, in the same process; and the default with Keep in
Place off (``keep_in_place=False``), whose difference is what keeping every move across the surface costs.

Time: median wall time of ``--repeats`` runs each, alternating. Memory: the peak of what NumPy and SciPy
allocate during one more run of each (tracemalloc, which NumPy reports its buffers to, and which slows
the run: so not timed), above what was allocated before it. Gap: the longest wall time between the
start and a slice of ``core.MeshSmoother.steps``, or between two slices (what a cancel waits for), run
in chunks of iterations as the operator's modal run takes them (5M vertex-iterations a chunk). The
input is float32, as Blender hands it over.

Meshes: a noisy torus (``--mesh torus``, isotropic noise of ``--noise`` times the bounding-box
diagonal), or the pymeshlab wheel's bunny scan (closed, 28k vertices) subdivided at its edges'
midpoints ``--subdivisions`` times (3: 1.8M vertices; the surface is the scan's) with the same noise.

``--shuffled``: also the fixed run and the default on the same mesh numbered at random, as some scanners,
decimators and converters number theirs (the pipeline then runs renumbered for cache locality,
core.locality; the bunny's midpoints, numbered after its vertices, are scattered as they come).

``--error``: the RMS distance of every result to the clean surface in % of the diagonal (the torus's
own; the bunny's along the clean vertex normals), with the Automatic Amount as it runs and with its
work budget lifted (``work_budget=math.inf``), which is what the budget costs. ``--choice``: the
iterations GCV chooses on patches (big meshes) and on the whole mesh (``patch_from=math.inf``), both
without the work budget, and the time each choice takes.

    python bench/run.py default_cost                 # 5M vertices, 3 runs each
    python bench/run.py default_cost --vertices 1M --repeats 5 --shuffled
    python bench/run.py default_cost --vertices 5M --repeats 1 --error --choice
    python bench/run.py default_cost --mesh bunny --subdivisions 3 --repeats 1 --error --choice   # pymeshlab
"""

import math
import pathlib
import statistics
import time
import tracemalloc

import numpy as np

import core
from bench import meshes
from bench.common import Parameter, count, repeats
from core import locality
from core.mesh import amount as mesh_amount

CHUNK_WORK = 5_000_000  # vertex-iterations a slice, as operators/mesh_smooth.py's MODAL_WORK
FIXED = dict(alpha=0.1, beta=0.6, iterations=10)
ADDON = dict(weld=True)  # as operators/jobs.py runs it (border: the paper's rule)


def peak_of(function):
    """(peak bytes above the start, result) of one call, traced by tracemalloc."""
    tracemalloc.start()
    tracemalloc.reset_peak()
    base = tracemalloc.get_traced_memory()[0]
    result = function()
    peak = tracemalloc.get_traced_memory()[1] - base
    tracemalloc.stop()
    return peak, result


def smoothed(noisy, edges, faces, options, budget=None):
    """(seconds, positions, report, longest gap) of one core.MeshSmoother run, construction included (``budget``:
    the work budget, None: core's)."""
    start = last = time.perf_counter()
    run = core.MeshSmoother(noisy, edges, faces=faces, work_budget=budget, **options)
    gap = 0.0
    for _ in run.steps(max(1, CHUNK_WORK // len(noisy))):
        now = time.perf_counter()
        gap, last = max(gap, now - last), now
    return last - start, run.result, run.report, gap


def chosen(noisy, edges, patch_from):
    """(iterations, sigma, seconds) GCV chooses without the work budget, on patches from ``patch_from``
    movable vertices up."""
    operator = core.umbrella_operator(edges, len(noisy))
    start = time.perf_counter()
    amount = core.choose_amount(noisy, operator=operator, work_budget=math.inf, patch_from=patch_from)
    return amount.iterations, amount.sigma, time.perf_counter() - start


def torus_distance(points, ratio=2.5, minor_radius=0.4):
    """Unsigned distance of (n, 3) points to the torus meshes.torus samples."""
    points = np.asarray(points, np.float64)
    ring = np.hypot(points[:, 0], points[:, 1]) - ratio * minor_radius
    return np.abs(np.hypot(ring, points[:, 2]) - minor_radius)


def subdivided(vertices, faces, times):
    """Every triangle split into four at its edges' midpoints, ``times`` times (the surface stays)."""
    for _ in range(times):
        n = vertices.shape[0]
        corners = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
        keys = np.minimum(corners[:, 0], corners[:, 1]) * n + np.maximum(corners[:, 0], corners[:, 1])
        unique, inverse = np.unique(keys, return_inverse=True)
        vertices = np.concatenate([vertices, (vertices[unique // n] + vertices[unique % n]) / 2.0])
        ab, bc, ca = (n + inverse.reshape(-1, 3)).T
        a, b, c = faces.T
        faces = np.concatenate([np.stack(f, -1) for f in ([a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca])])
    return vertices, faces


def bunny(times):
    """The pymeshlab wheel's bunny.obj (closed scan; coincident vertices merged), subdivided."""
    import pymeshlab  # only for the path of its sample meshes

    path = pathlib.Path(pymeshlab.__file__).resolve().parent / "tests" / "sample_meshes" / "bunny.obj"
    lines = path.read_text().splitlines()
    vertices = np.array([line.split()[1:4] for line in lines if line.startswith("v ")], np.float64)
    faces = np.array(
        [[int(corner.split("/")[0]) - 1 for corner in line.split()[1:4]] for line in lines if line.startswith("f ")]
    )
    vertices, inverse = np.unique(vertices, axis=0, return_inverse=True)
    return subdivided(vertices, inverse.ravel()[faces], times)


def normals_of(vertices, faces):
    """Area-weighted unit vertex normals."""
    return core.geometry.vertex_normals(vertices, faces)


PARAMETERS = (
    Parameter("mesh", "torus", "the noisy mesh: torus or bunny"),
    Parameter("vertices", "5M", "torus size, e.g. 5M, 1M, 250k", count),
    Parameter("subdivisions", 3, "bunny: midpoint subdivisions (3: 1.8M)"),
    Parameter("noise", 0.001, "noise, a fraction of the diagonal"),
    repeats(3),
    Parameter("error", False, "also the error, with and without the budget"),
    Parameter("choice", False, "also GCV's choice on patches and on the whole mesh"),
    Parameter("shuffled", False, "also the fixed run and the default on the mesh numbered at random"),
)
QUICK = {"vertices": "20k", "repeats": 1, "error": True, "choice": True, "shuffled": True}
SHUFFLED = ", numbered at random"


def shuffled(noisy, edges, faces):
    """The mesh with its vertices numbered at random, and the order that puts a result back."""
    order = np.random.default_rng(0).permutation(len(noisy))
    number = np.empty_like(order)
    number[order] = np.arange(order.size)
    return (noisy[order], number[edges], number[faces]), number


def run(args, out):
    if args.mesh not in ("torus", "bunny"):
        raise SystemExit(f"--mesh {args.mesh}: torus or bunny")
    if args.mesh == "torus":
        clean, faces = meshes.torus(args.vertices)
        name = "noisy torus"
        distance = torus_distance
    else:
        clean, faces = bunny(args.subdivisions)
        name = f"bunny subdivided {args.subdivisions} times"
        normals = normals_of(clean, faces)

        def distance(points):
            return np.abs(np.einsum("ij,ij->i", np.asarray(points, np.float64) - clean, normals))

    diagonal = meshes.bbox_diagonal(clean)
    noisy = meshes.add_noise(clean, args.noise, seed=1).astype(np.float32)
    edges = meshes.edges_from_faces(faces)
    runs = {
        "fixed: alpha 0.1, beta 0.6, 10 iterations": dict(FIXED),
        "default: Automatic Amount": {},
        "add-on default: weld, border curve": dict(ADDON),
        "default, sliding: Keep in Place off": {"keep_in_place": False},
    }
    mesh, back = {label: (noisy, edges, faces) for label in runs}, {}
    if args.shuffled:
        scattered, number = shuffled(noisy, edges, faces)
        for label in ("fixed: alpha 0.1, beta 0.6, 10 iterations", "default: Automatic Amount"):
            runs[label + SHUFFLED], mesh[label + SHUFFLED], back[label + SHUFFLED] = runs[label], scattered, number
    figures = {label: [] for label in runs}
    for _ in range(args.repeats):
        for label, options in runs.items():  # alternating, so all see the same machine
            figures[label].append(smoothed(*mesh[label], options))
    peaks = {
        label: peak_of(lambda label=label, options=options: smoothed(*mesh[label], options))[0]
        for label, options in runs.items()
    }
    errors = {}
    if args.error:
        errors["noisy input"] = (None, noisy)
        for label, rows in figures.items():
            result = rows[-1][1]
            errors[label] = (rows[-1][2], result if label not in back else result[back[label]])
        _, result, report, _ = smoothed(noisy, edges, faces, ADDON, budget=math.inf)
        errors["add-on default, no work budget"] = (report, result)
    choices = {}
    if args.choice:
        choices["on patches"] = chosen(noisy, edges, mesh_amount.PATCH_FROM)
        choices["on the whole mesh"] = chosen(noisy, edges, math.inf)
    out(f"# The default's cost on {len(noisy):,} vertices ({name}, noise {args.noise:.2%} of the diagonal)")
    out()
    table = out.table(
        "run", "iterations", "median time", "peak memory", "time / fixed", "memory / fixed", "longest gap"
    )
    fixed_label = next(iter(runs))
    fixed_time = statistics.median(row[0] for row in figures[fixed_label])
    for label, rows in figures.items():
        seconds = statistics.median(row[0] for row in rows)
        report, gap = rows[-1][2], max(row[3] for row in rows)
        table.row(
            label,
            report.iterations,
            f"{seconds:.2f} s",
            f"{peaks[label] / 2**30:.2f} GiB",
            f"{seconds / fixed_time:.2f}x",
            f"{peaks[label] / peaks[fixed_label]:.2f}x",
            f"{gap:.2f} s",
        )
    kept = statistics.median(row[0] for row in figures["default: Automatic Amount"])
    sliding = statistics.median(row[0] for row in figures["default, sliding: Keep in Place off"])
    out()
    out(f"Keep in Place costs {kept - sliding:+.2f} s, {(kept - sliding) / kept:+.1%} of the default's run.")
    if args.shuffled:
        own = "scattered" if locality.is_scattered(core.umbrella_operator(edges, len(noisy))) else "not scattered"
        label = "default: Automatic Amount" + SHUFFLED
        random = statistics.median(row[0] for row in figures[label])
        out(
            f"Numbered at random, the default takes {random:.2f} s, {random / kept:.2f}x its time in the mesh's own "
            f"numbering ({own}: core.locality)."
        )
    if errors:
        out()
        out("RMS distance to the clean surface, % of the diagonal:")
        out()
        table = out.table("run", "iterations", "RMS distance")
        for label, (report, points) in errors.items():
            rms = math.sqrt(float(np.mean(distance(points) ** 2))) / diagonal
            table.row(label, "" if report is None else report.iterations, f"{rms:.4%}")
    if choices:
        out()
        out("Iterations GCV chooses without the work budget:")
        out()
        table = out.table("chosen", "iterations", "noise (sigma), % of the diagonal", "time")
        for label, (iterations, sigma, seconds) in choices.items():
            table.row(label, iterations, f"{sigma / diagonal:.4%}", f"{seconds:.2f} s")
    return out.rows
