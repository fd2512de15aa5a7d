"""Point-cloud smoothing quality: core.smooth_point_cloud (HC on the RFS mesh, paper section 7)
against a PCA plane-projection baseline, CGAL jet / bilateral smoothing and MeshLab APSS / RIMLS.

Noisy samples of known surfaces (sphere, torus, cube with sharp edges, open spherical cap), Gaussian
noise sigma = 0.5 / 1 / 2 % of the bounding-box diagonal. Reported per method: RMS distance to the
true surface before and after, size change (mean distance to the shape's centre, after vs before),
and wall time of the smoothing call (conversions to the peers' data structures excluded).

    python bench/run.py points                       # 20k and 100k points, every shape and sigma
    python bench/run.py points --sizes 20k --shapes sphere,cube --sigmas 0.01
    python bench/run.py points --timing 100k,1M --repeats 3   # end-to-end time by stage, against CGAL jet
    python bench/run.py points --timing 1M --warm 6  # the same after touching 6 GB of fresh memory
    python bench/run.py points --emst 200x5000       # exact EMST of scan rings (rings x points per ring)
    python bench/run.py points --hc-steps 1M --repeats 3   # 66 HC steps alone, float32/64, with/without influence
    python bench/run.py points --sparse 1500         # sparse, nearly clean sphere (noise 0.1 x spacing)
    python bench/run.py points --alpha 0.01 --iterations-per-round 22   # a fixed amount: 3 x 22 steps

Our rows show the noise / spacing estimate r and the amount the run chose (rounds × steps, alpha).

Peers that are not installed are listed as such; the machine's python3 runs the core and baseline.
"""

import time
import warnings

import numpy as np
from scipy.spatial import cKDTree

import core
from bench.common import Parameter, repeats, sizes

# --- shapes: sampling and exact distance --------------------------------------------------------------


def _sphere_dirs(rng, n):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def sample_sphere(rng, n):
    return _sphere_dirs(rng, n)


def distance_sphere(p):
    return np.abs(np.linalg.norm(p, axis=1) - 1.0)


TORUS_R, TORUS_r = 1.0, 0.4


def sample_torus(rng, n):
    out = np.empty((0, 3))
    while len(out) < n:  # area-uniform: accept the tube angle with weight (R + r cos v) / (R + r)
        u, v = rng.random((2, 2 * n)) * 2 * np.pi
        keep = rng.random(2 * n) < (TORUS_R + TORUS_r * np.cos(v)) / (TORUS_R + TORUS_r)
        u, v = u[keep], v[keep]
        ring = TORUS_R + TORUS_r * np.cos(v)
        out = np.concatenate([out, np.stack([ring * np.cos(u), ring * np.sin(u), TORUS_r * np.sin(v)], 1)])
    return out[:n]


def distance_torus(p):
    ring = np.hypot(p[:, 0], p[:, 1]) - TORUS_R
    return np.abs(np.hypot(ring, p[:, 2]) - TORUS_r)


def sample_cube(rng, n):
    face = rng.integers(0, 6, n)
    p = rng.random((n, 3)) * 2 - 1
    axis = face % 3
    p[np.arange(n), axis] = np.where(face < 3, -1.0, 1.0)
    return p


def distance_cube(p):
    q = np.abs(p) - 1.0
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
    return np.abs(outside + np.minimum(q.max(axis=1), 0.0))


CAP_RADIUS, CAP_ANGLE = 1.5, np.radians(60)


def sample_cap(rng, n):
    z = rng.uniform(np.cos(CAP_ANGLE), 1.0, n)  # Archimedes: z uniform gives area-uniform points
    phi = rng.random(n) * 2 * np.pi
    s = np.sqrt(1 - z * z)
    return CAP_RADIUS * np.stack([s * np.cos(phi), s * np.sin(phi), z], 1)


def distance_cap(p):
    # Exact for points within the cap's cone, which is where noisy samples of it land (up to the rim).
    return np.abs(np.linalg.norm(p, axis=1) - CAP_RADIUS)


