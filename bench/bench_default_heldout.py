"""Does the Automatic Amount generalise? HC Smooth's default on the meshes it was tuned on and on
real scans it never saw, against the best HC setting of a grid, the fixed HC default and two Taubin
defaults.

Sets (bench_quality_inputs.py): ``tuning`` (the eight meshes of bench_quality.py, the ones the
Automatic Amount was tuned on) and ``heldout`` (real scans, open range scans among them). Noise σ =
0.1 / 0.25 / 0.5 % of the bounding-box diagonal along the clean vertex normals ("normal") or on every
coordinate ("iso"), one seed per cell (as bench_quality.py makes them). Measured: RMS distance of all
vertices (open borders included) to the clean surface, % of the diagonal, of

* the default: ``core.smooth_mesh(noisy, edges, faces=faces, weld=True, border="free")``, as the
  add-on runs it with nothing set;
* the best HC setting of the grid α {0, 0.05, 0.1, 0.2} × β {0.6, 0.75, 0.9} × iterations {1, 2, 3,
  5, 8, 12, 20, 30, 50, 80, 120, 200} (one run per (α, β), read at each count; a run stops once its
  error is past its minimum by a quarter);
* the fixed HC default (α 0.1, β 0.6, 10 iterations);
* trimesh's ``filter_taubin`` and MeshLab's ``apply_coord_taubin_smoothing`` at their defaults
  (λ 0.5, μ −0.5 / −0.53, 10 iterations).

Targets (issue 22, item 8), counted per set: the default within 15 % of the best HC setting; never
more than 5 % worse than the fixed HC default; better than both Taubin defaults in at least 80 % of
the cells.

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
    python bench/bench_default_heldout.py --from a.json b.json                # the report of earlier runs

The report goes to stdout and bench/results/; the numbers (grids included) to a JSON file beside it,
which ``--from`` reads back (runs split by mesh or σ give one report).
"""

import argparse
import json
import os
import pathlib
import sys
import time
import zlib

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "bench")]
import bench_quality as quality  # noqa: E402
import bench_quality_inputs as inputs  # noqa: E402
import meshes  # noqa: E402
from report import Report  # noqa: E402

import core  # noqa: E402

SIGMAS = "0.001,0.0025,0.005"
ALPHAS = (0.0, 0.05, 0.1, 0.2)
BETAS = (0.6, 0.75, 0.9)
CHECKPOINTS = (1, 2, 3, 5, 8, 12, 20, 30, 50, 80, 120, 200)
FIXED = {"alpha": 0.1, "beta": 0.6, "iterations": 10}
TRIMESH_TAUBIN = {"lamb": 0.5, "nu": 0.5, "iterations": 10}  # filter_taubin's defaults
BEST_WITHIN = 1.15  # the default's error at most this times the best HC setting's ...
FIXED_WITHIN = 1.05  # ... and this times the fixed HC default's, in every cell ...
TAUBIN_SHARE = 0.8  # ... and below both Taubin defaults in this share of the cells
LIGHT = 0.001  # the lightest noise added, the scale scanner noise is compared with
REFERENCES = {
    "scan": "the scan as it is",
    "default": "the scan smoothed by HC Smooth's default",
    "two-step": "the scan smoothed by MeshLab's two-step smoothing",
}


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


def hc_grid(case, border="free"):
    """RMS at every (alpha, beta, checkpoint) of the grid (NaN past a path's end), under the open-border
    rule ``border``. Returns (grid, best {params, rms})."""
    grid = quality.walk_grid(case, ALPHAS, BETAS, CHECKPOINTS, border=border)
    ia, ib, ic = np.unravel_index(np.nanargmin(grid), grid.shape)
    params = {"alpha": ALPHAS[ia], "beta": BETAS[ib], "iterations": CHECKPOINTS[ic]}
    return grid, {"params": params, "rms": float(grid[ia, ib, ic])}


def meshlab_taubin(case):
    return quality._meshlab(case, "apply_coord_taubin_smoothing")


def border_share(faces, count):
    """The share of the vertices on an open border (an edge of one face)."""
    pairs = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    unique, counts = np.unique(pairs, axis=0, return_counts=True)
    return np.unique(unique[counts == 1]).size / count


def measure_cell(mesh, set_name, kind, sigma, seed, reference="scan"):
    case = make_case(mesh, kind, sigma, seed, reference)
    start = time.perf_counter()
    ours, chosen = quality.hc_default(case)
    cell = {
        "set": set_name,
        "reference": reference,
        "mesh": mesh,
        "kind": kind,
        "sigma": sigma,
        "vertices": len(case.noisy),
        "closed": case.closed,
        "border": border_share(case.faces, len(case.noisy)),
        "input": case.rms(case.noisy),
        "default": {**chosen, "rms": case.rms(ours), "seconds": time.perf_counter() - start},
        "fixed": case.rms(quality.hc_fixed(case, FIXED)),
        "trimesh_taubin": case.rms(quality.trimesh_taubin(case, TRIMESH_TAUBIN)),
        "meshlab_taubin": case.rms(meshlab_taubin(case)),
    }
    grid, best = hc_grid(case)
    cell["best"] = best
    if quality.BORDER != "free" and cell["border"] > 0:  # the best HC setting that keeps borders as ours does
        cell["best_same_border"] = hc_grid(case, quality.BORDER)[1]
    cell["grid"] = {"alphas": ALPHAS, "betas": BETAS, "iterations": CHECKPOINTS, "rms": grid.tolist()}
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
        text += f", {params['held_parts']} parts held"  # the default would have collapsed them (core.collapse)
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
    if scans:
        scanner_table(scans, cells, out)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sets", default="tuning,heldout", help="tuning and/or heldout")
    parser.add_argument("--meshes", default="", help="only these meshes (of the sets)")
    parser.add_argument("--kinds", default="normal,iso")
    parser.add_argument("--sigmas", default=SIGMAS, help="noise, fractions of the bounding-box diagonal")
    parser.add_argument("--scanner", action="store_true", help="only the real scans with no noise added")
    parser.add_argument("--no-scanner", action="store_true", help="skip the real scans with no noise added")
    parser.add_argument("--reference", default="scan", choices=tuple(REFERENCES), help="the real scans' truth")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--border", default=quality.BORDER, help="the default's open-border rule (core.borders)")
    parser.add_argument("--from", dest="sources", nargs="+", default=[], help="report these JSON files' numbers")
    args = parser.parse_args()
    quality.BORDER = args.border
    with Report("bench_default_heldout") as out:
        out(f"`{' '.join(['bench/bench_default_heldout.py'] + sys.argv[1:])}`, {time.strftime('%Y-%m-%d %H:%M')}\n")
        if args.sources:
            record = {"cells": [], "scanner": []}
            for source in args.sources:
                data = json.loads(pathlib.Path(source).read_text())
                record["cells"] += data["cells"]
                record["scanner"] += data["scanner"]
            report(record, out)
            return
        out(f"The default's open borders: {quality.BORDER}.")
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
        out.sibling(".json").write_text(json.dumps(record))
        report(record, out)


if __name__ == "__main__":
    main()
