"""Mesh smoothing quality on real scans: HC Smooth's default result against other smoothers' defaults,
their small grids of settings, and the best result any HC setting reaches on the same input.

Inputs (bench_quality_inputs.py): the sample meshes of the pymeshlab wheel (bunny, cow, bone,
airplane), Blender's Suzanne subdivided twice (open), a cube, a thin plate and a thin torus; Gaussian
noise of σ = 0.1 / 0.2 / 0.4 / 1 % of the bounding-box diagonal, along the clean vertex normals
("normal") and on every coordinate ("iso"), one seed per cell.

Measured per result: RMS and max distance of the vertices to the clean surface (% of the diagonal),
volume change against the noisy input (closed meshes: the smoother's own change; the JSON also has it
against the clean mesh), wall time of the smoothing call (median of
--repeats for the rows at defaults, one run for grid rows).

    python bench/run.py quality                                  # every mesh, noise kind and σ; peers in Python
    python bench/run.py quality --blender                        # with Blender's Smooth / Laplacian Smooth modifiers
    python bench/run.py quality --meshes bunny,cow --kinds normal --sigmas 0.004
    python bench/run.py quality --no-grid                        # skip the HC parameter grid (faster)
    python bench/run.py quality --hc 0.05,0.6,20                 # an extra fixed HC setting (alpha,beta,iterations)
    python bench/run.py quality --plot docs/images/error_vs_iterations.png   # error vs iterations, one scan

The report (markdown) goes to stdout and bench/results/; the raw numbers, HC grid included, to a JSON
file beside it.
"""

import json
import pathlib
import statistics
import subprocess
import tempfile
import time
import warnings
import zlib
from dataclasses import dataclass, field

import numpy as np

import core
import settings_spec
from bench import bench_quality_inputs as inputs
from bench import meshes
from bench.common import ROOT, Parameter, repeats

SIGMAS = "0.001,0.002,0.004,0.01"
HC_ALPHAS = (0.0, 0.01, 0.03, 0.1, 0.3)
HC_BETAS = (0.5, 0.6, 0.75, 0.9)
HC_CHECKPOINTS = (1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 40, 50, 60, 80, 100, 130, 160, 200)
GRID_SUBSET = 3000  # vertices the grid's RMS is measured on; the best candidates are re-measured on all
GRID_GIVE_UP = 1.25  # a path of the grid stops once its error rises above this times its minimum so far


# --- one input ----------------------------------------------------------------------------------------


@dataclass
class Case:
    mesh: str
    kind: str
    sigma: float  # fraction of the diagonal
    clean: np.ndarray
    faces: np.ndarray
    noisy: np.ndarray
    edges: np.ndarray = field(init=False)
    diagonal: float = field(init=False)
    closed: bool = field(init=False)

    def __post_init__(self):
        self.edges = meshes.edges_from_faces(self.faces)
        self.diagonal = inputs.diagonal(self.clean)
        self.closed = inputs.is_closed(self.faces)
        self.surface = inputs.Surface(self.clean, self.faces)
        self.volume = inputs.signed_volume(self.clean, self.faces) if self.closed else None
        self.noisy_volume = inputs.signed_volume(self.noisy, self.faces) if self.closed else None

    @property
    def key(self):
        return f"{self.mesh}/{self.kind}/{self.sigma:g}"

    def rms(self, positions, rows=None):
        points = positions if rows is None else positions[rows]
        return float(np.sqrt(np.mean(self.surface.distance(points) ** 2)) / self.diagonal)

    def measure(self, positions):
        distance = self.surface.distance(positions) / self.diagonal
        volume = inputs.signed_volume(positions, self.faces) if self.closed else None
        return {
            "rms": float(np.sqrt(np.mean(distance**2))),
            "max": float(distance.max()),
            "dv": volume / self.volume - 1.0 if self.closed else None,
            "dv_input": volume / self.noisy_volume - 1.0 if self.closed else None,
        }


def make_case(mesh, kind, sigma, seed):
    clean, faces = inputs.load_mesh(mesh)
    normals = inputs.vertex_normals(clean, faces)
    cell_seed = zlib.crc32(f"{mesh}/{kind}/{sigma:g}".encode()) ^ seed
    noisy = inputs.add_noise(clean, normals, sigma * inputs.diagonal(clean), kind, cell_seed)
    return Case(mesh, kind, sigma, clean, faces, noisy)


