"""What the default costs on a big scan: core.smooth_mesh with the Automatic Amount against the fixed
10-iteration HC run (alpha 0.1, beta 0.6), on the same noisy torus, in the same process.

Time: median wall time of ``--repeat`` runs each. Memory: the peak of what NumPy and SciPy allocate
during the call (tracemalloc, which NumPy reports its buffers to), above what was allocated before it.
The input is float32, as Blender hands it over.

    python bench/bench_default_cost.py                 # 5M vertices, 3 runs each
    python bench/bench_default_cost.py --vertices 1M --repeat 5
"""

import argparse
import pathlib
import statistics
import sys
import time
import tracemalloc

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
import core  # noqa: E402
from bench import meshes  # noqa: E402
from bench.report import Report  # noqa: E402


def count(text):
    """'5M' -> 5_000_000, '250k' -> 250_000."""
    scale = {"k": 1_000, "M": 1_000_000}.get(text[-1], 1)
    return int(float(text[:-1] if scale > 1 else text) * scale)


def measured(function):
    """(seconds, peak bytes above the start, result) of one call."""
    tracemalloc.start()
    tracemalloc.reset_peak()
    base = tracemalloc.get_traced_memory()[0]
    start = time.perf_counter()
    result = function()
    seconds = time.perf_counter() - start
    peak = tracemalloc.get_traced_memory()[1] - base
    tracemalloc.stop()
    return seconds, peak, result


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--vertices", default="5M", help="torus size, e.g. 5M, 1M, 250k (default 5M)")
    parser.add_argument("--noise", type=float, default=0.001, help="noise, a fraction of the diagonal (0.001)")
    parser.add_argument("--repeat", type=int, default=3, help="runs of each (median reported; default 3)")
    args = parser.parse_args()
    vertices, faces = meshes.torus(count(args.vertices))
    noisy = meshes.add_noise(vertices, args.noise, seed=1).astype(np.float32)
    edges = meshes.edges_from_faces(faces)
    del vertices
    runs = {
        "fixed: alpha 0.1, beta 0.6, 10 iterations": lambda: core.smooth_mesh(
            noisy, edges, faces=faces, alpha=0.1, beta=0.6, iterations=10, return_report=True
        ),
        "default: Automatic Amount": lambda: core.smooth_mesh(noisy, edges, faces=faces, return_report=True),
    }
    figures = {name: [] for name in runs}
    for _ in range(args.repeat):
        for name, run in runs.items():  # alternating, so both see the same machine
            seconds, peak, (_, report) = measured(run)
            figures[name].append((seconds, peak, report))
    with Report("bench_default_cost") as out:
        out(f"# The default's cost on {len(noisy):,} vertices (noisy torus, noise {args.noise:.2%} of the diagonal)")
        out()
        out(f"`python bench/bench_default_cost.py --vertices {args.vertices} --repeat {args.repeat}`")
        out()
        out("| run | iterations | median time | peak memory | time / fixed | memory / fixed |")
        out("|---|---|---|---|---|---|")
        fixed_time = statistics.median(s for s, _, _ in figures[next(iter(runs))])
        fixed_peak = statistics.median(p for _, p, _ in figures[next(iter(runs))])
        for name, rows in figures.items():
            seconds = statistics.median(s for s, _, _ in rows)
            peak = statistics.median(p for _, p, _ in rows)
            report = rows[-1][2]
            out(
                f"| {name} | {report.iterations} | {seconds:.2f} s | {peak / 2**30:.2f} GiB | "
                f"{seconds / fixed_time:.2f}x | {peak / fixed_peak:.2f}x |"
            )


if __name__ == "__main__":
    main()
