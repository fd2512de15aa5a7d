"""Open borders and split vertices on real open scans: how far the border moves against the interior.

The scans: the range map ``rangemaps/face000.ply`` and the textured bunny ``bunny10k_textured.obj``
(holes at the bottom; UV seams split its vertices) of the pymeshlab wheel, and pymeshfix's
``StanfordBunny.ply`` (the raw scan, holes and all). Each is read as a file importer reads it (split
vertices stay split), given Gaussian noise along the normals of its welded surface (0, 0.1 and 0.25 %
of the bounding-box diagonal; coincident vertices get the same noise, as in a file), and smoothed by
``core.smooth_mesh`` with the Automatic Amount (its defaults) under four rules:

* free: ``weld=False, border="free"`` (the core's defaults: the paper's algorithm on the file's vertices)
* weld: ``weld=True, border="free"``
* curve: ``weld=True, border="curve"`` (borders smoothed as curves)
* fixed: ``weld=True, border="fixed"`` (Pin Boundary)

Per run, over the welded vertices (each counted once; border = on an edge of one welded face): the RMS
move of border and interior vertices in % of the diagonal and their ratio; the border's mean move
into the surface, across its curve (in the tangent plane: positive pulls the outline in, while
smoothing a jagged outline moves its vertices both ways and averages out); the largest shift of a side
of the bounding box and the change of its diagonal (% of the diagonal); the largest gap between copies
of one vertex (% of the diagonal); the RMS distance to the clean scan, border and interior (per vertex,
% of the diagonal; at noise 0 it is the move itself).

    .envs/bench/bin/python bench/bench_borders.py                      # 3 scans x 3 noises x 4 rules, ~1 min
    .envs/bench/bin/python bench/bench_borders.py --scans face --noises 0 --rules free,curve
    .envs/bench/bin/python bench/bench_borders.py --timing 1M   # the cost of welding and borders instead

``--primitives``: Blender's Plane, Grid and open Cylinder (bench/primitives.py, as Blender builds
them) and a 20 x 20 Grid with a hole (its middle 2 x 2 quads taken out: 8 vertices around it), noise of
0.1 and 0.3 median edge lengths along the normals and on every axis, 5 seeds: each border loop's length
and enclosed area (the magnitude of its vector area) over the clean loop's, for the noisy input, the
default (Keep in Place) and the sliding default (``keep_in_place=False``); mean and range over the seeds.

    .envs/bench/bin/python bench/bench_borders.py --primitives          # a few seconds

``--timing N``: on a noisy torus of N vertices, its triangle soup (about N vertices, one sixth of them
welded) and the torus cut open (two border loops), the time of core.mesh.welding.weld alone and of
core.smooth_mesh (alpha 0.1, beta 0.6, 10 iterations) under each rule, best of ``--repeats``.
"""

import importlib.util
import pathlib
import time

import numpy as np

import core
from bench import bench_quality_inputs as inputs
from bench import meshes
from bench.common import Parameter, counts, repeats

RULES = {
    "free": dict(weld=False, border="free"),
    "weld": dict(weld=True, border="free"),
    "curve": dict(weld=True, border="curve"),
    "fixed": dict(weld=True, border="fixed"),
}


def scan_files():
    """name -> path of the open scans (pymeshfix's bunny only where pymeshfix is installed)."""
    samples = inputs.pymeshlab_samples()
    files = {"face": samples / "rangemaps" / "face000.ply", "bunny10k": samples / "bunny10k_textured.obj"}
    meshfix = importlib.util.find_spec("pymeshfix")  # located, not imported (its examples need pyvista)
    if meshfix is not None:
        files["stanford_bunny"] = pathlib.Path(meshfix.origin).parent / "examples" / "StanfordBunny.ply"
    return files


def load_as_imported(path):
    """(vertices, faces) as the file holds them: no vertex merged, unused vertices dropped."""
    import trimesh

    mesh = trimesh.load(str(path), process=False, force="mesh")
    vertices, faces = np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64)
    used = np.unique(faces)
    number = np.full(len(vertices), -1)
    number[used] = np.arange(used.size)
    return vertices[used].copy(), number[faces]


