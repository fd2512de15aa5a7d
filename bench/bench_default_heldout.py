"""Does the Automatic Amount generalise? HC Smooth's default on the meshes it was tuned on and on
real scans it never saw, against the best HC setting of a grid, the fixed HC default and two Taubin
defaults.

Sets (bench_quality_inputs.py): ``tuning`` (the eight meshes of bench_quality.py, the ones the
Automatic Amount was tuned on) and ``heldout`` (real scans, open range scans among them). Noise σ =
0.1 / 0.25 / 0.5 % of the bounding-box diagonal along the clean vertex normals ("normal") or on every
coordinate ("iso"), one seed per cell (as bench_quality.py makes them). Measured, % of the diagonal,
for the noisy input and each of

* the default: ``core.smooth_mesh(noisy, edges, faces=faces, weld=True, border="free")``, as the
  add-on runs it with nothing set (Keep in Place on);
* the default, sliding: the same with ``keep_in_place=False``;
* the best HC setting of the grid α {0, 0.05, 0.1, 0.2} × β {0.6, 0.75, 0.9} × iterations {1, 2, 3,
  5, 8, 12, 20, 30, 50, 80, 120, 200} (one run per (α, β), read at each count; a run stops once its
  errors are past their minima by a quarter), chosen by the surface measure and by the vertex measure;
* the fixed HC default (α 0.1, β 0.6, 10 iterations);
* trimesh's ``filter_taubin`` and MeshLab's ``apply_coord_taubin_smoothing`` at their defaults
  (λ 0.5, μ −0.5 / −0.53, 10 iterations):

* surface: the RMS distance of all vertices (open borders included) to the clean surface;
* vertex: the RMS distance of each vertex to its own clean position;
* slide: the RMS of the along-surface part of each vertex's move from the noisy input (the move less
  its component along the clean vertex normal);
* open meshes: the border vertices' (on an edge of one face) RMS distance to the clean border curve
  (the clean mesh's border edges as segments), and their pull-in: the mean offset from the nearest
  point of that curve along the clean surface's inward direction there (in the border face's plane,
  across the edge, towards its third corner), in σ and in % of the diagonal.

Targets, counted per set. Issue 22, item 8 (surface): the default within 15 % of the best HC setting;
never more than 5 % worse than the fixed HC default; better than both Taubin defaults in at least 80 %
of the cells. Issue 31: the default's slide ≤ MeshLab Taubin's and ≤ 0.4 × the sliding default's; its
surface distance ≤ 1.05 × the sliding default's; its vertex distance (normal noise) below every peer
default's and ≤ 1.15 × the best HC setting's by the vertex measure (isotropic noise: reported only);
on open meshes a border pull-in ≤ 0.1 σ and a border distance to the clean curve ≤ 0.5 × the input's.

Real scans carry their own scanner noise, and the scan is the truth the results are measured
against: a smoother that removes that noise too is counted as moving away from the truth. Each run
also smooths every real scan with no noise added and reports the noise the default estimates, how far
it moves the scan and how that compares with the lightest noise added (0.1 %). ``--reference``
takes the scanner noise out of the truth first: the real scans are smoothed once (by the default,
``default``, or by MeshLab's two-step smoothing, ``two-step``: a smoother that is neither HC nor
Taubin) and the result is the clean mesh the noise is added to.

    python bench/bench_default_heldout.py --sets heldout                      # one set (~10 min)
    python bench/bench_default_heldout.py --meshes face,armadillo --sigmas 0.001 --kinds normal
    python bench/bench_default_heldout.py --scanner                           # scanner noise only
    python bench/bench_default_heldout.py --sets heldout --sigmas 0.001 --reference two-step
    python bench/run.py default_heldout --sources a.json,b.json           # the report of earlier runs

The report goes to stdout and bench/results/; the numbers (grids included) to a JSON file beside it,
which ``--from`` reads back (runs split by mesh or σ give one report).
"""

import json
import os
import pathlib
import sys
import time
import zlib

import numpy as np

import core
from bench import bench_quality as quality
from bench import bench_quality_inputs as inputs
from bench import meshes
from bench.common import ROOT, Parameter
from core.mesh.in_place import keep_in_place

