"""Point-cloud smoothing quality on real scans: core.smooth_point_cloud at its defaults against CGAL jet
smoothing (k = 24), CGAL bilateral smoothing, a PCA plane projection (k = 32) and MeshLab's APSS / RIMLS
projections, on the same noisy samples.

Inputs: area-uniform samples of 20k or 100k points of the benchmark meshes (bench_quality_inputs.py: the
pymeshlab wheel's bunny, cow, bone and airplane, Blender's Suzanne, a cube, a thin plate, a thin torus),
Gaussian noise of σ = 0.1 / 0.25 / 0.5 / 1 % of the bounding-box diagonal, along the normal of the face
each point was drawn from ("normal") or on every coordinate ("iso"), one seed per cell.

Measured per method: RMS and max distance to the clean surface (% of the diagonal), the noise it
removed (1 - RMS after / RMS before), the mean-radius change (mean distance to the clean sample's
centroid, against the clean sample's; the noisy input's own is shown) and the wall time of the
smoothing call (conversion into CGAL / MeshLab structures excluded).

    python bench/run.py quality_points                              # 20k points, every object, noise and σ
    python bench/run.py quality_points --sizes 100k --methods ours,jet,pca --kinds normal
    python bench/run.py quality_points --objects cow,bunny --sigmas 0.0025,0.005 --methods ours,jet
    python bench/run.py quality_points --methods ours,uniform,jet  # with and without the local amount
    python bench/run.py quality_points --objects plate --sigmas 0.005,0.01 --methods ours,jet --steps 8,20

The report goes to stdout and bench/results/ (markdown and JSON).
"""

import os
import time
import zlib

import numpy as np

from bench import bench_points
from bench import bench_quality_inputs as inputs
from bench.common import Parameter, sizes

SIGMAS = "0.001,0.0025,0.005,0.01"


def ours(points):
    result, seconds, note = bench_points.hc_rfs(points)
    return result, seconds, note


def ours_uniform(points):
    return bench_points.hc_rfs(points, local_amount=False)


def pca32(points):
    start = time.perf_counter()
    out = bench_points.pca_projection(points, k=32)
    return out, time.perf_counter() - start


METHODS = {
    "ours": ("HC Smooth (defaults)", ours),
    "uniform": ("HC Smooth, one global amount (local_amount=False)", ours_uniform),
    "jet": ("CGAL jet k=24", bench_points.cgal_jet),
    "pca": ("PCA plane k=32", pca32),
    "bilateral": ("CGAL bilateral k=24 x3", bench_points.cgal_bilateral),
    "apss": (f"MeshLab APSS scale {bench_points.MESHLAB_SCALE}", bench_points.meshlab_apss),
    "rimls": (f"MeshLab RIMLS scale {bench_points.MESHLAB_SCALE}", bench_points.meshlab_rimls),
}


def mean_radius(points, centre):
    return float(np.linalg.norm(points - centre, axis=1).mean())


PARAMETERS = (
    Parameter("objects", ",".join(inputs.ALL_MESHES)),
    sizes("20k", "points per sample, comma-separated"),
    Parameter("kinds", "normal,iso"),
    Parameter("sigmas", SIGMAS),
    Parameter("methods", ",".join(METHODS), f"keys among {', '.join(METHODS)}"),
    Parameter("seed", 0),
    Parameter("steps", "", "also ours with these fixed HC steps per round (alpha matched), e.g. 8,20"),
)
QUICK = {"objects": "cube", "sizes": "2k", "kinds": "iso", "sigmas": "0.005"}