SHAPES = {
    "sphere": (sample_sphere, distance_sphere, np.zeros(3)),
    "torus": (sample_torus, distance_torus, np.zeros(3)),
    "cube": (sample_cube, distance_cube, np.zeros(3)),
    "patch": (sample_cap, distance_cap, np.array([0, 0, CAP_RADIUS * (1 + np.cos(CAP_ANGLE)) / 2])),
}


def noisy(shape, n, sigma_fraction, seed=0):
    sample, distance, centre = SHAPES[shape]
    rng = np.random.default_rng(seed)
    clean = sample(rng, n)
    diagonal = np.linalg.norm(clean.max(axis=0) - clean.min(axis=0))
    return clean + rng.normal(scale=sigma_fraction * diagonal, size=clean.shape), diagonal


# --- methods -----------------------------------------------------------------------------------------


def pca_projection(points, k=24):
    """Baseline: project each point onto the PCA plane of its k nearest neighbours."""
    _, neighbours = cKDTree(points).query(points, k, workers=-1)
    out = np.empty_like(points)
    for start in range(0, len(points), 200_000):
        block = slice(start, start + 200_000)
        nb = points[neighbours[block]]
        centre = nb.mean(axis=1)
        centred = nb - centre[:, None]
        _, vectors = np.linalg.eigh(np.einsum("nki,nkj->nij", centred, centred))
        normal = vectors[:, :, 0]
        offset = points[block] - centre
        out[block] = points[block] - np.einsum("ni,ni->n", offset, normal)[:, None] * normal
    return out


def _cgal_point_set(points):
    from CGAL import CGAL_Point_set_3

    point_set = CGAL_Point_set_3.Point_set_3()
    point_set.insert_range(np.ascontiguousarray(points, np.float64).ravel().tolist())
    return point_set


def _cgal_points(point_set):
    return np.array([[p.x(), p.y(), p.z()] for p in point_set.points()])


def cgal_jet(points, k=24):
    from CGAL import CGAL_Point_set_processing_3 as P

    point_set = _cgal_point_set(points)
    start = time.perf_counter()
    P.jet_smooth_point_set(point_set, k)
    return _cgal_points(point_set), time.perf_counter() - start


def cgal_bilateral(points, k=24, passes=3):
    from CGAL import CGAL_Point_set_processing_3 as P

    point_set = _cgal_point_set(points)
    start = time.perf_counter()
    point_set.add_normal_map()
    P.jet_estimate_normals(point_set, k)  # bilateral smoothing needs normals
    for _ in range(passes):
        P.bilateral_smooth_point_set(point_set, k, sharpness_angle=25.0)
    return _cgal_points(point_set), time.perf_counter() - start


MESHLAB_SCALE = 8  # filterscale; the best of 2 (default, barely smooths), 4, 8, 16 on sphere and cube, σ 1 %


def _meshlab(points, filter_name):
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.ascontiguousarray(points, np.float64)))
    start = time.perf_counter()
    ms.apply_filter("compute_normal_for_point_clouds", k=10)
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.ascontiguousarray(points, np.float64)))  # the proxy
    ms.set_current_mesh(0)  # with the proxy current, MeshLab 2025.7 segfaults
    ms.apply_filter(filter_name, controlmesh=0, proxymesh=1, filterscale=MESHLAB_SCALE)
    seconds = time.perf_counter() - start
    return ms.mesh(1).vertex_matrix().copy(), seconds


def meshlab_apss(points):
    return _meshlab(points, "compute_mls_projection_apss")


def meshlab_rimls(points):
    return _meshlab(points, "compute_mls_projection_rimls")


def amount(report):
    """The noise estimate and the amount of smoothing a run used, for the tables."""
    return f"r {report.noise.ratio:.2f}: {report.rounds}×{report.iterations_per_round}, α {report.alpha:.2g}"


def hc_rfs(points, **options):
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)
        out, report = core.smooth_point_cloud(points, return_mesh=True, **options)
    return out, time.perf_counter() - start, amount(report)


