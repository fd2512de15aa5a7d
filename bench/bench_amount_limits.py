"""How far can any automatic amount go on the light-noise mesh cells? (bench/README.md, "Other benchmarks")

For each cell of bench_quality.py's benchmark: the best peer at its defaults (Blender's modifiers left
out), HC Smooth's default, and along HC paths with alpha 0 (beta 0.6, 0.75, 0.9; 1 to --iterations
iterations; closed meshes get their volume back as the operator does) three picks:

* oracle: the least true RMS distance to the clean surface, the most any choice of (beta, iterations)
  at alpha 0 can reach;
* GCV: the least generalized cross-validation score over every (beta, iterations), as core.mesh.amount
  computes it but given the clean normals;
* Cp: Mallows' Cp, the unbiased estimate of the error given the *true* noise sigma and the clean
  normals, R(k) + sigma^2 (2 t(k) - 1), which no mesh-only estimate can beat on average.

R(k) is the mean square of the removed part along the normals, t(k) = tr(S_k) / n from 30 Hutchinson
probes. RMS in % of the diagonal; a pick "wins" when it is below the best peer's default.

    .envs/bench/bin/python bench/run.py amount_limits                     # 7 coarse meshes, ~3 min
    .envs/bench/bin/python bench/run.py amount_limits --meshes cow --kinds iso --sigmas 0.002
"""

import numpy as np

import core
from bench import bench_quality as bq
from bench import bench_quality_inputs as inputs
from bench.common import Parameter

BETAS = (0.6, 0.75, 0.9)
PROBES = 30
COARSE = "cow,bone,cube,plate,airplane,suzanne,thin_torus"  # the bunny's cells are all won


def paths(case, iterations):
    """Per beta: (true RMS with the volume given back, R along the clean normals, t) at 1..iterations."""
    n = len(case.noisy)
    operator = core.umbrella_operator(case.edges, n)
    normals = inputs.vertex_normals(case.clean, case.faces)
    probes = np.random.default_rng(0).choice([-1.0, 1.0], size=(n, PROBES))
    out = {}
    for beta in BETAS:

        def run(start, beta=beta):
            return bq.quiet(
                core.Smoothing, start, None, method="hc", alpha=0.0, beta=beta, iterations=iterations, operator=operator
            )

        data = run(case.noisy)
        blocks = [(run(probes[:, i : i + 3]), probes[:, i : i + 3]) for i in range(0, PROBES, 3)]
        rms, residual, trace = [], [], []
        for _ in range(iterations):
            data.advance(1)
            smoothed = data.result().positions
            positions = smoothed
            if case.closed:
                positions = core.mesh.volume.restore_volume(case.noisy, smoothed, case.faces)[0]
            along = np.einsum("ij,ij->i", case.noisy - smoothed, normals)
            total = 0.0
            for block, probe in blocks:
                block.advance(1)
                total += float(np.einsum("ij,ij->", block.result().positions, probe))
            rms.append(case.rms(positions))
            residual.append(float(np.mean(along**2)))
            trace.append(total / (PROBES * n))
        out[beta] = tuple(np.asarray(x) for x in (rms, residual, trace))
    return out


def pick(table, score):
    """(beta, iterations, true RMS) where ``score(R, t)`` is least over every path."""
    beta = min(table, key=lambda b: score(*table[b][1:]).min())
    k = int(np.argmin(score(*table[beta][1:])))
    return beta, k + 1, float(table[beta][0][k])


PARAMETERS = (
    Parameter("meshes", COARSE),
    Parameter("kinds", "normal,iso"),
    Parameter("sigmas", "0.001,0.002,0.004"),
    Parameter("iterations", 40),
)
QUICK = {"meshes": "cube", "kinds": "iso", "sigmas": "0.004", "iterations": 4}


def run(args, out):
    peers = [p for p in bq.PEERS if p.run is not None and bq.available(p)]
    out(f"Peers at their defaults: {', '.join(p.name for p in peers) or 'none installed'}. RMS in % of the diagonal.\n")
    table = out.table(
        "mesh", "noise", "σ", "best peer default", "HC Smooth default", "oracle, α 0", "GCV", "Cp, true σ"
    )
    counts = {"default": 0, "oracle": 0, "gcv": 0, "cp": 0}
    cells = 0
    for mesh in inputs.parse_list(args.meshes):
        for kind in inputs.parse_list(args.kinds):
            for sigma in inputs.parse_list(args.sigmas, float):
                case = bq.make_case(mesh, kind, sigma, 0)
                peer_rms, peer_name = min(
                    ((case.rms(p.run(case, p.default)), p.name) for p in peers), default=(np.inf, "none")
                )
                default = case.rms(bq.hc_default(case)[0])
                walks = paths(case, args.iterations)
                sig2 = (sigma * case.diagonal) ** 2
                beta_o = min(walks, key=lambda b: walks[b][0].min())
                oracle = (beta_o, int(np.argmin(walks[beta_o][0])) + 1, float(walks[beta_o][0].min()))
                gcv = pick(walks, lambda r, t: r / (1.0 - t) ** 2)
                cp = pick(walks, lambda r, t, sig2=sig2: r + sig2 * (2.0 * t - 1.0))
                picks = {"default": default, "oracle": oracle[2], "gcv": gcv[2], "cp": cp[2]}
                text = {}
                for key, value in picks.items():
                    won = value < peer_rms
                    counts[key] += won
                    text[key] = f"**{100 * value:.4f}**" if won else f"{100 * value:.4f}"
                cells += 1
                table.row(
                    mesh,
                    kind,
                    f"{100 * sigma:g}%",
                    f"{100 * peer_rms:.4f} ({peer_name})",
                    text["default"],
                    f"{text['oracle']} (β {oracle[0]:g}, {oracle[1]})",
                    f"{text['gcv']} (β {gcv[0]:g}, {gcv[1]})",
                    f"{text['cp']} (β {cp[0]:g}, {cp[1]})",
                )
    out(
        f"\nBelow the best peer's default (bold), of {cells}: HC Smooth default {counts['default']}, "
        f"oracle {counts['oracle']}, GCV {counts['gcv']}, Cp with the true σ {counts['cp']}."
    )
    return out.rows
