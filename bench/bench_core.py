"""Speed, exactness and memory of core.hc_smooth against its peers.

    python bench/run.py core [--sizes 100k,1M] [--repeats N] [--quick] [--shuffle] [--amount]

On a noisy closed torus (sigma = 1 % of the bounding-box diagonal, fixed seed) it times 10 HC
iterations with the operator built inside every run (both modes, float32 and float64), trimesh's
filter_humphrey, PyMeshLab's HC (10 calls) and Open3D's Laplacian and Taubin filters, in the same
run; prints medians, speed-ups against filter_humphrey and the volume change of each result. Then it
checks the float64 result against an independent sparse-matrix form of Algorithm 1, the
sequential/simultaneous time ratio and the peak extra memory per vertex. Peers that are not installed
are reported as such. ``--amount`` times the mesh Automatic Amount instead (whole mesh vs patches).
"""

import ctypes
import gc
import os
import platform
import statistics
import time
import tracemalloc
import warnings
from importlib import metadata

import numpy as np
import scipy
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve_triangular

import core
from bench import meshes
from bench.common import Parameter, repeats, sizes

RATIO, MINOR = 2.5, 0.4  # torus shape (R = RATIO * MINOR)
TARGET_SPEEDUP = 3.0  # HC simultaneous vs filter_humphrey at 1M vertices
TARGET_SEQUENTIAL = 1.5  # sequential time / simultaneous time
TARGET_BYTES = 250.0  # peak extra memory per vertex
TARGET_AGREEMENT = 1e-9  # max deviation / bbox diagonal, float64


# --- Reference: Algorithm 1 in matrix form (paper section 5), written independently of core/ --------


def reference_operator(edges, n):
    """T with t_ij = 1/|adj(i)| from scipy.sparse's own COO -> CSR (duplicates summed, then set to 1)."""
    i, j = np.concatenate([edges[:, 0], edges[:, 1]]), np.concatenate([edges[:, 1], edges[:, 0]])
    adjacency = sp.coo_matrix((np.ones(i.size), (i, j)), shape=(n, n)).tocsr()
    adjacency.setdiag(0)
    adjacency.eliminate_zeros()
    adjacency.data[:] = 1.0
    degree = np.asarray(adjacency.sum(axis=1)).ravel()
    return sp.diags(1.0 / degree) @ adjacency


def reference_hc(original, edges, alpha, beta, iterations, mode):
    """x <- Tx - (βE + (1-β)T)(Tx - (αo + (1-α)x)); sequential: (E - L) p = U q for the Laplacian pass.

    Every vertex of the benchmark meshes has neighbours and none is fixed, so V_var is everything.
    """
    o = original.astype(np.float64)
    t = reference_operator(edges, o.shape[0])
    if mode == "sequential":
        lower = (sp.identity(o.shape[0], format="csr") - sp.tril(t, k=-1)).tocsr()
        upper = sp.triu(t, k=1).tocsr()
    x = o.copy()
    for _ in range(iterations):
        p = t @ x if mode == "simultaneous" else spsolve_triangular(lower, upper @ x, lower=True)
        b = p - (alpha * o + (1.0 - alpha) * x)
        x = p - (beta * b + (1.0 - beta) * (t @ b))
    return x


# --- Peers: each takes (vertices, faces) and returns the smoothed vertices; build cost included ------