def timed(function):
    def run(points):
        start = time.perf_counter()
        out = function(points)
        return out, time.perf_counter() - start

    return run


def available_methods(hc_options):
    methods = {
        "HC on RFS (ours, defaults)": lambda p: hc_rfs(p, **hc_options),
        "HC on RFS (ours, no swapping)": lambda p: hc_rfs(p, **{**hc_options, "swap": False}),
        "PCA projection k=24": timed(pca_projection),
    }
    missing = []
    try:
        import CGAL.CGAL_Point_set_processing_3  # noqa: F401

        methods["CGAL jet k=24"] = cgal_jet
        methods["CGAL bilateral k=24 x3"] = cgal_bilateral
    except ImportError:
        missing.append("CGAL (pip cgal)")
    try:
        import pymeshlab  # noqa: F401

        methods[f"MeshLab APSS scale {MESHLAB_SCALE}"] = meshlab_apss
        methods[f"MeshLab RIMLS scale {MESHLAB_SCALE}"] = meshlab_rimls
    except ImportError:
        missing.append("PyMeshLab")
    return methods, missing


def rms(values):
    return float(np.sqrt(np.mean(values**2)))


def size_of(points, centre):
    return float(np.linalg.norm(points - centre, axis=1).mean())


def parse_count(text):
    text = text.strip().lower()
    scale = {"k": 1_000, "m": 1_000_000}.get(text[-1], 1)
    return int(float(text[:-1] if scale > 1 else text) * scale)


def quality(args, out):
    methods, missing = available_methods(hc_options(args))
    if args.methods:
        wanted = [w.strip().lower() for w in args.methods.split(",")]
        methods = {k: v for k, v in methods.items() if any(w in k.lower() for w in wanted)}
    out("## Point-cloud smoothing quality\n")
    if missing:
        out("Not installed: " + ", ".join(missing) + "\n")
    out(
        "RMS distance to the true surface as % of the bounding-box diagonal (before → after), size change "
        "(mean distance to the centre, after vs before), wall time of the smoothing call.\n"
    )
    table = out.table(
        "shape", "points", "σ", "method", "RMS before", "RMS after", "after/before", "size change", "time (s)"
    )
    for n in args.sizes:
        for shape in args.shapes.split(","):
            _, distance, centre = SHAPES[shape]
            for sigma in [float(s) for s in args.sigmas.split(",")]:
                points, diagonal = noisy(shape, n, sigma, seed=args.seed)
                before = rms(distance(points)) / diagonal
                for name, method in methods.items():
                    try:
                        result, seconds, *note = method(points)  # ours adds its noise estimate and amount
                    except Exception as error:  # a peer failing is a result too
                        failed = f"failed: {type(error).__name__}: {error}"
                        table.row(shape, n, f"{sigma:.1%}", name, failed, "", "", "", "")
                        continue
                    finite = np.isfinite(result).all(axis=1)  # MeshLab APSS can return NaN points
                    lost = "" if finite.all() else f" ({(~finite).sum()} NaN points left out)"
                    result = result[finite]
                    after = rms(distance(result)) / diagonal
                    size = size_of(result, centre) / size_of(points[finite], centre) - 1
                    note = f" [{note[0]}]" if note else ""
                    table.row(
                        shape,
                        n,
                        f"{sigma:.1%}",
                        f"{name}{note}{lost}",
                        f"{before:.3%}",
                        f"{after:.3%}",
                        f"{after / before:.2f}",
                        f"{size:+.2%}",
                        f"{seconds:.2f}",
                    )


def cgal_jet_with_insertion(points, k=24):
    """CGAL jet smoothing as a user of its Python binding runs it: the points inserted, then smoothed
    (reading them back out, a Python loop over the points, is left out)."""
    from CGAL import CGAL_Point_set_processing_3 as P

    start = time.perf_counter()
    point_set = _cgal_point_set(points)
    P.jet_smooth_point_set(point_set, k)
    return time.perf_counter() - start


