"""Keep Sharp Edges (core.mesh.sharp_edges) on sharp-edged parts, against HC and feature-preserving peers.

Parts: the cube and the thin plate of bench_quality_inputs.py and the CAD-like parts of sharp_parts.py
(a bevelled box, a cylinder with a through hole, a fandisk-like block). ``tuning`` (cube, bevelled box,
holed cylinder) is what the default angle, the Automatic Amount's rule and the guidance's constants were
chosen on; no constant was chosen on ``heldout`` (plate, fandisk), though the plate's thin rim is why
the guidance has vertex rings. Noise σ = 0.1 / 0.25 / 0.5 / 1 % of the
bounding-box diagonal, along the clean vertex normals ("normal") or on every coordinate ("iso"), one
seed per cell (bench_quality.make_case's seeding).

Methods, same run, same input:

* ours: ``core.smooth_mesh(noisy, edges, faces=faces, weld=True, keep_sharp_edges=True)`` (the Automatic
  Amount, as the add-on would run it), and at the fixed default (``core.mesh.sharp_edges.DEFAULT_ITERATIONS``
  steps, no Automatic Amount);
* HC Smooth's default (``core.smooth_mesh`` with nothing set) and the best HC setting of
  bench_default_heldout.py's grid (α × β × iterations, read on all vertices);
* MeshLab's two-step smoothing (``apply_coord_two_steps_smoothing``, Sun et al. 2007) at its defaults
  (3 steps, 60°, 20 + 20 passes) and the best of steps {1, 2, 3, 5, 8} × angle {30, 45, 60};
* MeshLab's surface-preserving Laplacian (``apply_coord_laplacian_smoothing_surface_preserving``) at its
  defaults (1 iteration, 0.5°) and the best of iterations {1, 5, 20} × angle {2, 10, 30}°;
* MeshLib's ``meshDenoiseViaNormals`` (Mumford–Shah normal filtering) at its defaults and the best of
  β {0.003, 0.01, 0.03, 0.1};
* VTK's ``vtkWindowedSincPolyDataFilter`` (Taubin's windowed sinc, what ParaView, 3D Slicer and PyVista's
  ``smooth_taubin`` run) with its feature-edge smoothing on (edges over the feature angle are smoothed
  only along themselves, their corners fixed): at VTK's other defaults (20 iterations, pass band 0.1,
  feature angle 45°, coordinates normalised) and the best of iterations {10, 20, 50} × pass band
  {0.1, 0.01, 0.001} × feature angle {30, 45, 60}° or the feature-edge smoothing off.

Measured: RMS distance of the vertices to the clean surface (% of the diagonal, as bench_quality.py),
the dihedral-angle error on the true sharp edges (mean |angle − clean angle| over the mesh edges whose
clean faces meet at more than 25°), the volume change against the clean part, time. Targets (issue 24):
ours no worse than MeshLab's two-step (default and best) in RMS in every cell; sharp edges within 5°
at 0.5 % noise; |ΔV| ≤ 0.5 %.

``--cost`` times the Automatic Amount with the option on against HC's default (``core.smooth_mesh`` with
nothing set) on noisy tori of meshes.py (isotropic noise 0.1 % of the diagonal, float32), each run in a
fresh process, interleaved, medians of ``--repeat``; with the gap (the longest wait between two calls of
the progress callback: what a status line or a cancel waits for) and the process's peak memory.

``--bounds`` measures, instead of the peers, what the vertex fitting could reach with perfect normals:
ours with the clean part's face normals in place of the filtered ones at every step, and at the first
step only; ours with the first step's choice of nearest planes made by the truth (each face takes, of
its ring's filtered normals, the one nearest its clean normal: what a perfect choice of side could
reach with the filter as it is); ours with every face taking, at every step, of its ring's clean planes
the one nearest its corners (the sides' planes known exactly, the side still chosen from the noisy
positions: the nearest-plane choice with perfect planes); and the noisy vertices moved to their
nearest points of the clean surface (RMS 0: the creases' error of vertices on the surface but off the
crease lines).

``--organic`` smooths organic scans (no sharp edges) with the option on and reports it beside HC's
default and the best HC setting.

    python bench/run.py sharp_edges                                   # both sets (~10 min)
    python bench/run.py sharp_edges --sets tuning --parts cube --sigmas 0.005 --kinds normal
    python bench/run.py sharp_edges --organic bunny,cow --sigmas 0.001,0.0025,0.005 --sets none
    python bench/run.py sharp_edges --sets none --cost 250k,1M       # time and memory on noisy tori (~6 min)
    python bench/run.py sharp_edges --bounds --sigmas 0.005           # with perfect normals (~1 min)

The report goes to stdout and bench/results/; the numbers to a JSON file beside it.
"""