SIGMAS = "0.001,0.0025,0.005"
ALPHAS = (0.0, 0.05, 0.1, 0.2)
BETAS = (0.6, 0.75, 0.9)
CHECKPOINTS = (1, 2, 3, 5, 8, 12, 20, 30, 50, 80, 120, 200)
FIXED = {"alpha": 0.1, "beta": 0.6, "iterations": 10}
TRIMESH_TAUBIN = {"lamb": 0.5, "nu": 0.5, "iterations": 10}  # filter_taubin's defaults
BEST_WITHIN = 1.15  # the default's error at most this times the best HC setting's ...
FIXED_WITHIN = 1.05  # ... and this times the fixed HC default's, in every cell ...
TAUBIN_SHARE = 0.8  # ... and below both Taubin defaults in this share of the cells
# Issue 31, counted per set on the cells with the measures (surface, vertex, slide, border):
SLIDE_WITHIN = 0.4  # the default's slide at most this times the sliding default's (and <= MeshLab Taubin's)
SURFACE_WITHIN = 1.05  # the default's distance to the surface at most this times the sliding default's
VERTEX_WITHIN = 1.15  # vertex distance at most this times the best HC setting's by that measure (normal noise)
PULL_WITHIN = 0.1  # open meshes: the border's mean pull into the surface at most this times σ ...
BORDER_WITHIN = 0.5  # ... and its RMS distance to the clean border curve at most this times the input's
LIGHT = 0.001  # the lightest noise added, the scale scanner noise is compared with
REFERENCES = {
    "scan": "the scan as it is",
    "default": "the scan smoothed by HC Smooth's default",
    "two-step": "the scan smoothed by MeshLab's two-step smoothing",
}