class Scan:
    def __init__(self, name, path):
        self.name = name
        self.vertices, self.faces = load_as_imported(path)
        self.edges = edges_of(self.faces)
        operator = core.umbrella_operator(self.edges, len(self.vertices))
        weld = core.mesh.welding.weld(self.vertices, operator)
        n = len(self.vertices)
        self.label = weld.label if weld is not None else np.arange(n)
        self.first = weld.first if weld is not None else np.arange(n)
        welded_faces = weld.triangles(self.faces) if weld is not None else self.faces
        clean = self.vertices[self.first]
        self.normals = inputs.vertex_normals(clean, welded_faces)
        self.diagonal = inputs.diagonal(clean)
        border_edges = core.mesh.borders.border_edges(welded_faces, len(self.first))
        border = np.zeros(len(self.first), dtype=bool)
        border[border_edges.ravel()] = True
        self.border = border
        self.clean = clean
        self.curve, self.inward = inward_directions(clean, welded_faces, border_edges, self.normals)

    def noisy(self, sigma, seed=0):
        """Noise along the normals on the welded vertices, the same on every copy."""
        welded = inputs.add_noise(self.clean, self.normals, sigma * self.diagonal, "normal", seed)
        return welded[self.label]


def inward_directions(points, faces, border_edges, normals):
    """(vertices, unit directions): for each border vertex with two border neighbours, the direction in
    its surface's tangent plane, across its border curve, towards the surface (from its neighbours'
    mean, without the parts along the normal and along the curve)."""
    n = len(points)
    operator = core.umbrella_operator(edges_of(faces), n)
    mean = np.stack(
        [np.bincount(operator.rows(), weights=points[operator.indices, k], minlength=n) for k in range(3)], 1
    )
    towards = mean / np.maximum(operator.degree, 1)[:, None] - points
    count = np.bincount(border_edges.ravel(), minlength=n)
    curve = np.flatnonzero(count == 2)
    ends = np.zeros((n, 2), dtype=np.int64)
    slot = np.zeros(n, dtype=np.int64)
    for a, b in border_edges:  # a few thousand border edges
        ends[a, slot[a] % 2], ends[b, slot[b] % 2] = b, a
        slot[a] += 1
        slot[b] += 1
    tangent = points[ends[curve, 1]] - points[ends[curve, 0]]
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    direction = towards[curve]
    for axis in (normals[curve], tangent):
        direction -= np.einsum("ij,ij->i", direction, axis)[:, None] * axis
    length = np.linalg.norm(direction, axis=1)
    good = length > 0
    return curve[good], direction[good] / length[good, None]


def edges_of(faces):
    pairs = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    return np.unique(pairs, axis=0)


def rms(values):
    return float(np.sqrt(np.mean(values**2))) if values.size else 0.0


def measure(scan, noisy, result):
    """The figures of one run, in % of the diagonal."""
    start, end = noisy[scan.first], result[scan.first]
    move = np.linalg.norm(end - start, axis=1)
    error = np.linalg.norm(end - scan.clean, axis=1)
    border, interior = scan.border, ~scan.border
    low, high = start.min(axis=0), start.max(axis=0)
    shift = max(np.abs(end.min(axis=0) - low).max(), np.abs(end.max(axis=0) - high).max())
    diagonal_change = inputs.diagonal(end) / inputs.diagonal(start) - 1.0
    gap = np.linalg.norm(result - result[scan.first[scan.label]], axis=1).max()
    pull = np.einsum("ij,ij->i", (end - start)[scan.curve], scan.inward).mean()
    percent = 100.0 / scan.diagonal
    return dict(
        border=rms(move[border]) * percent,
        interior=rms(move[interior]) * percent,
        shift=shift * percent,
        diagonal=100.0 * diagonal_change,
        pull=pull * percent,
        gap=gap * percent,
        error_border=rms(error[border]) * percent,
        error_interior=rms(error[interior]) * percent,
    )


# --- outlines of open primitives ----------------------------------------------------------------------

PRIMITIVE_RATIOS = (0.1, 0.3)  # noise, median edge lengths
PRIMITIVE_SEEDS = (0, 1, 2, 3, 4)