import json
import math
import sys
import time
import zlib

import numpy as np

import core
from bench import bench_default_heldout as heldout
from bench import bench_quality as quality
from bench import bench_quality_inputs as inputs
from bench import sharp_parts
from bench.common import ROOT, Parameter, counts, repeats
from core.mesh import sharp_edges

SETS = {"tuning": ("cube", "bevelled_box", "holed_cylinder"), "heldout": ("plate", "fandisk")}
SIGMAS = "0.001,0.0025,0.005,0.01"
CREASE_DEGREES = 25.0
DIHEDRAL_TARGET = 5.0  # degrees, at TARGET_SIGMA
TARGET_SIGMA = 0.005
VOLUME_TARGET = 0.005
TWO_STEP_GRID = [{"stepsmoothnum": s, "normalthr": a} for s in (1, 2, 3, 5, 8) for a in (30.0, 45.0, 60.0)]
PRESERVING_GRID = [{"iterations": k, "angledeg": a} for k in (1, 5, 20) for a in (2.0, 10.0, 30.0)]
MESHLIB_GRID = [{"beta": b} for b in (0.003, 0.01, 0.03, 0.1)]
VTK_GRID = [
    {"iterations": k, "pass_band": p, **features}
    for k in (10, 20, 50)
    for p in (0.1, 0.01, 0.001)
    for features in ({"feature_angle": 30.0}, {"feature_angle": 45.0}, {"feature_angle": 60.0}, {"features": False})
]


def load(name):
    if name in sharp_parts.PARTS:
        return sharp_parts.PARTS[name]()
    return inputs.load_mesh(name)


def make_case(name, kind, sigma, seed, cache):
    if name not in cache:
        cache[name] = load(name)
    clean, faces = cache[name]
    normals = inputs.vertex_normals(clean, faces)
    cell_seed = zlib.crc32(f"{name}/{kind}/{sigma:g}".encode()) ^ seed
    noisy = inputs.add_noise(clean, normals, sigma * inputs.diagonal(clean), kind, cell_seed)
    case = quality.Case(name, kind, sigma, clean, faces, noisy)
    case.creases = creases(clean, faces)
    return case


def creases(vertices, faces, degrees=CREASE_DEGREES):
    """(face a, face b, dihedral angle in degrees) of the mesh edges whose two faces meet at more than
    ``degrees``: the true sharp edges."""
    pairs = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    key = pairs[:, 0].astype(np.int64) * len(vertices) + pairs[:, 1]
    order = np.argsort(key, kind="stable")
    key, face = key[order], np.repeat(np.arange(len(faces)), 3)[order]
    shared = key[1:] == key[:-1]
    a, b = face[:-1][shared], face[1:][shared]
    angles = dihedral(vertices, faces, a, b)
    sharp = angles > degrees
    return a[sharp], b[sharp], angles[sharp]


def dihedral(vertices, faces, a, b):
    normals = sharp_edges.face_normals(vertices, faces)
    return np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", normals[a], normals[b]), -1.0, 1.0)))