def timing(args, out):
    if args.warm:
        # On a VM, memory the guest touches for the first time can cost seconds per GB: touched and freed
        # here, the run's own allocations find backed pages (the figure is this machine's, not ours).
        clock = time.perf_counter()
        np.ones(int(args.warm * (1 << 27)))
        out(f"(touched {args.warm:g} GB of fresh memory first: {time.perf_counter() - clock:.1f} s)\n")
    try:
        import CGAL.CGAL_Point_set_processing_3  # noqa: F401

        peer = cgal_jet_with_insertion
    except ImportError:
        peer = None
        out("CGAL (pip cgal) is not installed: our times only.\n")
    out("## End-to-end time of core.smooth_point_cloud (noisy sphere, σ 0.5 %, float32) against CGAL jet (k 24)\n")
    out(
        "Runs alternate ours / CGAL jet (insertion included); each row is one of ours with its stages, then "
        "the medians and their ratio.\n"
    )
    out(
        "| points | run | total (s) | neighbours | noise | EMST | SDG | RFS | HC | local amount | swapping "
        "| CGAL jet (s) | amount | faces |"
    )
    out("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for n in [parse_count(s) for s in args.timing.split(",")]:
        points, _ = noisy("sphere", n, 0.005, seed=args.seed)
        points = points.astype(np.float32)
        totals, peers = [], []
        for run in range(args.repeats):
            start = time.perf_counter()
            _, report = core.smooth_point_cloud(points, return_mesh=True, **hc_options(args))
            totals.append(time.perf_counter() - start)
            peers.append(peer(points) if peer else float("nan"))
            s = report.seconds
            out(
                f"| {n} | {run + 1} | {totals[-1]:.1f} | {s.get('neighbours', 0):.1f} | {s.get('noise', 0):.2f} | "
                + " | ".join(f"{s.get(k, 0):.1f}" for k in ("emst", "sdg", "rfs", "hc", "local amount", "swap"))
                + f" | {peers[-1]:.1f} | {amount(report)} | {len(report.mesh.faces)} |"
            )
        ours, jet = float(np.median(totals)), float(np.median(peers))
        out(f"| {n} | **median** | **{ours:.1f}** | | | | | | | | | **{jet:.1f}** | **{ours / jet:.2f}× jet** | |")


def hc_steps_timing(args, out):
    """The HC stage alone: one run's final RFS mesh and local-amount influence, then 66 HC steps on it
    (one round of the 3 x 66 a noisy 1M sphere gets), float32 and float64, with and without the influence."""
    from core.adjacency import umbrella_operator
    from core.smoothing import smooth

    n = parse_count(args.hc_steps)
    points, _ = noisy("sphere", n, 0.005, seed=args.seed)
    _, report = core.smooth_point_cloud(points.astype(np.float32), return_mesh=True)
    operator = umbrella_operator(report.mesh.edges, n)
    weighted = int((report.influence < 1).sum())
    out(f"## 66 HC steps on the RFS mesh of a noisy {n}-point sphere ({operator.indptr[-1]} non-zeros)\n")
    out(f"| precision | influence | seconds ({args.repeats} runs) |")
    out("|---|---|---|")
    for dtype in (np.float32, np.float64):
        start = points.astype(dtype)
        for influence in (None, report.influence):
            seconds = []
            for _ in range(args.repeats):
                clock = time.perf_counter()
                smooth(start, None, alpha=0.0033, beta=0.55, iterations=66, operator=operator, influence=influence)
                seconds.append(time.perf_counter() - clock)
            what = "none" if influence is None else f"local amount ({weighted} points below 1)"
            out(f"| {np.dtype(dtype).name} | {what} | " + " / ".join(f"{s:.2f}" for s in seconds) + " |")


def sparse(args, out):
    """Sparse, nearly clean clouds: n points on the unit sphere, noise 0.1 x the spacing sqrt(4 pi / n)."""
    n = parse_count(args.sparse)
    out(f"## Sparse, nearly clean: {n} points on a unit sphere, noise 0.1 × the spacing (seeds 0-4)\n")
    out("| seed | noise removed | amount | size change |")
    out("|---|---|---|---|")
    for seed in range(5):
        rng = np.random.default_rng(seed)
        clean = sample_sphere(rng, n)
        points = clean + rng.normal(scale=0.1 * np.sqrt(4 * np.pi / n), size=clean.shape)
        result, _, note = hc_rfs(points, **hc_options(args))
        removed = 1 - rms(distance_sphere(result)) / rms(distance_sphere(points))
        size = size_of(result, np.zeros(3)) / size_of(points, np.zeros(3)) - 1
        out(f"| {seed} | {removed:.1%} | {note} | {size:+.2%} |")


def scan_rings(rings, per_ring, seed=0):
    """Latitude rings on the unit sphere, dense along each ring and far apart across (a scanner's
    lines): the hard case for the EMST, whose kNN lists never leave a ring."""
    rng = np.random.default_rng(seed)
    theta = np.linspace(0.05, np.pi - 0.05, rings)[:, None]
    phi = np.linspace(0.0, 2 * np.pi, per_ring, endpoint=False)[None, :] + rng.random((rings, 1))
    p = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta) + 0 * phi], axis=-1)
    return p.reshape(-1, 3) + rng.normal(scale=1e-5, size=(rings * per_ring, 3))