# --- HC Smooth ----------------------------------------------------------------------------------------


def quiet(function, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)
        return function(*args, **kwargs)


def hc_default_settings():
    """HC Smooth's mesh defaults, as the operator, the scene settings and the command line get them."""
    return {
        "alpha": settings_spec.ALPHA.default,
        "beta": settings_spec.BETA.default,
        "iterations": settings_spec.ITERATIONS.default,
    }


BORDER = "free"  # the open-border rule hc_default runs with (core.mesh.borders)


def hc_default(case, **options):
    """HC Smooth's default result: what the operator and the command line give with nothing changed
    (core.smooth_mesh, the pipeline they all run, with the options the add-on passes: split vertices
    welded). ``options`` go to core.smooth_mesh as well (``keep_in_place=False``: the default that lets
    vertices slide along the surface)."""
    result, report = core.smooth_mesh(
        case.noisy, case.edges, faces=case.faces, weld=True, border=BORDER, return_report=True, **options
    )
    settings = {"alpha": report.alpha, "beta": report.beta, "iterations": report.iterations}
    if report.amount is not None:
        settings.update(noise=report.amount.sigma / case.diagonal, noise_over_edge=report.amount.ratio)
    if report.held_parts:
        settings.update(held_parts=report.held_parts)
    return result, settings


def _amount_label(params):
    """'12 it.', or with the gentler steps the Automatic Amount takes on light noise '4 it., beta 0.75'."""
    gentler = params["beta"] != hc_default_settings()["beta"]
    return f"{params['iterations']} it." + (f", beta {params['beta']:g}" if gentler else "")


def hc_fixed(case, params):
    return quiet(
        core.hc_smooth,
        case.noisy,
        case.edges,
        alpha=params["alpha"],
        beta=params["beta"],
        iterations=params["iterations"],
    )


def walk_grid(case, alphas, betas, checkpoints, rows=None, border="free", measures=None):
    """RMS of HC (on ``rows``, all vertices if None) at every (alpha, beta, checkpoint), NaN past the end
    of a path: each path runs once, read at its checkpoints, and stops past its minimum. ``border``: the
    open-border rule of the runs (core.mesh.borders; "free" is the paper's algorithm). ``measures``: {name:
    function of the positions (all vertices) -> float}, read at the same checkpoints; then a path stops
    once every measure is past its minimum, and the return is (grid, {name: grid of that measure})."""
    operator = core.umbrella_operator(case.edges, len(case.noisy))
    held = np.zeros(len(case.noisy), dtype=bool)
    operator, held = core.mesh.borders.apply_border(border, operator, case.faces, held)
    shape = (len(alphas), len(betas), len(checkpoints))
    grid = np.full(shape, np.nan)
    extra = {name: np.full(shape, np.nan) for name in measures or {}}
    for ia, alpha in enumerate(alphas):
        for ib, beta in enumerate(betas):
            run = quiet(
                core.Smoothing,
                case.noisy,
                None,
                method="hc",
                alpha=alpha,
                beta=beta,
                iterations=checkpoints[-1],
                operator=operator,
                fixed=held,
            )
            done = 0
            for ic, checkpoint in enumerate(checkpoints):
                try:
                    run.advance(checkpoint - done)
                except core.DivergenceError:
                    break
                done = checkpoint
                positions = run.result().positions
                grid[ia, ib, ic] = case.rms(positions, rows)
                for name, function in (measures or {}).items():
                    extra[name][ia, ib, ic] = function(positions)
                paths = [grid[ia, ib, : ic + 1]] + [values[ia, ib, : ic + 1] for values in extra.values()]
                if ic >= 3 and all(p[-1] > GRID_GIVE_UP * p.min() and p[-1] > p[-2] for p in paths):
                    break  # past every path's minimum: the errors only grow from here
    return (grid, extra) if measures else grid


def hc_grid(case, seed):
    """RMS of HC at every (alpha, beta, checkpoint) of the grid on a vertex subset, then the best few
    re-measured on all vertices. Returns (grid (a, b, c) array, best {params, rms, max, dv})."""
    n = len(case.noisy)
    rows = np.sort(np.random.default_rng(seed).choice(n, min(n, GRID_SUBSET), replace=False))
    grid = walk_grid(case, HC_ALPHAS, HC_BETAS, HC_CHECKPOINTS, rows)
    order = np.argsort(np.nan_to_num(grid, nan=np.inf), axis=None)[:6]
    best = None
    for flat in order:
        ia, ib, ic = np.unravel_index(flat, grid.shape)
        params = {"alpha": HC_ALPHAS[ia], "beta": HC_BETAS[ib], "iterations": HC_CHECKPOINTS[ic]}
        measured = case.measure(hc_fixed(case, params))
        if best is None or measured["rms"] < best["rms"]:
            best = {"params": params, **measured}
    return grid, best