def measure(case, positions, seconds=None):
    measured = case.measure(positions)
    out = {"rms": measured["rms"], "dv": measured["dv"], "seconds": seconds}
    if getattr(case, "creases", None) is not None and case.creases[0].size:
        a, b, angles = case.creases
        errors = np.abs(dihedral(positions, case.faces, a, b) - angles)
        out.update(dihedral=float(errors.mean()), dihedral_median=float(np.median(errors)))
    return out


def timed(function, *args, **kwargs):
    start = time.perf_counter()
    result = function(*args, **kwargs)
    return result, time.perf_counter() - start


# --- methods ------------------------------------------------------------------------------------------


def ours(case, automatic=True):
    options = {} if automatic else {"iterations": sharp_edges.DEFAULT_ITERATIONS}
    result, report = core.smooth_mesh(
        case.noisy, case.edges, faces=case.faces, weld=True, keep_sharp_edges=True, return_report=True, **options
    )
    chosen = {"steps": report.iterations, "angle": round(math.degrees(report.sharpness_angle), 1)}
    return result, {**chosen, "held_parts": report.held_parts}  # parts left as they were (core.mesh.collapse)


def two_step(case, params):
    return quality._meshlab(case, "apply_coord_two_steps_smoothing", **params)


def preserving(case, params):
    return quality._meshlab(case, "apply_coord_laplacian_smoothing_surface_preserving", **params)


def meshlib_denoise(case, params):
    import meshlib.mrmeshnumpy as mn
    import meshlib.mrmeshpy as mm

    mesh = mn.meshFromFacesVerts(case.faces.astype(np.int32), case.noisy.astype(np.float32))
    settings = mm.DenoiseViaNormalsSettings()
    for name, value in params.items():
        setattr(settings, name, value)
    mm.meshDenoiseViaNormals(mesh, settings)
    out = mn.getNumpyVerts(mesh).astype(np.float64)
    if out.shape != case.noisy.shape:
        raise RuntimeError("MeshLib changed the vertex count")
    return out


def vtk_sinc(case, params):
    from vtk.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray, vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
    from vtkmodules.vtkFiltersCore import vtkWindowedSincPolyDataFilter

    points = vtkPoints()
    points.SetData(numpy_to_vtk(np.ascontiguousarray(case.noisy, dtype=np.float64), deep=True))
    cells = vtkCellArray()
    offsets = np.arange(0, 3 * len(case.faces) + 1, 3)
    cells.SetData(numpy_to_vtkIdTypeArray(offsets, deep=True), numpy_to_vtkIdTypeArray(case.faces.ravel(), deep=True))
    mesh = vtkPolyData()
    mesh.SetPoints(points)
    mesh.SetPolys(cells)
    sinc = vtkWindowedSincPolyDataFilter()
    sinc.SetInputData(mesh)
    sinc.SetFeatureEdgeSmoothing(params.get("features", True))
    sinc.NormalizeCoordinatesOn()
    sinc.SetNumberOfIterations(params.get("iterations", 20))
    sinc.SetPassBand(params.get("pass_band", 0.1))
    sinc.SetFeatureAngle(params.get("feature_angle", 45.0))
    sinc.Update()
    out = vtk_to_numpy(sinc.GetOutput().GetPoints().GetData()).astype(np.float64)
    if out.shape != case.noisy.shape:
        raise RuntimeError("VTK changed the vertex count")
    return out


PEERS = {  # name: (run, defaults, grid)
    "MeshLab two-step": (two_step, {}, TWO_STEP_GRID),
    "MeshLab surface-preserving": (preserving, {}, PRESERVING_GRID),
    "MeshLib denoise": (meshlib_denoise, {}, MESHLIB_GRID),
    "VTK windowed sinc": (vtk_sinc, {}, VTK_GRID),
}


def peer_cell(case, run, defaults, grid):
    result, seconds = timed(run, case, defaults)
    default = measure(case, result, seconds)
    best = None
    for params in grid:
        measured = case.rms(run(case, params))
        if best is None or measured < best[0]:
            best = (measured, params)
    best_result = run(case, best[1])
    return default, {**measure(case, best_result), "params": best[1]}