def peer_methods(alpha, beta, iterations):
    """{name: (description, run)} for every peer that imports, else {name: (reason, None)}."""
    found = {}
    try:
        import trimesh
        from trimesh.smoothing import filter_humphrey

        def humphrey(vertices, faces):
            mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
            return np.asarray(filter_humphrey(mesh, alpha=alpha, beta=beta, iterations=iterations).vertices)

        found["trimesh filter_humphrey"] = (f"trimesh {trimesh.__version__}, α={alpha}, β={beta}", humphrey)
    except ImportError as error:
        found["trimesh filter_humphrey"] = (f"not installed ({error.name})", None)
    try:
        import pymeshlab

        def meshlab_hc(vertices, faces):
            meshset = pymeshlab.MeshSet()
            meshset.add_mesh(pymeshlab.Mesh(vertex_matrix=vertices, face_matrix=faces.astype(np.int32)))
            for _ in range(iterations):  # one HC step per call; no α, β fixed at 0.5
                meshset.apply_coord_hc_laplacian_smoothing()
            return meshset.current_mesh().vertex_matrix()

        found["PyMeshLab HC"] = (f"pymeshlab {metadata.version('pymeshlab')}, {iterations} calls", meshlab_hc)
    except ImportError as error:
        found["PyMeshLab HC"] = (f"not installed ({error.name})", None)
    try:
        import open3d as o3d

        def o3d_mesh(vertices, faces):
            return o3d.geometry.TriangleMesh(
                o3d.utility.Vector3dVector(vertices), o3d.utility.Vector3iVector(faces.astype(np.int32))
            )

        def laplacian(vertices, faces):
            smoothed = o3d_mesh(vertices, faces).filter_smooth_laplacian(number_of_iterations=iterations)
            return np.asarray(smoothed.vertices)

        def taubin(vertices, faces):
            smoothed = o3d_mesh(vertices, faces).filter_smooth_taubin(number_of_iterations=iterations)
            return np.asarray(smoothed.vertices)

        found["Open3D Laplacian"] = (f"open3d {o3d.__version__}, λ=0.5", laplacian)
        found["Open3D Taubin"] = (f"open3d {o3d.__version__}, λ=0.5, μ=-0.53", taubin)
    except ImportError as error:
        for name in ("Open3D Laplacian", "Open3D Taubin"):
            found[name] = (f"not installed ({error.name})", None)
    return found


# --- Measuring -----------------------------------------------------------------------------------------


def timed(run, repeats):
    """Median wall time of ``repeats`` calls, CPU time / wall time of the whole lot (> 1: threads), and
    the last result."""
    times = []
    cpu = 0.0
    for _ in range(repeats):
        gc.collect()
        start, start_cpu = time.perf_counter(), time.process_time()
        result = run()
        times.append(time.perf_counter() - start)
        cpu += time.process_time() - start_cpu
    return statistics.median(times), cpu / sum(times), result


def torus_rms(points, diagonal):
    """RMS distance to the smooth torus the mesh samples, in % of the bounding-box diagonal."""
    p = np.asarray(points, dtype=np.float64)
    ring = np.hypot(p[:, 0], p[:, 1]) - RATIO * MINOR
    distance = np.hypot(ring, p[:, 2]) - MINOR
    return 100.0 * float(np.sqrt(np.mean(distance**2))) / diagonal


def traced_extra_bytes(run, n_vertices):
    """Peak memory allocated during ``run`` beyond its output, per vertex (tracemalloc sees NumPy)."""
    gc.collect()
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        result = run()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return (peak - base - result.nbytes) / n_vertices


def _status_kib(field):
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith(field + ":"):
                return int(line.split()[1]) * 1024
    raise OSError(field)


def rss_extra_bytes(run, n_vertices):
    """Peak resident growth during ``run`` beyond its output, per vertex (Linux: resets VmHWM first).

    Unlike tracemalloc this also sees C-level allocations (SuperLU); None where /proc cannot do it.
    glibc's malloc would reuse freed, still resident heap blocks unseen, so they are handed back first
    and its mmap threshold is pinned (large arrays then come from and go back to the system)."""
    try:
        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt(-3, 128 * 1024)  # M_MMAP_THRESHOLD; fixed from now on
    except (OSError, AttributeError):
        return None
    try:
        gc.collect()
        libc.malloc_trim(0)
        with open("/proc/self/clear_refs", "w") as refs:
            refs.write("5")  # reset the peak-RSS watermark
        base = _status_kib("VmRSS")
        result = run()
        peak = _status_kib("VmHWM")
    except OSError:
        return None
    return (peak - base - result.nbytes) / n_vertices


def machine_line():
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as info:
            cpu = next(line.split(":", 1)[1].strip() for line in info if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg()) if hasattr(os, "getloadavg") else "n/a"
    return (
        f"{cpu}, {os.cpu_count()} cores, load average at start {load}; Python {platform.python_version()}, "
        f"NumPy {np.__version__}, SciPy {scipy.__version__}"
    )