# --- peers --------------------------------------------------------------------------------------------


def _trimesh(case):
    import trimesh

    return trimesh.Trimesh(case.noisy.copy(), case.faces, process=False, validate=False)


def trimesh_taubin(case, p):
    import trimesh

    mesh = _trimesh(case)
    trimesh.smoothing.filter_taubin(mesh, lamb=p["lamb"], nu=p["nu"], iterations=p["iterations"])
    return np.asarray(mesh.vertices)


def trimesh_laplacian(case, p):
    import trimesh

    mesh = _trimesh(case)
    trimesh.smoothing.filter_laplacian(mesh, lamb=p["lamb"], iterations=p["iterations"], volume_constraint=True)
    return np.asarray(mesh.vertices)


def _open3d(case):
    import open3d as o3d

    return o3d.geometry.TriangleMesh(
        o3d.utility.Vector3dVector(case.noisy), o3d.utility.Vector3iVector(case.faces.astype(np.int32))
    )


def open3d_taubin(case, p):
    return np.asarray(_open3d(case).filter_smooth_taubin(number_of_iterations=p["iterations"]).vertices)


def open3d_laplacian(case, p):
    return np.asarray(_open3d(case).filter_smooth_laplacian(number_of_iterations=p["iterations"]).vertices)


def _meshlab(case, filter_name, calls=1, **params):
    import pymeshlab

    meshset = pymeshlab.MeshSet()
    meshset.add_mesh(pymeshlab.Mesh(vertex_matrix=case.noisy, face_matrix=case.faces.astype(np.int32)))
    for _ in range(calls):
        meshset.apply_filter(filter_name, **params)
    out = meshset.current_mesh().vertex_matrix()
    if out.shape != case.noisy.shape:
        raise RuntimeError(f"MeshLab changed the vertex count ({len(case.noisy)} -> {len(out)})")
    return out.copy()


def meshlab_two_step(case, p):
    return _meshlab(case, "apply_coord_two_steps_smoothing", stepsmoothnum=p["steps"])


def meshlab_hc(case, p):
    return _meshlab(case, "apply_coord_hc_laplacian_smoothing", calls=p["calls"])


def laplacian_plain(case, p):
    return core.laplacian_smooth(case.noisy, case.edges, variant="plain", iterations=p["iterations"])


@dataclass
class Peer:
    name: str
    default: dict
    grid: list
    run: object = None  # (case, params) -> positions; None: a Blender modifier
    modifier: str = None
    needs: str = None  # the module it imports

    def settings(self):
        seen, out = set(), []
        for params in [self.default] + self.grid:
            key = json.dumps(params, sort_keys=True)
            if key not in seen:
                seen.add(key)
                out.append(params)
        return out


def label(params):
    return ", ".join(
        f"{k} {v:g}" if isinstance(v, (int, float)) and not isinstance(v, bool) else f"{k} {v}"
        for k, v in params.items()
    )