def measure_cell(name, set_name, kind, sigma, seed, cache, peers=True):
    case = make_case(name, kind, sigma, seed, cache)
    cell = {"set": set_name, "mesh": name, "kind": kind, "sigma": sigma, "vertices": len(case.noisy)}
    cell["input"] = measure(case, case.noisy)
    (result, chosen), seconds = timed(ours, case)
    cell["ours"] = {**measure(case, result, seconds), **chosen}
    (result, chosen), seconds = timed(ours, case, False)
    cell["ours_fixed"] = {**measure(case, result, seconds), **chosen}
    (result, chosen), seconds = timed(quality.hc_default, case)
    cell["hc"] = {**measure(case, result, seconds), "iterations": chosen["iterations"]}
    _, best = heldout.hc_grid(case)
    cell["hc_best"] = {**measure(case, quality.hc_fixed(case, best["params"])), "params": best["params"]}
    if peers:
        for peer, (run, defaults, grid) in PEERS.items():
            try:
                cell[peer], cell[peer + " best"] = peer_cell(case, run, defaults, grid)
            except ImportError as missing:
                cell[peer] = {"missing": str(missing)}
    return cell


class _CleanNormals:
    """core.mesh.sharp_edges with the clean face normals in place of the filtered ones at the steps of
    ``steps`` (all if None): a ``with`` block patches its filter and its nearest planes."""

    def __init__(self, normals, steps=None):
        self.normals, self.steps, self.step = normals, steps, 0

    def __enter__(self):
        self.saved = sharp_edges.filter_steps, sharp_edges.nearest_plane_normals
        filtering, nearest = self.saved

        def filter_steps(normals, rings, cos_threshold, iterations=sharp_edges.NORMAL_ITERATIONS, guidance=None):
            clean = self.steps is None or self.step in self.steps
            self.step += 1
            if not clean:
                return (yield from filtering(normals, rings, cos_threshold, iterations, guidance))
            yield
            return self.normals.copy()

        def nearest_plane_normals(points, normals, rings):
            clean = self.steps is None or self.step - 1 in self.steps
            return normals if clean else nearest(points, normals, rings)

        sharp_edges.filter_steps, sharp_edges.nearest_plane_normals = filter_steps, nearest_plane_normals
        return self

    def __exit__(self, *exc):
        sharp_edges.filter_steps, sharp_edges.nearest_plane_normals = self.saved


class _BestRingNormal:
    """core.mesh.sharp_edges with the first step's nearest planes chosen by the truth: each face takes, of its
    ring's filtered normals, the one nearest its clean normal. A ``with`` block patches the choice."""

    def __init__(self, normals):
        self.normals, self.calls = normals, 0

    def __enter__(self):
        self.saved = sharp_edges.nearest_plane_normals

        def nearest_plane_normals(points, normals, rings):
            self.calls += 1
            if self.calls > 2:  # the first step chooses twice: from the start, from the fitted corners
                return self.saved(points, normals, rings)
            pairs = rings.ring.tocoo()
            closeness = np.einsum("ij,ij->i", normals[pairs.col], self.normals[pairs.row])
            order = np.lexsort((-closeness, pairs.row))
            first = np.r_[0, np.flatnonzero(np.diff(pairs.row[order])) + 1]
            return normals[pairs.col[order][first]]

        sharp_edges.nearest_plane_normals = nearest_plane_normals
        return self

    def __exit__(self, *exc):
        sharp_edges.nearest_plane_normals = self.saved