# --- One mesh size -------------------------------------------------------------------------------------


def _unshuffle(result, noisy, scattered):
    """Bring a result on the renumbered mesh back to the original numbering (for the quality columns)."""
    back = np.empty(len(noisy), dtype=np.int64)
    back[np.lexsort(noisy.T[::-1])] = np.lexsort(scattered.T[::-1])
    return result[back]


def sequential_solve_floor(points, edges, iterations, repeats):
    """Seconds for the ``iterations`` triangular solves of a sequential HC run, nothing else (core
    internals: this is a diagnostic, not an API)."""
    from core.smoothing import _GaussSeidel

    operator = core.umbrella_operator(edges, points.shape[0])
    system = _GaussSeidel(operator, np.ones(points.shape[0], dtype=bool), 1.0, points.dtype)
    planar = np.ascontiguousarray(points.T)

    def solves():
        for _ in range(iterations):
            system.solve_lower(planar.copy())

    return timed(solves, repeats)[0]


def bench_size(n_target, args, peers, out):
    vertices, faces = meshes.torus(n_target, ratio=RATIO, minor_radius=MINOR)
    noisy = meshes.add_noise(vertices, fraction=0.01, seed=args.seed)
    if args.shuffle:
        noisy, faces = meshes.shuffled(noisy, faces, seed=args.seed)
    edges = meshes.edges_from_faces(faces).astype(np.int32)  # Blender hands out int32 edge pairs
    n = noisy.shape[0]
    diagonal = meshes.bbox_diagonal(noisy)
    true_volume = meshes.torus_volume(RATIO, MINOR)
    repeats = args.repeats or (5 if n < 500_000 else 3)
    hc = dict(alpha=args.alpha, beta=args.beta, iterations=args.iterations)
    order = "random" if args.shuffle else "grid"
    out(
        f"\n## {n_target:,} vertices requested ({n:,} vertices, {edges.shape[0]:,} edges, "
        f"{faces.shape[0]:,} triangles)\n"
    )
    out(
        f"Noisy torus (σ = 1 % of bbox diagonal, seed {args.seed}, vertex order: {order}); "
        f"{args.iterations} iterations; median of {repeats} runs. Input RMS distance to the true torus: "
        f"{torus_rms(noisy, diagonal):.3f} % of diagonal; its volume vs the true torus: "
        f"{core.measure_change(noisy, noisy, faces).volume_before / true_volume - 1:+.3%}.\n"
    )

    rows = []  # (method, variant, seconds, cpu/wall, result)
    core_times = {}
    for mode in ("simultaneous", "sequential"):
        for dtype in (np.float32, np.float64):
            start = noisy.astype(dtype)
            seconds, cpu, result = timed(
                lambda start=start, mode=mode: core.hc_smooth(start, edges, mode=mode, **hc), repeats
            )
            core_times[mode, dtype] = seconds
            rows.append(("core.hc_smooth", f"{mode}, {np.dtype(dtype).name}", seconds, cpu, result))
    for name, (description, run) in peers.items():
        if run is None:
            rows.append((name, description, None, None, None))
            continue
        seconds, cpu, result = timed(lambda run=run: run(noisy, faces), repeats)
        rows.append((name, description, seconds, cpu, result))

    if not args.shuffle:
        # Scanners and converters may number vertices at random: the same mesh renumbered, core and
        # trimesh (the core then works in reverse Cuthill-McKee order, core.locality).
        scattered, scattered_faces = meshes.shuffled(noisy, faces, seed=args.seed)
        scattered_edges = meshes.edges_from_faces(scattered_faces).astype(np.int32)
        for dtype in (np.float32, np.float64):
            start = scattered.astype(dtype)
            seconds, cpu, result = timed(lambda start=start: core.hc_smooth(start, scattered_edges, **hc), repeats)
            rows.append(
                (
                    "core.hc_smooth",
                    f"simultaneous, {np.dtype(dtype).name}, random vertex order",
                    seconds,
                    cpu,
                    _unshuffle(result, noisy, scattered),
                )
            )
        description, run = peers.get("trimesh filter_humphrey", (None, None))
        if run is not None:
            seconds, cpu, result = timed(lambda: run(scattered, scattered_faces), repeats)
            rows.append(
                ("trimesh filter_humphrey", "random vertex order", seconds, cpu, _unshuffle(result, noisy, scattered))
            )

    humphrey = next((row[2] for row in rows if row[0] == "trimesh filter_humphrey"), None)
    table = out.table(
        "method",
        "variant",
        "median time (s)",
        "CPU / wall",
        "speed-up vs filter_humphrey",
        "volume change",
        "volume vs true torus",
        "RMS to true torus (% diag)",
        align="llrrrrrr",
    )
    for method, variant, seconds, cpu, result in rows:
        if seconds is None:
            table.row(method, variant, "–", "–", "–", "–", "–", "–")
            continue
        change = core.measure_change(noisy, result, faces)
        volume = f"{change.volume_change:+.3%}" if change.volume_change is not None else "n/a"
        truth = f"{change.volume_after / true_volume - 1:+.3%}" if change.volume_after is not None else "n/a"
        speedup = f"{humphrey / seconds:.2f}×" if humphrey else "–"
        table.row(
            method,
            variant,
            f"{seconds:.3f}",
            f"{cpu:.2f}",
            speedup,
            volume,
            truth,
            f"{torus_rms(result, diagonal):.3f}",
        )

    # Exactness: float64 against the independent matrix form, both modes; trimesh's HC as a bonus.
    out("\n| check | value | target | |")
    out("|---|---:|---:|---|")
    verdicts = []

    def check(name, value, target, ok, unit=""):
        verdicts.append(ok)
        out(f"| {name} | {value}{unit} | {target}{unit} | {'ok' if ok else 'MISSED'} |")

    for mode in ("simultaneous", "sequential"):
        expected = reference_hc(noisy, edges, args.alpha, args.beta, args.iterations, mode)
        got = core.hc_smooth(noisy, edges, mode=mode, **hc)
        deviation = float(np.abs(got - expected).max()) / diagonal
        check(
            f"float64 {mode} vs matrix form of Algorithm 1 (max dev / diag)",
            f"{deviation:.1e}",
            f"≤ {TARGET_AGREEMENT:.0e}",
            deviation <= TARGET_AGREEMENT,
        )
        if mode == "simultaneous":
            core_result = got
    humphrey_result = next((row[4] for row in rows if row[0] == "trimesh filter_humphrey"), None)
    if humphrey_result is not None:
        deviation = float(np.abs(humphrey_result - core_result).max()) / diagonal
        out(f"| trimesh filter_humphrey vs core, same α, β (max dev / diag) | {deviation:.1e} | (info) | |")
    for dtype in (np.float32, np.float64):
        ratio = core_times["sequential", dtype] / core_times["simultaneous", dtype]
        check(
            f"sequential / simultaneous time, {np.dtype(dtype).name}",
            f"{ratio:.2f}",
            f"≤ {TARGET_SEQUENTIAL}",
            ratio <= TARGET_SEQUENTIAL,
        )
    for dtype in (np.float32, np.float64):
        # The floor of the sequential mode: its triangular solves alone (SciPy's SuperLU, one call per
        # iteration with every coordinate; SciPy runs one SuperLU call at a time, so no threads help).
        floor = sequential_solve_floor(noisy.astype(dtype), edges, args.iterations, repeats)
        out(
            f"| SuperLU solves alone ({args.iterations} × 3 coordinates) / simultaneous run, "
            f"{np.dtype(dtype).name} | {floor / core_times['simultaneous', dtype]:.2f} "
            "| (info: the floor of the ratio above) | |"
        )
    if humphrey:
        for dtype in (np.float32, np.float64):
            speedup = humphrey / core_times["simultaneous", dtype]
            name = f"speed-up vs filter_humphrey, simultaneous {np.dtype(dtype).name}"
            if n >= 900_000:
                check(name, f"{speedup:.2f}", f"≥ {TARGET_SPEEDUP:g}", speedup >= TARGET_SPEEDUP, "×")
            else:
                out(f"| {name} | {speedup:.2f}× | (target at 1M) | |")
    for mode in ("simultaneous", "sequential"):
        for dtype in (np.float32, np.float64):
            start = noisy.astype(dtype)

            def run(start=start, mode=mode):
                return core.hc_smooth(start, edges, mode=mode, **hc)

            traced = traced_extra_bytes(run, n)
            resident = rss_extra_bytes(run, n)
            resident_text = f", peak RSS {resident:.0f}" if resident is not None else ""
            check(
                f"peak extra memory per vertex, {mode} {np.dtype(dtype).name} (tracemalloc{resident_text})",
                f"{traced:.1f}",
                f"≤ {TARGET_BYTES:g}",
                traced <= TARGET_BYTES,
                " B",
            )
    return all(verdicts)