PEERS = [
    Peer(
        "Laplacian (HC Smooth, 10 it.)",
        {"iterations": settings_spec.ITERATIONS.default},
        [{"iterations": k} for k in (1, 2, 3, 5, 20)],
        laplacian_plain,
    ),
    Peer(
        "trimesh Laplacian (vol.)",
        {"lamb": 0.5, "iterations": 10},
        [{"lamb": 0.5, "iterations": k} for k in (1, 3, 30)],
        trimesh_laplacian,
        needs="trimesh",
    ),
    Peer(
        "trimesh Taubin",
        {"lamb": 0.5, "nu": 0.5, "iterations": 10},
        [{"lamb": 0.5, "nu": 0.5, "iterations": k} for k in (3, 30, 100, 300)],
        trimesh_taubin,
        needs="trimesh",
    ),
    Peer(
        "Open3D Laplacian",
        {"iterations": 1},
        [{"iterations": k} for k in (3, 10, 30)],
        open3d_laplacian,
        needs="open3d",
    ),
    Peer(
        "Open3D Taubin",
        {"iterations": 1},
        [{"iterations": k} for k in (3, 10, 30, 100, 300)],
        open3d_taubin,
        needs="open3d",
    ),
    Peer("MeshLab two-step", {"steps": 3}, [{"steps": k} for k in (1, 10, 30)], meshlab_two_step, needs="pymeshlab"),
    Peer("MeshLab HC", {"calls": 1}, [{"calls": k} for k in (3, 10, 30)], meshlab_hc, needs="pymeshlab"),
    Peer(
        "Blender Smooth",
        {},
        [{"factor": f, "iterations": k} for f in (0.5, 1.0) for k in (1, 3, 10, 30) if (f, k) != (0.5, 1)],
        modifier="SMOOTH",
    ),
    Peer(
        "Blender Laplacian Smooth",
        {},
        [{"lambda_factor": f, "iterations": k} for f in (0.1, 1.0) for k in (1, 10)] + [{"iterations": 10}],
        modifier="LAPLACIANSMOOTH",
    ),
]


def available(peer):
    if peer.needs is None:
        return True
    try:
        __import__(peer.needs)
        return True
    except ImportError:
        return False


def timed(function, *args, repeats=1):
    times, out = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        out = function(*args)
        times.append(time.perf_counter() - start)
    return out, statistics.median(times)


def run_blender(cases, peers, repeats, out):
    """Every Blender peer setting on every case, in one bpy45 process. Returns {(case key, peer, json params):
    (positions, seconds)}."""
    python = inputs.BPY45
    if not python.exists():
        out(f"Blender peers skipped: {python} is missing\n")
        return {}
    jobs, index = {}, []
    for case in cases:
        for peer in peers:
            for params in peer.settings():
                i = len(index)
                jobs.update(
                    {
                        f"vertices_{i}": case.noisy,
                        f"faces_{i}": case.faces,
                        f"modifier_{i}": peer.modifier,
                        f"settings_{i}": json.dumps(params),
                        f"repeats_{i}": repeats if params == peer.default else 1,
                    }
                )
                index.append((case.key, peer.name, json.dumps(params, sort_keys=True)))
    with tempfile.TemporaryDirectory() as folder:
        job_file, result_file = pathlib.Path(folder, "jobs.npz"), pathlib.Path(folder, "results.npz")
        np.savez(job_file, count=len(index), **jobs)
        subprocess.run(
            [str(python), "-m", "bench.bench_quality_blender", str(job_file), str(result_file)],
            cwd=ROOT,  # `-m` finds bench/ there
            check=True,
            timeout=3600,
        )
        results = np.load(result_file)
        return {key: (results[f"positions_{i}"], float(results[f"seconds_{i}"])) for i, key in enumerate(index)}


# --- report -------------------------------------------------------------------------------------------


def pct(value, digits=3):
    return "–" if value is None else f"{100 * value:.{digits}f}"


def signed_pct(value):
    return "–" if value is None else f"{100 * value:+.2f}"