class _CleanPlanes:
    """core.mesh.sharp_edges where every face, at every step, takes of its ring's clean planes (each face's clean
    normal through its clean centroid) the one nearest its current corners: the choice of side with the
    sides' planes known exactly, made as ``nearest_plane_normals`` makes it. A ``with`` block patches the
    filter (its normals are not used) and the choice."""

    def __init__(self, case):
        self.faces = case.faces
        self.normals = sharp_edges.face_normals(case.clean, case.faces)
        self.offsets = np.einsum("ij,ij->i", self.normals, case.clean[case.faces].mean(axis=1))

    def __enter__(self):
        self.saved = sharp_edges.filter_steps, sharp_edges.nearest_plane_normals

        def filter_steps(normals, rings, cos_threshold, iterations=sharp_edges.NORMAL_ITERATIONS, guidance=None):
            yield
            return normals

        def nearest_plane_normals(points, normals, rings):
            pairs = rings.ring.tocoo()
            distances = np.einsum("mkc,mc->mk", points[self.faces[pairs.row]], self.normals[pairs.col])
            cost = np.sum((distances - self.offsets[pairs.col][:, None]) ** 2, axis=1)
            order = np.lexsort((cost, pairs.row))
            first = np.r_[0, np.flatnonzero(np.diff(pairs.row[order])) + 1]
            return self.normals[pairs.col[order][first]]

        sharp_edges.filter_steps, sharp_edges.nearest_plane_normals = filter_steps, nearest_plane_normals
        return self

    def __exit__(self, *exc):
        sharp_edges.filter_steps, sharp_edges.nearest_plane_normals = self.saved


def bounds_cell(name, set_name, kind, sigma, seed, cache):
    case = make_case(name, kind, sigma, seed, cache)
    cell = {"set": set_name, "mesh": name, "kind": kind, "sigma": sigma}
    cell["input"] = measure(case, case.noisy)
    cell["ours"] = measure(case, ours(case)[0])
    clean = sharp_edges.face_normals(case.clean, case.faces)
    with _CleanNormals(clean):
        cell["clean normals"] = measure(case, ours(case)[0])
    with _CleanNormals(clean, steps={0}):
        cell["clean normals, first step"] = measure(case, ours(case)[0])
    with _BestRingNormal(clean):
        cell["best ring normal, first step"] = measure(case, ours(case)[0])
    with _CleanPlanes(case):
        cell["clean planes, side by the corners"] = measure(case, ours(case)[0])
    import open3d as o3d

    nearest = case.surface.scene.compute_closest_points(o3d.core.Tensor(case.noisy.astype(np.float32)))
    cell["on the surface"] = measure(case, nearest["points"].numpy().astype(np.float64))
    return cell


BOUND_COLUMNS = [
    "input",
    "ours",
    "clean normals",
    "clean normals, first step",
    "best ring normal, first step",
    "clean planes, side by the corners",
    "on the surface",
]


# --- report -------------------------------------------------------------------------------------------


def pct(value, digits=3):
    return "–" if value is None else f"{100 * value:.{digits}f}"


COLUMNS = [
    ("input", "input"),
    ("ours", "**ours (auto)**"),
    ("ours_fixed", f"ours ({sharp_edges.DEFAULT_ITERATIONS} steps)"),
    ("hc", "HC default"),
    ("hc_best", "HC best"),
    ("MeshLab two-step", "two-step"),
    ("MeshLab two-step best", "two-step best"),
    ("MeshLab surface-preserving", "surf.-pres."),
    ("MeshLab surface-preserving best", "surf.-pres. best"),
    ("MeshLib denoise", "MeshLib"),
    ("MeshLib denoise best", "MeshLib best"),
    ("VTK windowed sinc", "VTK sinc"),
    ("VTK windowed sinc best", "VTK sinc best"),
]


def table(cells, out, key, title, formatter):
    present = [(k, label) for k, label in COLUMNS if any(k in cell and key in cell[k] for cell in cells)]
    out(f"\n{title}\n")
    out("| part | noise | " + " | ".join(label for _, label in present) + " |")
    out("|---|---|" + "---:|" * len(present))
    for cell in cells:
        values = [formatter(cell[k].get(key)) if k in cell and key in cell[k] else "–" for k, _ in present]
        out(f"| {cell['mesh']} | {cell['kind']} {100 * cell['sigma']:g} % | " + " | ".join(values) + " |")