def amount_timing(sizes, args, out):
    """core.choose_amount on the benchmark's torus, its probes on the whole mesh and on patches (from
    core.mesh.amount.PATCH_FROM movable vertices up): time, iterations chosen and the largest difference of
    t(k), the degrees of freedom per vertex, between the two."""
    from core.mesh import amount as noise

    table = out.table(
        "vertices", "noise (% of diagonal)", "probes on", "seconds", "iterations chosen", "largest t(k) difference"
    )
    for n_target in sizes:
        vertices, faces = meshes.torus(n_target, ratio=RATIO, minor_radius=MINOR)
        edges = meshes.edges_from_faces(faces).astype(np.int32)
        for fraction in (0.001, 0.002):
            noisy = meshes.add_noise(vertices, fraction=fraction, seed=args.seed)
            operator = core.umbrella_operator(edges, noisy.shape[0])
            traces = {}
            for where, patch_from in (("whole mesh", noisy.shape[0] + 1), ("patches", noise.PATCH_FROM)):
                clock = time.perf_counter()
                chooser = core.AmountChooser(noisy, operator=operator, beta=args.beta, patch_from=patch_from)
                for _ in chooser.steps():
                    pass
                seconds = time.perf_counter() - clock
                traces[where] = chooser.traces
                difference = ""
                if where == "patches":
                    whole = traces["whole mesh"]
                    common = [k for k in chooser.traces if k in whole]
                    difference = f"{max(abs(chooser.traces[k] / whole[k] - 1) for k in common):.2%}"
                table.row(
                    f"{noisy.shape[0]:,}",
                    f"{100 * fraction:g}",
                    where,
                    f"{seconds:.2f}",
                    chooser.amount.iterations,
                    difference,
                )