def quality(args, out, record):
    cases = [
        make_case(m, k, s, args.seed)
        for m in inputs.parse_list(args.meshes)
        for k in inputs.parse_list(args.kinds)
        for s in inputs.parse_list(args.sigmas, float)
    ]
    peers = [p for p in PEERS if (p.modifier is None or args.blender) and available(p)]
    if args.no_peers:
        peers = []
    missing = [p.name for p in PEERS if p.modifier is None and not available(p)]
    blender = run_blender(cases, [p for p in peers if p.modifier], args.repeats, out) if args.blender else {}
    peers = [p for p in peers if p.modifier is None or blender]
    extra = None
    if args.hc:
        a, b, k = args.hc.split(",")
        extra = {"alpha": float(a), "beta": float(b), "iterations": int(k)}

    out("## Mesh smoothing quality on real scans\n")
    out(
        f"Load average at start: {' '.join(f'{x:.2f}' for x in __import__('os').getloadavg())}. "
        + (f"Not installed: {', '.join(missing)}. " if missing else "")
        + ("" if args.blender else "Blender's modifiers not run (add --blender). ")
    )
    out("RMS distance to the clean surface, % of the bounding-box diagonal (lower is better).\n")
    columns = ["HC Smooth default", "best HC"] + [p.name for p in peers] + (["HC " + label(extra)] if extra else [])
    out("| mesh | noise | σ | input | " + " | ".join(columns) + " | default / best HC | best peer default |")
    out("|---" * (len(columns) + 6) + "|")
    volume_rows, peer_best_rows, time_rows = [], [], []
    for case in cases:
        cell = {
            "mesh": case.mesh,
            "kind": case.kind,
            "sigma": case.sigma,
            "vertices": len(case.noisy),
            "closed": case.closed,
            "edge_over_diagonal": inputs.mean_edge_length(case.clean, case.faces) / case.diagonal,
            "input": case.measure(case.noisy),
            "methods": {},
        }
        (ours, chosen), seconds = timed(hc_default, case, repeats=args.repeats)
        cell["methods"]["HC Smooth default"] = {"params": chosen, **case.measure(ours), "seconds": seconds}
        if not args.no_grid:
            grid, best = hc_grid(case, zlib.crc32(case.key.encode()))
            cell["hc_grid"] = {
                "alphas": HC_ALPHAS,
                "betas": HC_BETAS,
                "iterations": HC_CHECKPOINTS,
                "rms_on_subset": grid.tolist(),
            }
            cell["methods"]["best HC"] = best
        if extra:
            result, seconds = timed(hc_fixed, case, extra)
            cell["methods"]["HC " + label(extra)] = {"params": extra, **case.measure(result), "seconds": seconds}
        for peer in peers:
            runs = []
            for params in peer.settings():
                is_default = params == peer.default
                try:
                    if peer.modifier:
                        result, seconds = blender[(case.key, peer.name, json.dumps(params, sort_keys=True))]
                    else:
                        result, seconds = timed(peer.run, case, params, repeats=args.repeats if is_default else 1)
                    measured = case.measure(result)
                except Exception as error:  # a peer failing is a result too
                    measured, seconds = (
                        {"rms": None, "max": None, "dv": None, "error": f"{type(error).__name__}: {error}"},
                        None,
                    )
                runs.append({"params": params, "default": is_default, **measured, "seconds": seconds})
            cell["methods"][peer.name] = runs[0]
            cell.setdefault("peer_grids", {})[peer.name] = runs
        record.append(cell)

        m = cell["methods"]
        ours_rms = m["HC Smooth default"]["rms"]
        best = m.get("best HC")
        peer_defaults = {p.name: m[p.name]["rms"] for p in peers if m[p.name]["rms"] is not None}
        best_peer = min(peer_defaults, key=peer_defaults.get) if peer_defaults else None
        chosen = m["HC Smooth default"]["params"]
        cells = [
            pct(ours_rms) + (f" ({_amount_label(chosen)})" if "noise" in chosen else ""),
            f"{pct(best['rms'])} ({label(best['params'])})" if best else "–",
        ]
        cells += [pct(m[p.name]["rms"]) for p in peers]
        if extra:
            cells.append(pct(m["HC " + label(extra)]["rms"]))
        ratio = f"{ours_rms / best['rms']:.2f}" if best else "–"
        verdict = "–"
        if best_peer:
            won = ours_rms < peer_defaults[best_peer]
            verdict = f"{'won' if won else '**LOST**'} ({best_peer} {pct(peer_defaults[best_peer])})"
        out(
            f"| {case.mesh} | {case.kind} | {case.sigma:.1%} | {pct(cell['input']['rms'])} | "
            + " | ".join(cells)
            + f" | {ratio} | {verdict} |"
        )
        volume_rows.append(
            (
                case,
                [m[c]["dv_input"] if c in m and m[c].get("dv_input") is not None else None for c in columns],
                [m[c]["max"] if c in m and m[c].get("max") is not None else None for c in columns],
            )
        )
        peer_best_rows.append((case, cell))
        time_rows.append((case, [m[c].get("seconds") if c in m else None for c in columns]))

    out(
        "\nVolume change against the noisy input, % (closed meshes; Suzanne is open): the smoother's own change. "
        "The noisy input's volume differs from the clean mesh's by chance (column 'input', against the clean "
        "mesh: up to ±2 % on the small meshes at σ 1 %):\n"
    )
    out("| mesh | noise | σ | input | " + " | ".join(columns) + " |")
    out("|---" * (len(columns) + 4) + "|")
    for (case, volumes, _), cell in zip(volume_rows, record[-len(volume_rows) :]):
        if case.closed:
            out(
                f"| {case.mesh} | {case.kind} | {case.sigma:.1%} | {signed_pct(cell['input']['dv'])} | "
                + " | ".join(signed_pct(v) for v in volumes)
                + " |"
            )
    out("\nMax distance to the clean surface, % of the diagonal:\n")
    out("| mesh | noise | σ | input | " + " | ".join(columns) + " |")
    out("|---" * (len(columns) + 4) + "|")
    for (case, _, maxima), cell in zip(volume_rows, record[-len(volume_rows) :]):
        out(
            f"| {case.mesh} | {case.kind} | {case.sigma:.1%} | {pct(cell['input']['max'], 2)} | "
            + " | ".join(pct(v, 2) for v in maxima)
            + " |"
        )
    if peers:
        out("\nPeers at the best setting of their grid (RMS, setting; the grids are in the JSON file):\n")
        out("| mesh | noise | σ | " + " | ".join(p.name for p in peers) + " |")
        out("|---" * (len(peers) + 3) + "|")
        for case, cell in peer_best_rows:
            texts = []
            for peer in peers:
                runs = [r for r in cell["peer_grids"][peer.name] if r["rms"] is not None]
                best_run = min(runs, key=lambda r: r["rms"]) if runs else None
                texts.append(
                    f"{pct(best_run['rms'])} ({label(best_run['params']) or 'defaults'})" if best_run else "failed"
                )
            out(f"| {case.mesh} | {case.kind} | {case.sigma:.1%} | " + " | ".join(texts) + " |")
    out(f"\nTime of the smoothing call, s (median of {args.repeats} at defaults; best HC: not timed):\n")
    out("| mesh | vertices | noise | σ | " + " | ".join(columns) + " |")
    out("|---" * (len(columns) + 4) + "|")
    for case, seconds in time_rows:
        out(
            f"| {case.mesh} | {len(case.noisy)} | {case.kind} | {case.sigma:.1%} | "
            + " | ".join("–" if s is None else f"{s:.3f}" for s in seconds)
            + " |"
        )
    if not args.no_grid and record:
        ratios = [c["methods"]["HC Smooth default"]["rms"] / c["methods"]["best HC"]["rms"] for c in record]
        out(
            f"\nHC Smooth default / best HC: median {np.median(ratios):.2f}, worst {max(ratios):.2f} "
            f"({sum(r <= 1.1 for r in ratios)} of {len(ratios)} cells within 10 %)."
        )
    if peers and record:
        lost = [
            c
            for c in record
            if any(
                r["rms"] is not None and r["default"] and r["rms"] <= c["methods"]["HC Smooth default"]["rms"]
                for runs in c["peer_grids"].values()
                for r in runs
            )
        ]
        out(f"Cells where a peer's default beat HC Smooth's default: {len(lost)} of {len(record)}.")
    dvs = [
        (abs(c["methods"]["HC Smooth default"]["dv"]), abs(c["methods"]["HC Smooth default"]["dv_input"]))
        for c in record
        if c["closed"]
    ]
    if dvs:
        out(
            f"Largest |ΔV| of HC Smooth's default on closed meshes: {100 * max(d[1] for d in dvs):.2f} % against "
            f"the noisy input ({sum(d[1] <= 0.005 for d in dvs)} of {len(dvs)} cells within 0.5 %), "
            f"{100 * max(d[0] for d in dvs):.2f} % against the clean mesh."
        )