def targets(cells, out, name):
    beaten = [
        c
        for c in cells
        if "MeshLab two-step" in c
        and "rms" in c["MeshLab two-step"]
        and c["ours"]["rms"] > min(c["MeshLab two-step"]["rms"], c["MeshLab two-step best"]["rms"])
    ]
    above_default = [
        c for c in cells if "rms" in c.get("MeshLab two-step", {}) and c["ours"]["rms"] > c["MeshLab two-step"]["rms"]
    ]
    at_target = [c for c in cells if c["sigma"] == TARGET_SIGMA and "dihedral" in c["ours"]]
    sharp = [c for c in at_target if c["ours"]["dihedral"] <= DIHEDRAL_TARGET]
    sharp_median = [c for c in at_target if c["ours"]["dihedral_median"] <= DIHEDRAL_TARGET]
    volume = [c for c in cells if c["ours"]["dv"] is not None and abs(c["ours"]["dv"]) <= VOLUME_TARGET]
    closed = [c for c in cells if c["ours"]["dv"] is not None]
    out(
        f"\n**{name}** ({len(cells)} cells). Ours (auto) RMS ≤ MeshLab two-step's default in "
        f"{len(cells) - len(above_default)} / {len(cells)} cells, ≤ its default and its best in "
        f"{len(cells) - len(beaten)} / {len(cells)}; sharp edges within {DIHEDRAL_TARGET:g}° at "
        f"{100 * TARGET_SIGMA:g} % in {len(sharp)} / {len(at_target)} (the median error within it in "
        f"{len(sharp_median)} / {len(at_target)}); |ΔV| ≤ {100 * VOLUME_TARGET:g} % in "
        f"{len(volume)} / {len(closed)}."
    )
    for c in beaten:
        out(
            f"- RMS above two-step's: {c['mesh']} {c['kind']} {100 * c['sigma']:g} %: ours "
            f"{pct(c['ours']['rms'])}, two-step {pct(c['MeshLab two-step']['rms'])}, best "
            f"{pct(c['MeshLab two-step best']['rms'])} ({c['MeshLab two-step best']['params']})"
        )


