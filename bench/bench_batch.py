"""A folder of scans through the file route without Blender: serial against `--jobs 2` (a LocalCluster) and
against `--scheduler` (a 2-worker LocalCluster started here, as `dask scheduler` + 2 `dask worker`).

    .envs/bench/bin/python bench/run.py batch                     # 16 files of 250k vertices, medians of 3
    .envs/bench/bin/python bench/run.py batch --quick             # 4 files of 20k vertices, one run

Each run is `python scripts/hc_smooth_files.py scans/ -o OUT [--jobs 2 | --scheduler ADDRESS]` in a fresh
process, timed end to end (start-up, the cluster's start for --jobs, reading, smoothing, writing), runs
interleaved; every result is checked byte for byte against the serial run's. The machine's load average is
reported beside the times (the VM is shared: compare the ratios of one run).
"""

import hashlib
import math
import os
import pathlib
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

from bench.common import ROOT, Parameter, count, repeats

SCRIPT = ROOT / "scripts" / "hc_smooth_files.py"
# Every run gets the environment this process started with, as a user's shell has it: starting a LocalCluster
# sets MALLOC_TRIM_THRESHOLD_ (Dask's nanny.pre-spawn-environ) in this process's os.environ for good, and a
# serial run that inherited it would take about 1.7 times as long (cli/batch.py, heap_for_large_arrays).
ENVIRONMENT = dict(os.environ)


def torus_ply(path, vertices, seed):
    """A noisy closed quad torus of about ``vertices`` vertices (σ 0.2 % of its size) as binary PLY."""
    n = max(8, round(math.sqrt(vertices)))
    u, v = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    a, b = 2 * np.pi * u / n, 2 * np.pi * v / n
    p = np.stack([(2 + np.cos(b)) * np.cos(a), (2 + np.cos(b)) * np.sin(a), np.sin(b)], -1).reshape(-1, 3)
    p += np.random.default_rng(seed).normal(0, 0.012, p.shape)
    q = np.stack([u * n + v, (u + 1) % n * n + v, (u + 1) % n * n + (v + 1) % n, u * n + (v + 1) % n], -1)
    faces = np.zeros(n * n, [("c", "u1"), ("i", "<i4", 4)])
    faces["c"], faces["i"] = 4, q.reshape(-1, 4)
    head = (
        f"ply\nformat binary_little_endian 1.0\nelement vertex {len(p)}\nproperty float x\nproperty float y\n"
        f"property float z\nelement face {n * n}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    path.write_bytes(head.encode() + p.astype("<f4").tobytes() + faces.tobytes())
    return len(p)


def digests(folder):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}


def timed_run(scans, out, extra):
    shutil.rmtree(out, ignore_errors=True)
    start = time.perf_counter()
    completed = subprocess.run(
        [sys.executable, str(SCRIPT), str(scans), "-o", str(out), *extra],
        capture_output=True,
        text=True,
        env=ENVIRONMENT,
    )
    seconds = time.perf_counter() - start
    if completed.returncode != 0:
        raise SystemExit(f"{' '.join(extra) or 'serial'} failed:\n{completed.stdout}\n{completed.stderr}")
    return seconds


PARAMETERS = (
    Parameter("files", 16),
    Parameter("vertices", "250k", "vertices per file", count),
    repeats(3),
)
QUICK = {"files": 4, "vertices": "20k", "repeats": 1}


def run(args, out):
    import distributed

    with tempfile.TemporaryDirectory(prefix="bench_batch_") as temporary:
        work = pathlib.Path(temporary)
        scans = work / "scans"
        scans.mkdir()
        sizes = [torus_ply(scans / f"scan{i:02d}.ply", args.vertices, i) for i in range(args.files)]
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=":0") as cluster:
            routes = {
                "serial": [],
                "--jobs 2": ["--jobs", "2"],
                "--scheduler": ["--scheduler", cluster.scheduler_address],
            }
            times = {name: [] for name in routes}
            loads = []
            expected = None
            for _ in range(args.repeats):
                for name, extra in routes.items():
                    loads.append(os.getloadavg()[0])
                    times[name].append(timed_run(scans, work / "out", extra))
                    found = digests(work / "out")
                    expected = expected or found
                    if found != expected:
                        raise SystemExit(f"{name}: results differ from the serial run's")
        serial = statistics.median(times["serial"])
        out(f"{args.files} files of {sizes[0]:,} vertices, medians of {args.repeats}; load average (1 min)")
        out(f"{min(loads):.1f} to {max(loads):.1f} while it ran (other jobs share the machine).")
        out("Every run's result files equal the serial run's, byte for byte.")
        out()
        table = out.table("route", "wall time, median (runs)", "/ serial", align="lrr")
        for name, values in times.items():
            runs = ", ".join(f"{value:.1f}" for value in values)
            table.row(name, f"{statistics.median(values):.1f} s ({runs})", f"{statistics.median(values) / serial:.2f}")
    return out.rows