def emst_timing(args, out):
    from core.pointcloud.spanning_tree import NeighbourIndex, boruvka_emst

    rings, per_ring = (int(x) for x in args.emst.lower().split("x"))
    points = scan_rings(rings, per_ring, seed=args.seed)
    out(f"## Exact EMST of {rings} scan rings x {per_ring} points ({len(points)} points)\n")
    out("| run | kNN lists (s) | Borůvka (s) | total (s) |")
    out("|---|---|---|---|")
    for run in range(args.repeats):
        start = time.perf_counter()
        index = NeighbourIndex(points, 12)
        middle = time.perf_counter()
        boruvka_emst(index)
        end = time.perf_counter()
        out(f"| {run + 1} | {middle - start:.1f} | {end - middle:.1f} | {end - start:.1f} |")


def hc_options(args):
    options = {}
    for name in ("rounds", "alpha", "beta"):
        if getattr(args, name) is not None:
            options[name] = getattr(args, name)
    if args.spacing_factor is not None:
        options["spacing_factor"] = args.spacing_factor
        options["gap_factor"] = max(args.spacing_factor, 3.0)
    if args.iterations_per_round is not None:
        options["iterations_per_round"] = args.iterations_per_round
    return options


PARAMETERS = (
    sizes("20k,100k"),
    Parameter("shapes", "sphere,torus,cube,patch"),
    Parameter("sigmas", "0.005,0.01,0.02"),
    Parameter("methods", "", "comma-separated name fragments, e.g. 'ours,jet'"),
    Parameter("timing", "", "sizes for the end-to-end timing table instead, e.g. 100k,1M"),
    Parameter("emst", "", "time the exact EMST of scan rings instead, e.g. 200x5000"),
    Parameter("sparse", "", "noise removed from a sparse, nearly clean sphere of this many points instead, e.g. 1500"),
    Parameter("warm", 0.0, "with --timing: touch this many GB of memory first"),
    Parameter("hc_steps", "", "time 66 HC steps alone on one size instead, e.g. 1M"),
    repeats(1, "timing runs per size (the table gives each)"),
    Parameter("rounds", None, "for our rows (default: the core's)", int),
    Parameter("alpha", None, "", float),
    Parameter("beta", None, "", float),
    Parameter("spacing_factor", None, "", float),
    Parameter("iterations_per_round", None, "", int),
    Parameter("seed", 0),
)
QUICK = {"sizes": "2k", "shapes": "sphere", "sigmas": "0.01"}


def run(args, out):
    if args.emst:
        emst_timing(args, out)
    elif args.hc_steps:
        hc_steps_timing(args, out)
    else:
        (timing if args.timing else sparse if args.sparse else quality)(args, out)
    return out.rows