def report(record, out):
    out("# Keep Sharp Edges on sharp-edged parts\n")
    out(f"Default angle {record['angle']:g}°, load average {record['load']}.")
    for set_name in ("tuning", "heldout"):
        cells = [c for c in record["cells"] if c["set"] == set_name]
        if not cells:
            continue
        out(f"\n## {set_name} set: {', '.join(dict.fromkeys(c['mesh'] for c in cells))}")
        table(cells, out, "rms", "RMS distance to the clean surface, % of the diagonal:", pct)
        table(
            cells,
            out,
            "dihedral",
            f"Sharp edges: mean |dihedral error|, degrees (edges > {CREASE_DEGREES:g}°):",
            lambda v: "–" if v is None else f"{v:.1f}",
        )
        table(
            cells,
            out,
            "dv",
            "Volume change against the clean part, %:",
            lambda v: "–" if v is None else f"{100 * v:+.2f}",
        )
        table(cells, out, "seconds", "Time, seconds (one run):", lambda v: "–" if v is None else f"{v:.2f}")
        out(
            "\nOurs: steps and angle the Automatic Amount chose: "
            + "; ".join(
                f"{c['mesh']} {c['kind']} {100 * c['sigma']:g} %: {c['ours']['steps']} at {c['ours']['angle']:g}°"
                + (f", {c['ours']['held_parts']} parts held" if c["ours"].get("held_parts") else "")
                for c in cells
            )
        )
        targets(cells, out, set_name)
    if record.get("bounds"):
        out(
            "\n## With perfect normals\n\nMean / median |dihedral error| on the true sharp edges, degrees (RMS, % "
            "of the diagonal): ours with the clean face normals given to the fitting at every step, at the first "
            "step only, with each face taking at the first step the filtered normal of its ring nearest its clean "
            "normal, with each face taking at every step the clean plane of its ring nearest its corners (the "
            "sides' planes known exactly, the side chosen from the positions), and the noisy vertices moved to "
            "their nearest points of the clean surface.\n"
        )
        out("| part | noise | " + " | ".join(BOUND_COLUMNS) + " |")
        out("|---|---|" + "---:|" * len(BOUND_COLUMNS))
        for c in record["bounds"]:
            values = [
                f"{c[k]['dihedral']:.1f} / {c[k]['dihedral_median']:.1f} ({pct(c[k]['rms'])})" for k in BOUND_COLUMNS
            ]
            out(f"| {c['mesh']} | {c['kind']} {100 * c['sigma']:g} % | " + " | ".join(values) + " |")
    organic = record.get("organic", [])
    if organic:
        out("\n## Organic scans with Keep Sharp Edges on\n")
        out("RMS distance to the scan, % of the diagonal (the scans' own scanner noise is in the truth):\n")
        out("| scan | noise | input | HC default | HC best | ours (auto) | ours / HC default |")
        out("|---|---|---:|---:|---:|---:|---:|")
        for c in organic:
            out(
                f"| {c['mesh']} | {c['kind']} {100 * c['sigma']:g} % | {pct(c['input']['rms'])} | "
                f"{pct(c['hc']['rms'])} | {pct(c['hc_best']['rms'])} | {pct(c['ours']['rms'])} | "
                f"{c['ours']['rms'] / c['hc']['rms']:.2f} |"
            )


def timed_with_gap(function, *args, **kwargs):
    """(seconds, the longest wait between two calls of the progress callback or the ends: what a cancel
    waits for or a status line shows, the wait before the first call, the run's report) of
    ``function(*args, return_report=True, progress=..., **kwargs)``."""
    called = [time.perf_counter()]
    _, report = function(*args, return_report=True, progress=lambda _: called.append(time.perf_counter()), **kwargs)
    called.append(time.perf_counter())
    return called[-1] - called[0], float(np.max(np.diff(called))), called[1] - called[0], report


def cost_child(size, method):
    """One timed run in this (fresh) process, printed as JSON: HC's default ("hc") or Keep Sharp Edges with
    the Automatic Amount ("sharp") on the noisy torus of ``size`` vertices, with this process's peak RSS
    (the torus, NumPy and SciPy included) and its RSS before the run."""
    import resource

    from bench import meshes

    vertices, faces = meshes.torus(size)
    noisy = meshes.add_noise(vertices, 0.001, seed=1).astype(np.float32)
    edges = meshes.edges_from_faces(faces)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    options = {"keep_sharp_edges": True} if method == "sharp" else {}
    seconds, gap, first, report = timed_with_gap(core.smooth_mesh, noisy, edges, faces=faces, **options)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        json.dumps(
            {
                "seconds": seconds,
                "gap": gap,
                "first": first,
                "steps": report.iterations,
                "peak_mb": peak,
                "before_mb": before,
                "vertices": len(vertices),
            }
        )
    )