# --- error versus iterations --------------------------------------------------------------------------


def plot(args, out):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    mesh, kind, sigma = args.plot_case.split("/")
    case = make_case(mesh, kind, float(sigma), args.seed)
    steps = np.unique(np.round(np.geomspace(1, args.plot_iterations, 40)).astype(int))
    defaults = hc_default_settings()
    curves = {}

    def follow(name, method, **params):
        run = quiet(core.Smoothing, case.noisy, case.edges, method=method, iterations=int(steps[-1]), **params)
        done, values = 0, []
        for k in steps:
            run.advance(int(k) - done)
            done = int(k)
            values.append(case.rms(run.result().positions))
        curves[name] = (steps, np.array(values))

    follow(
        f"HC (α {defaults['alpha']:g}, β {defaults['beta']:g}: the fixed amount)",
        "hc",
        alpha=defaults["alpha"],
        beta=defaults["beta"],
    )
    follow(f"HC (α 0, β {defaults['beta']:g}: the Automatic Amount's path)", "hc", alpha=0.0, beta=defaults["beta"])
    chosen, report = core.smooth_mesh(case.noisy, case.edges, faces=case.faces, return_report=True)
    follow("Laplacian (paper 3.1)", "plain")
    try:  # trimesh counts the λ and the μ pass as one iteration each: a pair costs what an HC iteration does
        values = [case.rms(trimesh_taubin(case, {"lamb": 0.5, "nu": 0.5, "iterations": 2 * int(k)})) for k in steps]
        curves["Taubin (trimesh, λ 0.5, μ −0.5; λ|μ pairs)"] = (steps, np.array(values))
    except ImportError:
        out("trimesh is not installed: no Taubin curve")
    figure, axes = plt.subplots(figsize=(8, 5.6), dpi=130)
    styles = [("#7f8c8d", "-"), ("#c0392b", "-"), ("#2c3e50", "--"), ("#2980b9", "-.")]  # in the order followed
    for (name, (x, y)), (colour, line) in zip(curves.items(), styles):
        axes.plot(x, 100 * y, line, color=colour, lw=2, label=name)
    axes.plot(
        [report.iterations],
        [100 * case.rms(chosen)],
        "o",
        color="#c0392b",
        ms=9,
        mfc="white",
        mew=2,
        label=f"HC Smooth's default: {report.iterations} iterations chosen, volume kept",
    )
    axes.axhline(100 * case.rms(case.noisy), color="grey", lw=1, ls=":", label="noisy input")
    axes.set_xscale("log")
    axes.set_yscale("log")
    ticks = [
        t
        for t in (0.05, 0.07, 0.1, 0.15, 0.2, 0.3, 0.5, 0.7, 1, 1.5, 2, 3, 5)
        if 0.8 * min(100 * y.min() for _, y in curves.values())
        <= t
        <= 1.2 * max(100 * y.max() for _, y in curves.values())
    ]
    axes.set_yticks(ticks, [f"{t:g}" for t in ticks])
    axes.set_xticks([1, 2, 5, 10, 20, 50, 100, 200], ["1", "2", "5", "10", "20", "50", "100", "200"])
    axes.minorticks_off()
    axes.set_xlabel("iterations")
    axes.set_ylabel("RMS distance to the clean scan (% of the diagonal)")
    axes.set_title(
        f"{case.mesh} ({len(case.noisy):,} vertices), noise σ = {case.sigma:.1%} of the diagonal "
        f"{'along the normals' if case.kind == 'normal' else 'per coordinate'}",
        fontsize=10,
    )
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize=9, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, frameon=False)
    figure.tight_layout()
    path = ROOT / args.plot if not pathlib.Path(args.plot).is_absolute() else pathlib.Path(args.plot)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path)
    out("| iterations | " + " | ".join(curves) + " |")
    out("|---" * (len(curves) + 1) + "|")
    for i, k in enumerate(steps):
        out(f"| {k} | " + " | ".join(pct(y[i]) for _, y in curves.values()) + " |")
    out(
        f"\nHC Smooth's default (Automatic Amount): {report.iterations} iterations (noise estimate "
        f"{report.amount.sigma / case.diagonal:.3%} of the diagonal), RMS {pct(case.rms(chosen))} %"
    )
    out(f"\nwritten {path}")


PARAMETERS = (
    Parameter("meshes", ",".join(inputs.ALL_MESHES)),
    Parameter("kinds", "normal,iso", "noise along the normals and/or isotropic"),
    Parameter("sigmas", SIGMAS, "noise, fractions of the bounding-box diagonal"),
    Parameter("blender", False, "also run Blender's modifiers (in .envs/bpy45)"),
    Parameter("no_grid", False, "skip the HC parameter grid"),
    Parameter("no_peers", False),
    Parameter("hc", "", "an extra HC setting alpha,beta,iterations"),
    repeats(3, "timing runs at defaults (median)"),
    Parameter("seed", 0),
    Parameter("plot", "", "write the error-vs-iterations figure here instead"),
    Parameter("plot_case", "bunny/normal/0.004", "mesh/kind/sigma of the figure"),
    Parameter("plot_iterations", 300),
)
QUICK = {"meshes": "cube", "kinds": "iso", "sigmas": "0.004", "no_grid": True, "repeats": 1}


def run(args, out):
    record = []
    if args.plot:
        plot(args, out)
    else:
        quality(args, out, record)
    return record