def grid_with_hole(subdivisions=20, size=2.0, hole=2):
    """Blender's Grid of ``subdivisions`` quads a side with its middle ``hole`` x ``hole`` quads taken out
    (4 * hole boundary vertices around the hole; the vertices inside it dropped)."""
    from bench import primitives

    part = primitives.grid(subdivisions, size)
    side, low = subdivisions + 1, (subdivisions - hole) // 2
    kept = [
        face
        for index, face in enumerate(part.faces)  # row j = index // subdivisions, column i = index % subdivisions
        if not (low <= index % subdivisions < low + hole and low <= index // subdivisions < low + hole)
    ]
    used = np.unique(np.concatenate(kept))
    number = np.full(side * side, -1)
    number[used] = np.arange(used.size)
    return primitives.mesh(part.positions[used], [[int(number[v]) for v in face] for face in kept])


def open_primitives():
    from bench import primitives

    return {
        "plane": primitives.plane(),
        "grid": primitives.grid(),
        "cylinder_open": primitives.cylinder(fill="NOTHING"),
        "grid_with_hole": grid_with_hole(),
    }


def border_loops(faces):
    """The open borders (edges of one polygon) as closed loops of vertex indices, in order, longest first."""
    count = {}
    for face in faces:
        for a, b in zip(face, list(face[1:]) + [face[0]]):
            key = (min(a, b), max(a, b))
            count[key] = count.get(key, 0) + 1
    neighbours = {}
    for (a, b), n in count.items():
        if n == 1:
            neighbours.setdefault(a, []).append(b)
            neighbours.setdefault(b, []).append(a)
    loops, seen = [], set()
    for start in sorted(neighbours):
        if start in seen:
            continue
        loop, previous, current = [start], None, start
        seen.add(start)
        while True:
            following = [v for v in neighbours[current] if v != previous and (v not in seen or v == start)]
            if not following or following[0] == start:
                break
            previous, current = current, following[0]
            loop.append(current)
            seen.add(current)
        loops.append(np.array(loop))
    return sorted(loops, key=len, reverse=True)


def loop_length(points):
    return float(np.linalg.norm(points - np.roll(points, -1, axis=0), axis=1).sum())


def loop_area(points):
    """The magnitude of the closed polygon's vector area (its area where it is flat)."""
    centre = points.mean(axis=0)
    return float(0.5 * np.linalg.norm(np.cross(points - centre, np.roll(points, -1, axis=0) - centre).sum(axis=0)))


def outline_rows():
    """[(shape, loop name, vertices on it, kind, ratio, {run: (length ratios, area ratios)})] over the seeds."""
    from bench import primitives

    rows = []
    for name, part in open_primitives().items():
        loops = border_loops(part.faces)
        names = ["outline"] if len(loops) == 1 else ([f"ring {k + 1}" for k in range(len(loops))])
        if name == "grid_with_hole":
            names = ["outline", "hole"]
        for kind in ("normal", "isotropic"):
            for ratio in PRIMITIVE_RATIOS:
                runs = {"input": [], "default": [], "sliding": []}
                for seed in PRIMITIVE_SEEDS:
                    noisy = primitives.with_noise(part, ratio, kind, seed=seed)[0].positions
                    results = {
                        "input": noisy,
                        "default": core.smooth_mesh(noisy, part.edges, faces=part.faces, weld=True),
                        "sliding": core.smooth_mesh(
                            noisy, part.edges, faces=part.faces, weld=True, keep_in_place=False
                        ),
                    }
                    for run, positions in results.items():
                        runs[run].append(
                            [
                                (
                                    loop_length(positions[loop]) / loop_length(part.positions[loop]),
                                    loop_area(positions[loop]) / loop_area(part.positions[loop]),
                                )
                                for loop in loops
                            ]
                        )
                for k, loop in enumerate(loops):
                    values = {run: np.array([seed_values[k] for seed_values in v]) for run, v in runs.items()}
                    rows.append((name, names[k], len(loop), kind, ratio, values))
    return rows


def outlines(out):
    out(
        "Open primitives: each border loop's length and enclosed area (magnitude of its vector area) over the "
        f"clean loop's, mean (min–max) over seeds {', '.join(map(str, PRIMITIVE_SEEDS))}; noise in median edge "
        "lengths. default: core.smooth_mesh(..., weld=True) (Keep in Place); sliding: keep_in_place=False.\n"
    )
    table = out.table(
        "shape",
        "loop",
        "vertices",
        "noise",
        "σ / edge",
        "length: input",
        "default",
        "sliding",
        "area: input",
        "default",
        "sliding",
        align="llrlrrrrrrr",
    )

    def text(values):
        return f"{values.mean():.3f} ({values.min():.3f}–{values.max():.3f})"

    for name, loop, count, kind, ratio, values in outline_rows():
        cells = [text(values[run][:, 0]) for run in ("input", "default", "sliding")]
        cells += [text(values[run][:, 1]) for run in ("input", "default", "sliding")]
        table.row(name, loop, count, kind, f"{ratio:g}", *cells)


def best_time(repeats, function, *args, **kwargs):
    """The least wall time of ``repeats`` calls of function(*args, **kwargs)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function(*args, **kwargs)
        times.append(time.perf_counter() - start)
    return min(times)


def timing(out, size, repeats):
    """The cost of welding and of the border rules at ``size`` vertices."""
    vertices, faces = meshes.torus(size)
    vertices = meshes.add_noise(vertices, 0.002)
    small_vertices, small_faces = meshes.torus(size // 6)
    soup, soup_faces = small_vertices[small_faces].reshape(-1, 3), np.arange(small_faces.size).reshape(-1, 3)
    centroid = vertices[faces].mean(axis=1)
    cut = faces[~((centroid[:, 0] > 0.0) & (np.abs(centroid[:, 1]) < 0.02))]  # a slice out of the ring
    cases = [
        ("torus (closed)", vertices, faces),
        ("triangle soup", soup, soup_faces),
        ("torus cut open", vertices, cut),
    ]
    out(f"Timing, best of {repeats}: core.smooth_mesh(alpha=0.1, beta=0.6, iterations=10), seconds\n")
    table = out.table("mesh", "vertices", "border vertices", "weld() alone", *RULES)
    for name, points, triangles in cases:
        edges = meshes.edges_from_faces(triangles)
        operator = core.umbrella_operator(edges, len(points))
        weld_seconds = best_time(repeats, core.mesh.welding.weld, points, operator)
        border = len(np.unique(core.mesh.borders.border_edges(triangles, len(points))))
        cells = [name, f"{len(points):,}", f"{border:,}", f"{weld_seconds:.2f}"]
        for rule in RULES.values():
            options = dict(faces=triangles, alpha=0.1, beta=0.6, iterations=10, **rule)
            cells.append(f"{best_time(repeats, core.smooth_mesh, points, edges, **options):.2f}")
        table.row(*cells)


PARAMETERS = (
    Parameter("scans", "", "comma-separated: face, bunny10k, stanford_bunny (default all)"),
    Parameter("noises", "0,0.001,0.0025", "noise along the normals, fractions of the diagonal"),
    Parameter("rules", ",".join(RULES)),
    Parameter("timing", "", "vertex count (e.g. 1M): time welding and the rules instead"),
    repeats(3),
    Parameter("primitives", False, "outline length and area of open primitives instead"),
)
QUICK = {"scans": "bunny10k", "noises": "0.001", "rules": "weld", "repeats": 1}


def report_name(args):
    return "bench_borders_primitives" if args.primitives else "bench_borders_timing" if args.timing else "bench_borders"


def run(args, out):
    if args.primitives:
        outlines(out)
        return out.rows
    if args.timing:
        timing(out, counts(args.timing)[0], args.repeats)
        return out.rows
    files = scan_files()
    names = inputs.parse_list(args.scans) if args.scans else list(files)
    out("Automatic Amount (core.smooth_mesh defaults) under each rule; figures in % of the bounding-box diagonal.\n")
    scans = {name: Scan(name, files[name]) for name in names}
    for name, scan in scans.items():
        out(
            f"{name}: {len(scan.vertices)} vertices as imported, {len(scan.first)} welded, "
            f"{int(scan.border.sum())} on a border\n"
        )
    table = out.table(
        "scan",
        "noise",
        "rule",
        "iterations",
        "border RMS move",
        "interior RMS move",
        "ratio",
        "border pulled in",
        "box side shift",
        "box diagonal",
        "seam gap",
        "error border",
        "error interior",
    )
    for name, scan in scans.items():
        for noise in inputs.parse_list(args.noises, float):
            noisy = scan.noisy(noise)
            for rule in inputs.parse_list(args.rules):
                start = time.perf_counter()
                result, report = core.smooth_mesh(
                    noisy, scan.edges, faces=scan.faces, return_report=True, **RULES[rule]
                )
                seconds = time.perf_counter() - start
                m = measure(scan, noisy, result)
                ratio = m["border"] / m["interior"] if m["interior"] > 0 else float("inf")
                cells = [
                    name,
                    f"{100 * noise:g}%",
                    rule,
                    f"{report.iterations} (β {report.beta:g}, {seconds:.1f} s)",
                    f"{m['border']:.4f}",
                    f"{m['interior']:.4f}",
                    f"{ratio:.2f}",
                    f"{m['pull']:+.4f}",
                    f"{m['shift']:.4f}",
                    f"{m['diagonal']:+.4f}",
                    f"{m['gap']:.2g}",
                    f"{m['error_border']:.4f}",
                    f"{m['error_interior']:.4f}",
                ]
                table.row(*cells)
    return out.rows