PARAMETERS = (
    sizes("100k,1M"),
    repeats(0, "runs per timing (0: 5 below 500k vertices, 3 above)"),
    Parameter("shuffle", False, "renumber vertices at random (scanner-like order)"),
    Parameter("alpha", 0.1),
    Parameter("beta", 0.6),
    Parameter("iterations", 10),
    Parameter("seed", 0),
    Parameter("no_peers", False, "time core only"),
    Parameter("amount", False, "time the mesh Automatic Amount instead (whole mesh vs patches)"),
)
QUICK = {"sizes": "5k", "repeats": 1}


def run(args, out):
    if not args.sizes or min(args.sizes) < 9 or args.repeats < 0 or args.iterations < 1:
        raise SystemExit("sizes must be >= 9 vertices, repeats >= 0, iterations >= 1")
    out(f"Machine: {machine_line()}.")
    out(
        f"HC α = {args.alpha}, β = {args.beta}; core timings include input checks and building the "
        "operator from the edge list; peer timings include building their mesh objects and operators.\n"
    )
    peers = {} if args.no_peers else peer_methods(args.alpha, args.beta, args.iterations)
    # Warm up imports and code paths on a tiny mesh so the first timed run is not penalised.
    tiny, tiny_faces = meshes.torus(100)
    for mode in ("simultaneous", "sequential"):
        core.hc_smooth(tiny, meshes.edges_from_faces(tiny_faces), mode=mode, alpha=0.1, beta=0.6, iterations=1)
    for _, peer in peers.values():
        if peer is not None:
            peer(tiny, tiny_faces)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)  # --beta ≤ 0.5 is allowed for comparisons
        if args.amount:
            amount_timing(args.sizes, args, out)
        else:
            for n in args.sizes:
                bench_size(n, args, peers, out)
    return out.rows