def run(args, out):
    methods = {key: METHODS[key] for key in inputs.parse_list(args.methods)}
    for steps in inputs.parse_list(args.steps, int):
        methods[f"steps{steps}"] = (
            f"HC Smooth, {steps} steps per round",
            lambda points, steps=steps: bench_points.hc_rfs(points, iterations_per_round=steps),
        )
    record = []
    out(f"Load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}.\n")
    out(
        "Each cell: noise removed (1 − RMS after / RMS before; higher is better), RMS after in % of the "
        "diagonal, mean-radius change against the clean sample, time (s). "
        "Ours adds its noise estimate and amount.\n"
    )
    names = [name for name, _ in methods.values()]
    out("| object | points | noise | σ | input RMS (radius) | " + " | ".join(names) + " | ours − jet |")
    out("|---" * (len(names) + 6) + "|")
    for size in args.sizes:
        for name in inputs.parse_list(args.objects):
            vertices, faces = inputs.load_mesh(name)
            surface = inputs.Surface(vertices, faces)
            for kind in inputs.parse_list(args.kinds):
                for sigma in inputs.parse_list(args.sigmas, float):
                    seed = zlib.crc32(f"{name}/{size}/{kind}/{sigma:g}".encode()) ^ args.seed
                    clean, normals = inputs.sample_surface(vertices, faces, size, seed)
                    diagonal = inputs.diagonal(clean)
                    noisy = inputs.add_noise(clean, normals, sigma * diagonal, kind, seed + 1)
                    centre = clean.mean(axis=0)
                    radius = mean_radius(clean, centre)
                    before = float(np.sqrt(np.mean(surface.distance(noisy) ** 2)))
                    cell = {
                        "object": name,
                        "points": size,
                        "kind": kind,
                        "sigma": sigma,
                        "input": {"rms": before / diagonal, "radius": mean_radius(noisy, centre) / radius - 1},
                        "methods": {},
                    }
                    texts = []
                    for key, (_label, method) in methods.items():
                        try:
                            result, seconds, *note = method(noisy)
                        except Exception as error:  # a peer failing is a result too
                            cell["methods"][key] = {"error": f"{type(error).__name__}: {error}"}
                            texts.append(f"failed: {type(error).__name__}")
                            continue
                        finite = np.isfinite(result).all(axis=1)  # MeshLab APSS can return NaN points
                        distance = surface.distance(result[finite])
                        after = float(np.sqrt(np.mean(distance**2)))
                        entry = {
                            "rms": after / diagonal,
                            "max": float(distance.max()) / diagonal,
                            "removed": 1 - after / before,
                            "radius": mean_radius(result[finite], centre) / radius - 1,
                            "seconds": seconds,
                            "nan_points": int((~finite).sum()),
                        }
                        if note:
                            entry["note"] = note[0]
                        cell["methods"][key] = entry
                        extra = f"; {note[0]}" if note else ""
                        lost = f"; {entry['nan_points']} NaN" if entry["nan_points"] else ""
                        texts.append(
                            f"{entry['removed']:.0%} ({100 * entry['rms']:.3f}, {100 * entry['radius']:+.2f}%, "
                            f"{seconds:.1f} s{extra}{lost})"
                        )
                    m = cell["methods"]
                    versus = (
                        f"{m['ours']['removed'] - m['jet']['removed']:+.0%}"
                        if "removed" in m.get("ours", {}) and "removed" in m.get("jet", {})
                        else "–"
                    )
                    out(
                        f"| {name} | {size} | {kind} | {sigma:.2%} | {100 * before / diagonal:.3f} "
                        f"({100 * cell['input']['radius']:+.2f}%) | " + " | ".join(texts) + f" | {versus} |"
                    )
                    record.append(cell)
    for key in ("ours", "uniform"):
        pairs = [
            (c["methods"][key], c["methods"]["jet"])
            for c in record
            if "removed" in c["methods"].get(key, {}) and "removed" in c["methods"].get("jet", {})
        ]
        if not pairs:
            continue
        won = sum(o["removed"] >= j["removed"] for o, j in pairs)
        out(
            f"\n{methods[key][0]} removed at least jet's share of the noise in {won} of {len(pairs)} cells; "
            f"largest |radius change| {100 * max(abs(o['radius']) for o, _ in pairs):.2f} %."
        )
    return record