def core_version():
    """The commit the measured core is at (and whether core/ differs from it), or the ``.commit`` file of
    an exported tree (``git archive``)."""
    import subprocess

    try:
        commit = subprocess.run(
            ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=True
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "-C", str(ROOT), "status", "--porcelain", "core"], capture_output=True, text=True, check=True
        ).stdout.strip()
        return f"core at {commit}" + (" with uncommitted changes" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        stamp = ROOT / ".commit"
        return f"core at {stamp.read_text().strip()[:7]} (exported)" if stamp.exists() else f"core from {ROOT}"


def is_scan(mesh):
    return mesh in inputs.REAL or mesh in inputs.SCANS


def clean_mesh(mesh, reference):
    """(vertices, faces) of the truth: the mesh as stored, or for a real scan its own noise smoothed away
    first (REFERENCES)."""
    vertices, faces = inputs.load_mesh(mesh)
    if reference == "scan" or not is_scan(mesh):
        return vertices, faces
    if reference == "default":
        return core.smooth_mesh(vertices, meshes.edges_from_faces(faces), faces=faces), faces
    if reference == "two-step":
        stored = quality.Case(mesh, "none", 0.0, vertices, faces, vertices)
        return quality._meshlab(stored, "apply_coord_two_steps_smoothing"), faces
    raise ValueError(f"reference {reference!r}: one of {', '.join(REFERENCES)}")


def make_case(mesh, kind, sigma, seed, reference="scan"):
    """bench_quality.make_case (the same noise, seed for seed) on the truth ``reference`` gives."""
    clean, faces = clean_mesh(mesh, reference)
    normals = inputs.vertex_normals(clean, faces)
    cell_seed = zlib.crc32(f"{mesh}/{kind}/{sigma:g}".encode()) ^ seed
    noisy = inputs.add_noise(clean, normals, sigma * inputs.diagonal(clean), kind, cell_seed)
    return quality.Case(mesh, kind, sigma, clean, faces, noisy)


def hc_grid(case, border="free", vertex=None, in_place=None):
    """RMS at every (alpha, beta, checkpoint) of the grid (NaN past a path's end), under the open-border
    rule ``border``. Returns (grid, best {params, rms}); with ``vertex`` (a function of the positions: the
    RMS distance of each vertex to its own clean position) also (that measure's grid, its best {params,
    vertex}); with ``in_place`` too (a function of the positions: the surface distance of the run kept in
    place), its best {params, surface} last."""
    if vertex is None:
        grid = quality.walk_grid(case, ALPHAS, BETAS, CHECKPOINTS, border=border)
        return grid, _best(grid, "rms")
    extra = {"vertex": vertex} if in_place is None else {"vertex": vertex, "in_place": in_place}
    grid, values = quality.walk_grid(case, ALPHAS, BETAS, CHECKPOINTS, border=border, measures=extra)
    found = (grid, _best(grid, "rms"), values["vertex"], _best(values["vertex"], "vertex"))
    return found if in_place is None else (*found, _best(values["in_place"], "surface"))


def _best(grid, name):
    """{params, name: value} of the grid's smallest value."""
    ia, ib, ic = np.unravel_index(np.nanargmin(grid), grid.shape)
    params = {"alpha": ALPHAS[ia], "beta": BETAS[ib], "iterations": CHECKPOINTS[ic]}
    return {"params": params, name: float(grid[ia, ib, ic])}


def meshlab_taubin(case):
    return quality._meshlab(case, "apply_coord_taubin_smoothing")


def border_share(faces, count):
    """The share of the vertices on an open border (an edge of one face)."""
    pairs = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    unique, counts = np.unique(pairs, axis=0, return_counts=True)
    return np.unique(unique[counts == 1]).size / count


class CleanBorder:
    """The clean mesh's open border (its edges of exactly one face) as segments, each with the unit
    direction into the surface (in its face's plane, perpendicular to the segment, towards the face's
    third corner; where the nearest point is a border vertex, the mean of its segments'); ``vertices``:
    the border vertices (the same in every result: the faces do not change)."""

    CANDIDATES = 16  # nearest segment midpoints tried first; a point with more to check takes a ball query

    def __init__(self, clean, faces):
        from scipy.spatial import cKDTree

        pairs = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        third = faces[:, [2, 0, 1]].reshape(-1)
        unique, first, counts = np.unique(pairs, axis=0, return_index=True, return_counts=True)
        one = counts == 1
        self.edges = unique[one]
        self.vertices = np.unique(self.edges)
        if not self.edges.size:
            return
        self.start = clean[self.edges[:, 0]]
        self.along = clean[self.edges[:, 1]] - self.start
        self.length2 = np.einsum("ij,ij->i", self.along, self.along)
        towards = clean[third[first[one]]] - self.start
        towards -= (np.einsum("ij,ij->i", towards, self.along) / np.maximum(self.length2, 1e-300))[:, None] * self.along
        self.inward = towards / np.maximum(np.linalg.norm(towards, axis=1), 1e-300)[:, None]
        corner = np.zeros_like(clean)  # at a border vertex: the mean of its segments' directions
        for end in (0, 1):
            np.add.at(corner, self.edges[:, end], self.inward)
        self.corner = corner / np.maximum(np.linalg.norm(corner, axis=1), 1e-300)[:, None]
        self.half = 0.5 * float(np.sqrt(self.length2.max()))
        self.tree = cKDTree(self.start + 0.5 * self.along)

    def __bool__(self):
        return bool(self.edges.size)

    def _nearest(self, points, candidates):
        """(points, k) candidate segments -> (index of the nearest, offset from its nearest point, the
        inward direction there)."""
        t = np.einsum("ikj,ikj->ik", points[:, None] - self.start[candidates], self.along[candidates])
        t = np.clip(t / np.maximum(self.length2[candidates], 1e-300), 0.0, 1.0)
        offset = points[:, None] - (self.start[candidates] + t[..., None] * self.along[candidates])
        pick = np.argmin(np.einsum("ikj,ikj->ik", offset, offset), axis=1)
        rows = np.arange(len(points))
        segment, t = candidates[rows, pick], t[rows, pick]
        inward = self.inward[segment]
        for end, at in ((0, t <= 0.0), (1, t >= 1.0)):
            inward[at] = self.corner[self.edges[segment[at], end]]
        return segment, offset[rows, pick], inward

    def measure(self, positions):
        """(RMS distance of the border vertices to the clean border curve, their mean offset from it into
        the surface), in the positions' units."""
        points = positions[self.vertices]
        k = min(self.CANDIDATES, len(self.edges))
        reach, candidates = self.tree.query(points, k=k)
        candidates = candidates.reshape(len(points), k)
        segment, offset, inward = self._nearest(points, candidates)
        distance = np.linalg.norm(offset, axis=1)
        if k < len(self.edges):  # a segment not among the k nearest midpoints can still be nearer: check
            unsure = np.flatnonzero(distance + self.half > reach.reshape(len(points), k)[:, -1])
            for i in unsure:
                found = np.array(self.tree.query_ball_point(points[i], distance[i] + self.half + 1e-12))
                segment[i], offset[i], inward[i] = (a[0] for a in self._nearest(points[i : i + 1], found[None]))
            distance = np.linalg.norm(offset, axis=1)
        pull = np.einsum("ij,ij->i", offset, inward)
        return float(np.sqrt(np.mean(distance**2))), float(pull.mean())


def measures(case, normals, border, positions):
    """Issue 31's measures of one result, fractions of the diagonal: RMS distance to the clean surface
    (``surface``), of each vertex to its own clean position (``vertex``), of the part of each vertex's
    move (from the noisy input) along the surface, across the clean vertex normal (``slide``); on open
    meshes the border vertices' RMS distance to the clean border curve (``border``) and their mean offset
    from it into the surface (``pull``; ``pull_sigma`` in units of the noise σ)."""
    d = case.diagonal
    move = positions - case.noisy
    slide = move - np.einsum("ij,ij->i", move, normals)[:, None] * normals
    out = {
        "surface": case.rms(positions),
        "vertex": float(np.sqrt(np.mean(np.sum((positions - case.clean) ** 2, axis=1))) / d),
        "slide": float(np.sqrt(np.mean(np.sum(slide**2, axis=1))) / d),
    }
    if border:
        distance, pull = border.measure(positions)
        out.update(border=distance / d, pull=pull / d, pull_sigma=pull / d / case.sigma if case.sigma else None)
    return out


METHODS = {  # key in a cell's "measures" -> column title
    "input": "input",
    "default": "default",
    "sliding": "default, sliding",
    "fixed": "fixed HC",
    "trimesh_taubin": "trimesh Taubin",
    "meshlab_taubin": "MeshLab Taubin",
    "best": "best HC (surface)",
    "best_vertex": "best HC (vertex)",
}


def best_curve(case, border):
    """What 1-D smoothing reaches on an open mesh's border: the smallest RMS distance of the border vertices
    to the clean border curve (fraction of the diagonal) when the noisy border alone is smoothed as curves
    (HC on the border edges, the surface's other vertices left out), over the grid's alphas, betas and
    iterations (each path run once, read at its checkpoints); with its (alpha, beta, iterations)."""
    local = np.searchsorted(border.vertices, border.edges)
    positions = case.noisy.copy()
    best = (np.inf, None)
    for alpha in ALPHAS:
        for beta in BETAS:
            run = quality.quiet(
                core.Smoothing, case.noisy[border.vertices], local, alpha=alpha, beta=beta, iterations=CHECKPOINTS[-1]
            )
            done = 0
            for iterations in CHECKPOINTS:
                quality.quiet(run.advance, iterations - done)
                done = iterations
                positions[border.vertices] = run.result().positions
                distance = border.measure(positions)[0] / case.diagonal
                if distance < best[0]:
                    best = (distance, {"alpha": alpha, "beta": beta, "iterations": iterations})
    return {"border": float(best[0]), "params": best[1]}


def input_folded(case, triangles):
    """The share of the noisy input's triangles that face away from their clean triangle (shadow along its
    normal not positive): a layout folded by noise along the surface, which no result can keep in place
    without keeping the folds (core.mesh.in_place unfolds them by giving back slide)."""

    def normals(points):
        a, b, c = (points[triangles[:, k]] for k in range(3))
        return np.cross(b - a, c - a)

    return float(np.mean(np.einsum("ij,ij->i", normals(case.noisy), normals(case.clean)) <= 0.0))


def measure_cell(mesh, set_name, kind, sigma, seed, reference="scan"):
    case = make_case(mesh, kind, sigma, seed, reference)
    triangles = np.asarray(core.fan_triangles(case.faces))
    normals = inputs.vertex_normals(case.clean, case.faces)
    border = CleanBorder(case.clean, case.faces)
    start = time.perf_counter()
    ours, chosen = quality.hc_default(case)
    seconds = time.perf_counter() - start
    start = time.perf_counter()
    sliding, sliding_chosen = quality.hc_default(case, keep_in_place=False)
    sliding_seconds = time.perf_counter() - start
    results = {
        "input": case.noisy,
        "default": ours,
        "sliding": sliding,
        "fixed": quality.hc_fixed(case, FIXED),
        "trimesh_taubin": quality.trimesh_taubin(case, TRIMESH_TAUBIN),
        "meshlab_taubin": meshlab_taubin(case),
    }
    cell = {
        "set": set_name,
        "reference": reference,
        "mesh": mesh,
        "kind": kind,
        "sigma": sigma,
        "vertices": len(case.noisy),
        "closed": case.closed,
        "border": border_share(case.faces, len(case.noisy)),
        "border_vertices": int(border.vertices.size),
        "input_folded": input_folded(case, triangles),
    }

    def vertex(positions):
        return float(np.sqrt(np.mean(np.sum((positions - case.clean) ** 2, axis=1))) / case.diagonal)

    def in_place(positions):
        return case.rms(keep_in_place(case.noisy, positions, triangles))

    grid, best, vertex_grid, best_vertex, best_in_place = hc_grid(case, vertex=vertex, in_place=in_place)
    cell["best_in_place"] = best_in_place
    results["best"] = quality.hc_fixed(case, best["params"])
    results["best_vertex"] = quality.hc_fixed(case, best_vertex["params"])
    cell["measures"] = {name: measures(case, normals, border, positions) for name, positions in results.items()}
    if border:
        cell["best_curve"] = best_curve(case, border)
    m = cell["measures"]
    cell.update(
        {
            "input": m["input"]["surface"],
            "default": {**chosen, "rms": m["default"]["surface"], "seconds": seconds},
            "sliding": {**sliding_chosen, "rms": m["sliding"]["surface"], "seconds": sliding_seconds},
            "fixed": m["fixed"]["surface"],
            "trimesh_taubin": m["trimesh_taubin"]["surface"],
            "meshlab_taubin": m["meshlab_taubin"]["surface"],
            "best": best,
            "best_vertex": best_vertex,
        }
    )
    if quality.BORDER != "free" and cell["border"] > 0:  # the best HC setting that keeps borders as ours does
        cell["best_same_border"] = hc_grid(case, quality.BORDER)[1]
    cell["grid"] = {
        "alphas": ALPHAS,
        "betas": BETAS,
        "iterations": CHECKPOINTS,
        "rms": grid.tolist(),
        "vertex": vertex_grid.tolist(),
    }
    return cell


def measure_scanner(mesh, set_name):
    """The default on a real scan with no noise added: the noise it finds and how far it moves the scan."""
    clean, faces = inputs.load_mesh(mesh)
    case = quality.Case(mesh, "none", 0.0, clean, faces, clean.copy())
    ours, chosen = quality.hc_default(case)
    fixed = quality.hc_fixed(case, FIXED)
    move = np.linalg.norm(ours - clean, axis=1) / case.diagonal
    return {
        "set": set_name,
        "mesh": mesh,
        "vertices": len(clean),
        "closed": case.closed,
        "edge": inputs.mean_edge_length(clean, faces) / case.diagonal,
        "default": chosen,
        "move_rms": float(np.sqrt(np.mean(move**2))),
        "move_max": float(move.max()),
        "distance_rms": case.rms(ours),
        "fixed_distance_rms": case.rms(fixed),
    }


# --- report -------------------------------------------------------------------------------------------


def pct(value, digits=3):
    return "–" if value is None else f"{100 * value:.{digits}f}"


def amount_text(params):
    text = f"{params['iterations']} it."
    if params["beta"] != FIXED["beta"]:
        text += f", β {params['beta']:g}"
    if "noise" in params:
        text += f", σ̂ {100 * params['noise']:.3f}"
    if params.get("held_parts"):
        text += f", {params['held_parts']} parts held"  # the default would have collapsed them (core.mesh.collapse)
    return text


def verdicts(cell):
    ours = cell["default"]["rms"]
    return {
        "best": ours <= BEST_WITHIN * cell["best"]["rms"],
        "fixed": ours <= FIXED_WITHIN * cell["fixed"],
        "taubin": ours < min(cell["trimesh_taubin"], cell["meshlab_taubin"]),
    }


def set_table(cells, out):
    out(
        "| mesh | noise | σ | input | default (amount, σ̂) | best HC (α, β, it.) | fixed HC | trimesh Taubin "
        "| MeshLab Taubin | default / best | default / fixed | below both Taubins |"
    )
    out("|---|---|---:|---:|---|---|---:|---:|---:|---:|---:|---|")
    for cell in cells:
        ours, best, marks = cell["default"]["rms"], cell["best"], verdicts(cell)
        p = best["params"]
        out(
            f"| {cell['mesh']} | {cell['kind']} | {100 * cell['sigma']:g} % | {pct(cell['input'])} "
            f"| {pct(ours)} ({amount_text(cell['default'])}) "
            f"| {pct(best['rms'])} ({p['alpha']:g}, {p['beta']:g}, {p['iterations']}) "
            f"| {pct(cell['fixed'])} | {pct(cell['trimesh_taubin'])} | {pct(cell['meshlab_taubin'])} "
            f"| {'' if marks['best'] else '**'}{ours / best['rms']:.2f}{'' if marks['best'] else '**'} "
            f"| {'' if marks['fixed'] else '**'}{ours / cell['fixed']:.2f}{'' if marks['fixed'] else '**'} "
            f"| {'yes' if marks['taubin'] else '**no**'} |"
        )


def targets(cells):
    """(within 15 % of the best, within 5 % of the fixed, below both Taubins, cells)."""
    marks = [verdicts(c) for c in cells]
    return tuple(sum(m[k] for m in marks) for k in ("best", "fixed", "taubin")) + (len(cells),)


def summary(name, cells, out):
    best, fixed, taubin, n = targets(cells)
    ratios = [c["default"]["rms"] / c["best"]["rms"] for c in cells]
    fixed_ratios = [c["default"]["rms"] / c["fixed"] for c in cells]
    out(
        f"**{name}**: within 15 % of the best HC setting in {best} of {n} cells (target: all; median "
        f"{np.median(ratios):.2f}×, worst {max(ratios):.2f}×); at most 5 % worse than the fixed HC default in "
        f"{fixed} of {n} (target: all; worst {max(fixed_ratios):.2f}×); below both Taubin defaults in {taubin} of "
        f"{n} = {taubin / n:.0%} (target ≥ {TAUBIN_SHARE:.0%})."
    )
    same = [c for c in cells if "best_same_border" in c]
    if same:
        ratios = [c["default"]["rms"] / c["best_same_border"]["rms"] for c in same]
        within = sum(r <= BEST_WITHIN for r in ratios)
        out(
            f"  Open meshes against the best HC setting with the same border rule ({quality.BORDER}): within 15 % "
            f"in {within} of {len(same)} (median {np.median(ratios):.2f}×, worst {max(ratios):.2f}×)."
        )
    by_sigma = {}
    for cell in cells:
        by_sigma.setdefault(cell["sigma"], []).append(cell)
    for sigma, group in sorted(by_sigma.items()):
        b, f, t, m = targets(group)
        out(f"  σ {100 * sigma:g} %: best {b}/{m}, fixed {f}/{m}, Taubins {t}/{m}")


def scanner_table(scans, cells, out):
    out(
        "\nScanner noise: each real scan smoothed by the default with no noise added. σ̂: the noise the "
        "default estimates (% of the diagonal, along the normals); RMS / max move of the vertices; RMS "
        "distance of the result to the scan's own surface (what the default scores at a σ of 0 in the "
        "tables above, where the scan is the truth); the same for the fixed HC default. At σ 0.1 % added: "
        "the default's σ̂ against √(0.1² + σ̂₀²), and its error there.\n"
    )
    out(
        "| mesh | set | vertices | edge / diag. | σ̂₀ (no noise added) | σ̂₀ / 0.1 % | iterations | RMS move "
        "| max move | distance, default | distance, fixed HC | σ̂ at 0.1 % normal / iso | √(0.1² + σ̂₀²) "
        "| error at 0.1 % normal / iso |"
    )
    out("|---|---|---:|---:|---:|---:|---|---:|---:|---:|---:|---|---:|---|")
    light = {
        (c["mesh"], c["kind"]): c
        for c in cells
        if abs(c["sigma"] - LIGHT) < 1e-12 and c.get("reference", "scan") == "scan"
    }
    for scan in scans:
        noise = scan["default"].get("noise", 0.0)
        seen = [light.get((scan["mesh"], k)) for k in ("normal", "iso")]
        estimates = " / ".join(pct(c["default"].get("noise")) if c else "–" for c in seen)
        errors = " / ".join(pct(c["default"]["rms"]) if c else "–" for c in seen)
        out(
            f"| {scan['mesh']} | {scan['set']} | {scan['vertices']:,} | {pct(scan['edge'])} | {pct(noise)} "
            f"| {noise / LIGHT:.2f} | {amount_text({k: v for k, v in scan['default'].items() if k != 'noise'})} "
            f"| {pct(scan['move_rms'])} | {pct(scan['move_max'])} | {pct(scan['distance_rms'])} "
            f"| {pct(scan['fixed_distance_rms'])} | {estimates} | {pct(np.hypot(LIGHT, noise))} | {errors} |"
        )


def cell_name(cell):
    return f"{cell['mesh']} {cell['kind']} {100 * cell['sigma']:g} %"


def ratio(ours, theirs):
    """ours / theirs; a part held (nothing moved: a slide of 0 on both sides) reads 1, ours alone moving inf."""
    if theirs:
        return ours / theirs
    return 1.0 if not ours else float("inf")


def in_place_checks(cell):
    """{target: (ratio or value, met)} of issue 31 for one cell; targets that do not apply are left out."""
    m = cell["measures"]
    ours = m["default"]
    checks = {
        "slide_meshlab": (
            ratio(ours["slide"], m["meshlab_taubin"]["slide"]),
            ours["slide"] <= m["meshlab_taubin"]["slide"],
        ),
        "slide_sliding": (
            ratio(ours["slide"], m["sliding"]["slide"]),
            ours["slide"] <= SLIDE_WITHIN * m["sliding"]["slide"],
        ),
        "surface_sliding": (
            ratio(ours["surface"], m["sliding"]["surface"]),
            ours["surface"] <= SURFACE_WITHIN * m["sliding"]["surface"],
        ),
    }
    peers = min(m[k]["vertex"] for k in ("trimesh_taubin", "meshlab_taubin", "fixed"))
    best = m["best_vertex"]["vertex"]
    normal = cell["kind"] == "normal"
    checks["vertex_peers"] = (ours["vertex"] / peers, ours["vertex"] < peers if normal else None)
    checks["vertex_best"] = (ours["vertex"] / best, ours["vertex"] <= VERTEX_WITHIN * best if normal else None)
    if "border" in ours:
        checks["pull"] = (ours["pull_sigma"], ours["pull_sigma"] <= PULL_WITHIN)
        checks["border"] = (
            ours["border"] / m["input"]["border"],
            ours["border"] <= BORDER_WITHIN * m["input"]["border"],
        )
    return checks


def mark(value, met, digits=2):
    text = f"{value:.{digits}f}"
    return f"**{text}**" if met is False else text


def measures_table(cells, out):
    out(
        "\nSurface / vertex / slide, % of the diagonal: RMS distance to the clean surface; RMS distance of each "
        "vertex to its own clean position; RMS of the along-surface part of each vertex's move from the noisy "
        "input (the move less its part along the clean vertex normal). Best HC (vertex): the grid's setting "
        "nearest by the vertex measure (α, β, it.). Ratios: the default's slide over MeshLab Taubin's (target "
        f"≤ 1) and over the sliding default's (≤ {SLIDE_WITHIN:g}); its surface distance over the sliding "
        f"default's (≤ {SURFACE_WITHIN:g}); its vertex distance over the nearest peer default's (fixed HC, "
        f"both Taubins; < 1) and over the best HC setting's by that measure (≤ {VERTEX_WITHIN:g}; normal noise "
        "only, iso: reported). **Bold**: missed.\n"
    )
    names = list(METHODS)
    out(
        "| mesh | noise | σ | "
        + " | ".join(METHODS[k] for k in names)
        + " | slide / MeshLab | slide / sliding | surface / sliding | vertex / peers | vertex / best |"
    )
    out("|---|---|---:|" + "---:|" * len(names) + "---:|---:|---:|---:|---:|")
    for cell in cells:
        m = cell["measures"]
        texts = []
        for k in names:
            text = f"{pct(m[k]['surface'])} / {pct(m[k]['vertex'])} / {pct(m[k]['slide'])}"
            if k == "best_vertex":
                p = cell["best_vertex"]["params"]
                text += f" ({p['alpha']:g}, {p['beta']:g}, {p['iterations']})"
            texts.append(text)
        c = in_place_checks(cell)
        ratios = [
            mark(*c[k]) for k in ("slide_meshlab", "slide_sliding", "surface_sliding", "vertex_peers", "vertex_best")
        ]
        out(f"| {cell['mesh']} | {cell['kind']} | {100 * cell['sigma']:g} % | " + " | ".join(texts + ratios) + " |")


def border_table(cells, out):
    open_cells = [c for c in cells if "border" in c["measures"]["default"]]
    if not open_cells:
        return
    out(
        "\nOpen meshes, border vertices (on an edge of one face) against the clean border curve (the clean "
        "mesh's border edges): RMS distance to the curve, % of the diagonal / mean offset from the curve into "
        "the surface (the pull-in, inward positive: in the clean face's plane, across the border edge), in σ "
        f"/ the same in % of the diagonal. Targets for the default: pull-in ≤ {PULL_WITHIN:g} σ, RMS ≤ "
        f"{BORDER_WITHIN:g} × the input's. **Bold**: missed.\n"
    )
    names = list(METHODS)
    out("| mesh | noise | σ | border vertices | " + " | ".join(METHODS[k] for k in names) + " | default / input |")
    out("|---|---|---:|---:|" + "---:|" * len(names) + "---:|")
    for cell in open_cells:
        m, c = cell["measures"], in_place_checks(cell)
        texts = []
        for k in names:
            pull = f"{m[k]['pull_sigma']:+.2f}"
            if k == "default" and not c["pull"][1]:
                pull = f"**{pull}**"
            texts.append(f"{pct(m[k]['border'])} / {pull} / {100 * m[k]['pull']:+.4f}")
        out(
            f"| {cell['mesh']} | {cell['kind']} | {100 * cell['sigma']:g} % | {cell['border_vertices']:,} | "
            + " | ".join(texts)
            + f" | {mark(*c['border'])} |"
        )


IN_PLACE_TARGETS = {  # key -> (what, how the worst is found: the largest value)
    "slide_meshlab": "slide ≤ MeshLab Taubin's",
    "slide_sliding": f"slide ≤ {SLIDE_WITHIN:g} × the sliding default's",
    "surface_sliding": f"surface distance ≤ {SURFACE_WITHIN:g} × the sliding default's",
    "vertex_peers": "vertex distance below every peer default (normal noise)",
    "vertex_best": f"vertex distance ≤ {VERTEX_WITHIN:g} × the best HC setting's by that measure (normal noise)",
    "pull": f"border pull-in ≤ {PULL_WITHIN:g} σ (open meshes)",
    "border": f"border RMS to the clean curve ≤ {BORDER_WITHIN:g} × the input's (open meshes)",
}


def in_place_summary(name, cells, out):
    cells = [c for c in cells if "measures" in c]
    if not cells:
        return
    out(f"\n**{name}, issue 31** (worst: the largest ratio or value, in its cell):\n")
    for key, what in IN_PLACE_TARGETS.items():
        rows = [(c, in_place_checks(c).get(key)) for c in cells]
        counted = [(c, v) for c, v in rows if v is not None and v[1] is not None]
        reported = [(c, v) for c, v in rows if v is not None]
        if not reported:
            continue
        worst_cell, (worst, _) = max(counted or reported, key=lambda r: r[1][0])
        unit = " σ" if key == "pull" else "×"
        text = f"- {what}: "
        if counted:
            met = sum(v[1] for _, v in counted)
            text += f"**{met} of {len(counted)}**"
            missed = [cell_name(c) for c, v in counted if not v[1]]
            if missed:
                text += f" (missed: {', '.join(missed)})"
            text += "; "
        text += f"worst {worst:.2f}{unit} ({cell_name(worst_cell)})"
        iso = [(c, v) for c, v in reported if v[1] is None]
        if iso:
            c, (value, _) = max(iso, key=lambda r: r[1][0])
            median = np.median([v[0] for _, v in iso])
            text += f"; iso (reported only): median {median:.2f}×, worst {value:.2f}× ({cell_name(c)})"
        out(text)
    curves = [c for c in cells if "best_curve" in c and not in_place_checks(c).get("border", (0, True))[1]]
    if curves:
        reach = ", ".join(
            f"{cell_name(c)} {c['best_curve']['border'] / c['measures']['input']['border']:.2f}×" for c in curves
        )
        out(f"- what 1-D smoothing reaches (the best HC on the border curves alone / the input), where missed: {reach}")
    surfaces = [c for c in cells if "best_in_place" in c and not in_place_checks(c)["surface_sliding"][1]]
    if surfaces:
        reach = ", ".join(
            f"{cell_name(c)} {c['best_in_place']['surface'] / c['measures']['sliding']['surface']:.2f}×"
            for c in surfaces
        )
        out(f"- the best HC setting kept in place, surface over the sliding default's, where missed: {reach}")
    slides = [c for c in cells if "input_folded" in c and not in_place_checks(c)["slide_sliding"][1]]
    if slides:
        folded = ", ".join(f"{cell_name(c)} {100 * c['input_folded']:.0f} %" for c in slides)
        out(f"- the input's layout folded by its noise (triangles facing away), where slide ≤ 0.4× missed: {folded}")
    pulls = [c["measures"]["default"]["pull_sigma"] for c in cells if "pull_sigma" in c["measures"]["default"]]
    if pulls:
        out(f"- border pull-in of the default, σ: from {min(pulls):+.2f} to {max(pulls):+.2f}")


def report(record, out):
    cells, scans = record["cells"], record["scanner"]
    for name in inputs.SETS:
        for reference, truth in REFERENCES.items():
            group = [c for c in cells if c["set"] == name and c.get("reference", "scan") == reference]
            if not group:
                continue
            title = f"{name} set" + ("" if reference == "scan" else f", truth: {truth}")
            out(f"\n### {title}: {', '.join(dict.fromkeys(c['mesh'] for c in group))}\n")
            out(
                f"RMS distance of all vertices to the clean surface ({truth} for real scans), % of the "
                "diagonal; **bold**: a target missed in that cell.\n"
            )
            set_table(group, out)
            out("")
            summary(title, group, out)
            measured = [c for c in group if "measures" in c]
            if measured:
                measures_table(measured, out)
                border_table(measured, out)
                in_place_summary(title, measured, out)
    if scans:
        scanner_table(scans, cells, out)


PARAMETERS = (
    Parameter("sets", "tuning,heldout", "tuning and/or heldout"),
    Parameter("meshes", "", "only these meshes (of the sets)"),
    Parameter("kinds", "normal,iso"),
    Parameter("sigmas", SIGMAS, "noise, fractions of the bounding-box diagonal"),
    Parameter("scanner", False, "only the real scans with no noise added"),
    Parameter("no_scanner", False, "skip the real scans with no noise added"),
    Parameter("reference", "scan", f"the real scans' truth: {', '.join(REFERENCES)}"),
    Parameter("seed", 0),
    Parameter("border", quality.BORDER, "the default's open-border rule (core.mesh.borders)"),
    Parameter("sources", "", "report these JSON files' numbers instead (comma-separated)"),
)
QUICK = {"sets": "tuning", "meshes": "cube", "kinds": "iso", "sigmas": "0.0025", "no_scanner": True}


def run(args, out):
    if args.reference not in REFERENCES:
        raise SystemExit(f"--reference {args.reference}: one of {', '.join(REFERENCES)}")
    quality.BORDER = args.border  # the rule bench_quality.hc_default runs the default with
    if args.sources:
        record = {"cells": [], "scanner": []}
        for source in inputs.parse_list(args.sources):
            data = json.loads(pathlib.Path(source).read_text())
            record["cells"] += data["cells"]
            record["scanner"] += data["scanner"]
        report(record, out)
        return record
    out(f"The default's open borders: {quality.BORDER}; {core_version()}.")
    out(f"Load average at start: {' '.join(f'{x:.2f}' for x in os.getloadavg())}.")
    only = set(inputs.parse_list(args.meshes))
    sets = inputs.parse_list(args.sets)
    chosen = [(name, mesh) for name in sets for mesh in inputs.SETS[name] if not only or mesh in only]
    record = {"cells": [], "scanner": []}
    for set_name, mesh in chosen:
        if not args.scanner:
            for kind in inputs.parse_list(args.kinds):
                for sigma in inputs.parse_list(args.sigmas, float):
                    start = time.perf_counter()
                    record["cells"].append(measure_cell(mesh, set_name, kind, sigma, args.seed, args.reference))
                    print(f"  {mesh} {kind} {sigma:g}: {time.perf_counter() - start:.0f} s", file=sys.stderr)
        if not args.no_scanner and args.reference == "scan" and is_scan(mesh):
            record["scanner"].append(measure_scanner(mesh, set_name))
    report(record, out)
    return record