def cost(sizes, repeat, out, record):
    """HC's default and Keep Sharp Edges (Automatic Amount) on noisy tori, each run in a fresh process,
    interleaved, ``repeat`` times: medians of time, longest progress gap, peak memory."""
    import subprocess

    out("\n## Cost on big meshes\n")
    out(
        f"Noisy tori (isotropic noise 0.1 % of the diagonal, float32), each run in a fresh process, HC's default "
        f"and Keep Sharp Edges interleaved, medians of {repeat}; gap: the longest wait between two calls of the "
        "progress callback (what a status line or a cancel waits for); peak: the process's largest RSS (torus, "
        "NumPy and SciPy included; the RSS before the run in brackets).\n"
    )
    out(
        "| vertices | HC default (s) | Keep Sharp Edges (s) | ratio | steps | s per step | gap (s) | first call (s) "
        "| peak MB |"
    )
    out("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for size in sizes:
        runs = {"hc": [], "sharp": []}
        for _ in range(repeat):
            for method in runs:
                command = [sys.executable, "-m", "bench.bench_sharp_edges", str(size), method]
                done = subprocess.run(command, capture_output=True, text=True, check=True, cwd=ROOT)
                runs[method].append(json.loads(done.stdout.strip().splitlines()[-1]))
        record.setdefault("cost", []).append({"size": size, **runs})
        hc, ours = (float(np.median([r["seconds"] for r in runs[m]])) for m in ("hc", "sharp"))
        middle = {key: float(np.median([r[key] for r in runs["sharp"]])) for key in runs["sharp"][0]}
        out(
            f"| {int(middle['vertices']):,} | {hc:.1f} | {ours:.1f} | {ours / hc:.1f} | {middle['steps']:g} | "
            f"{ours / max(middle['steps'], 1):.1f} | {middle['gap']:.2f} | {middle['first']:.2f} | "
            f"{middle['peak_mb']:.0f} ({middle['before_mb']:.0f}) |"
        )


PARAMETERS = (
    Parameter("sets", "tuning,heldout", "tuning, heldout, or none"),
    Parameter("parts", "", "only these parts of the sets"),
    Parameter("sigmas", SIGMAS),
    Parameter("kinds", "normal,iso"),
    Parameter("organic", "", "organic scans to run with the option on, e.g. bunny"),
    Parameter("cost", "", "torus sizes to time, e.g. 250k,1M", counts),
    repeats(3, "--cost runs of each method, each in a fresh process (medians)"),
    Parameter("bounds", False, "with perfect normals, instead of the peers"),
    Parameter("no_peers", False, "ours alone"),
    Parameter("seed", 0),
)
QUICK = {
    "sets": "tuning",
    "parts": "holed_cylinder",
    "sigmas": "0.005",
    "kinds": "iso",
    "cost": "5k",
    "repeats": 1,
    "no_peers": True,
}


def run(args, out):
    sigmas = inputs.parse_list(args.sigmas, float)
    kinds = inputs.parse_list(args.kinds)
    only = set(inputs.parse_list(args.parts)) or None
    record = {
        "angle": math.degrees(sharp_edges.DEFAULT_SHARPNESS_ANGLE),
        "load": " ".join(f"{x:.1f}" for x in __import__("os").getloadavg()),
        "cells": [],
        "organic": [],
        "bounds": [],
    }
    cache = {}
    for set_name in inputs.parse_list(args.sets):
        for name in SETS.get(set_name, ()):
            if only and name not in only:
                continue
            for kind in kinds:
                for sigma in sigmas:
                    if args.bounds:
                        record["bounds"].append(bounds_cell(name, set_name, kind, sigma, args.seed, cache))
                        continue
                    record["cells"].append(
                        measure_cell(name, set_name, kind, sigma, args.seed, cache, peers=not args.no_peers)
                    )
                    c = record["cells"][-1]
                    print(
                        f"  {name} {kind} {sigma:g}: ours {pct(c['ours']['rms'])}, two-step "
                        f"{pct(c.get('MeshLab two-step', {}).get('rms'))}",
                        file=sys.stderr,
                        flush=True,
                    )
    for name in inputs.parse_list(args.organic):
        for kind in kinds:
            for sigma in sigmas:
                record["organic"].append(measure_cell(name, "organic", kind, sigma, args.seed, cache, peers=False))
    report(record, out)
    if args.cost:
        cost(args.cost, args.repeats, out, record)
    return record


if __name__ == "__main__":  # one --cost run in a fresh process: python -m bench.bench_sharp_edges SIZE METHOD
    cost_child(int(sys.argv[1]), sys.argv[2])
