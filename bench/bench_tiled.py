"""Scans larger than memory: the command line's tiled route (cli/tiled.py) against its whole (in-core) run.

A noisy torus is written as a binary PLY file (float x, y, z and an uchar colour per vertex, triangles),
generated in blocks of rows, so that no array of the whole mesh is made here. Each run is the command line
(`hc_smooth FILE -o OUT --iterations K`, with --memory-limit for the tiled one) in a process of its own
under /usr/bin/time -v: its peak memory is that process's maximum resident set, its time the command's own
(after the interpreter and Blender's module have loaded). Then:

* ``--compare 5M``: the whole run and the tiled run on the same file; the largest difference of their
  positions over the bounding-box diagonal, whether the files are byte for byte the same, and the time
  per vertex of each (medians of ``--repeats``).
* ``--jobs 2`` (with ``--compare``): the tiled run again with its tiles on a LocalCluster of that many
  workers (cli/batch.py): whether its file is the serial tiled run's, and its time against that run's.
* ``--big 30M``: the tiled run alone within ``--memory-limit`` (the whole run would not fit beside the
  other work on this machine); its peak memory and time per vertex.
* ``--obj 2M``: the same torus as an OBJ file (`v` lines of six decimals, a `vn` per vertex, faces
  `a//a b//b c//c`), run whole and tiled within ``--obj-limit``, as ``--compare`` does (its own report,
  bench_tiled_obj).

The generated files are deleted afterwards (they take about 30 bytes per vertex, twice: input and output).

    .envs/bench/bin/python bench/run.py tiled --compare 5M --compare-limit 2G --repeats 3
    .envs/bench/bin/python bench/run.py tiled --compare 5M --compare-limit 1G --jobs 2 --repeats 1
    .envs/bench/bin/python bench/run.py tiled --big 30M --memory-limit 4G --big-repeats 1
    .envs/bpy45/bin/python bench/run.py tiled --obj 2M --obj-limit 1G --repeats 3
"""

import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile

import numpy as np

from bench.common import ROOT, Parameter, count, repeats

RATIO, MINOR = 2.5, 0.4  # as bench/meshes.torus
VERTEX = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("red", "u1"), ("green", "u1"), ("blue", "u1")])
FACE = np.dtype([("count", "u1"), ("corners", "<i4", (3,))])
ROWS = 256  # torus rows (around the axis) per block written
WHOLE = "1000G"
AUTO = "auto"  # --iterations: leave the amount to the Automatic Amount  # the --memory-limit of an OBJ's whole run


def torus_rows(vertices, noise, seed):
    """(rows, tube, blocks): the noisy torus of about ``vertices`` vertices, ``blocks`` yielding (first row, points
    (m, 3), normals (m, 3)) of ROWS rows at a time, and its faces' blocks (``torus_faces``)."""
    tube = max(3, int(round(np.sqrt(vertices / RATIO))))
    rows = max(3, int(round(vertices / tube)))
    edge = 2 * np.pi * MINOR / tube
    v = np.linspace(0.0, 2.0 * np.pi, tube, endpoint=False)[None, :]
    rng = np.random.default_rng(seed)

    def blocks():
        for first in range(0, rows, ROWS):
            u = (2.0 * np.pi * np.arange(first, min(first + ROWS, rows)) / rows)[:, None]
            ring = RATIO * MINOR + MINOR * np.cos(v)
            points = np.stack(np.broadcast_arrays(ring * np.cos(u), ring * np.sin(u), MINOR * np.sin(v)), -1)
            normals = np.stack(np.broadcast_arrays(np.cos(u) * np.cos(v), np.sin(u) * np.cos(v), np.sin(v)), -1)
            yield points.reshape(-1, 3) + rng.normal(0.0, noise * edge, (points.size // 3, 3)), normals.reshape(-1, 3)

    return rows, tube, blocks()


def torus_faces(rows, tube):
    """The torus's triangles, ROWS rows at a time."""
    for first in range(0, rows, ROWS):
        i, j = np.meshgrid(np.arange(first, min(first + ROWS, rows)), np.arange(tube), indexing="ij")
        a, b = i * tube + j, ((i + 1) % rows) * tube + j
        c, d = ((i + 1) % rows) * tube + (j + 1) % tube, i * tube + (j + 1) % tube
        yield np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])


def write_torus_obj(path, vertices, noise=0.2, seed=0):
    """The noisy torus of ``write_torus`` as OBJ text: `v` (six decimals), then `vn`, then `f a//a b//b c//c`;
    returns the vertex count."""
    rows, tube, blocks = torus_rows(vertices, noise, seed)
    normals = []
    with open(path, "w") as file:
        file.write("# noisy torus of bench_tiled.py\n")
        for points, unit in blocks:
            file.write("".join("v %.6f %.6f %.6f\n" % tuple(row) for row in points.tolist()))
            normals.append(unit.astype(np.float32))
        for unit in normals:
            file.write("".join("vn %.4f %.4f %.4f\n" % tuple(row) for row in unit.tolist()))
        for triangles in torus_faces(rows, tube):
            file.write("".join("f %d//%d %d//%d %d//%d\n" % (a, a, b, b, c, c) for a, b, c in (triangles + 1).tolist()))
    return rows * tube


def write_torus(path, vertices, noise=0.2, seed=0):
    """A noisy torus of about ``vertices`` vertices as binary PLY (noise: Gaussian, ``noise`` x the edge length
    per coordinate); returns (vertex count, face count)."""
    rows, tube, blocks = torus_rows(vertices, noise, seed)
    n, faces = rows * tube, 2 * rows * tube
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment noisy torus of bench_tiled.py\n"
        f"element vertex {n}\nproperty float x\nproperty float y\nproperty float z\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\n"
        f"element face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    with open(path, "wb") as file:
        file.write(header.encode())
        for points, _ in blocks:
            records = np.zeros(len(points), VERTEX)
            records["x"], records["y"], records["z"] = points.T
            records["red"] = np.arange(len(points)) % 251
            file.write(records.tobytes())
        for triangles in torus_faces(rows, tube):
            records = np.zeros(len(triangles), FACE)
            records["count"], records["corners"] = 3, triangles
            file.write(records.tobytes())
    return n, faces


CHILD = """
import importlib, importlib.machinery, importlib.util, sys, time
package = importlib.util.module_from_spec(importlib.machinery.ModuleSpec("hc_smooth", None, is_package=True))
package.__path__ = [sys.argv[1]]
sys.modules["hc_smooth"] = package
command = importlib.import_module("hc_smooth.cli.command")
start = time.perf_counter()
status = command.main(sys.argv[2:])
print(f"command seconds: {time.perf_counter() - start:.3f}", flush=True)
sys.exit(status)
"""


def command_run(source, folder, iterations, limit=None, jobs=1):
    """(seconds of the command, peak resident memory in bytes, its output) of one command-line run; with
    ``jobs`` > 1 its tiles run on a LocalCluster of that many workers (peak: the largest process's)."""
    shutil.rmtree(folder, ignore_errors=True)
    argv = [source, "-o", folder] + ([] if iterations == AUTO else ["--iterations", str(iterations)])
    argv += ["--memory-limit", limit] if limit else []
    argv += ["--jobs", str(jobs)] if jobs > 1 else []
    done = subprocess.run(
        ["/usr/bin/time", "-v", sys.executable, "-c", CHILD, str(ROOT), *argv], capture_output=True, text=True
    )
    if done.returncode:
        raise SystemExit(f"the run failed:\n{done.stdout}\n{done.stderr}")
    seconds = float(re.search(r"command seconds: ([0-9.]+)", done.stdout).group(1))
    peak = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", done.stderr).group(1)) * 1024
    tiles = re.search(r"smoothed in (\d+) tiles of at most (\d+) vertices .*, ([0-9.]+) s$", done.stdout, re.M)
    return seconds, peak, tiles.groups() if tiles else None  # (tiles, largest, the tiled run's own seconds)


def positions(path):
    """(n, 3) float64 positions of a file written by ``write_torus`` (or its smoothed copy), read in blocks."""
    with open(path, "rb") as file:
        head = file.read(1 << 12)
    body = head.index(b"end_header\n") + len(b"end_header\n")
    n = int(re.search(rb"element vertex (\d+)", head).group(1))
    records = np.memmap(path, dtype=VERTEX, mode="r", offset=body, shape=(n,))
    out = np.empty((n, 3))
    for start in range(0, n, 1 << 22):
        block = records[start : start + (1 << 22)]
        out[start : start + len(block)] = np.stack([block["x"], block["y"], block["z"]], 1)
    return out


def same_bytes(a, b):
    with open(a, "rb") as one, open(b, "rb") as two:
        while True:
            x, y = one.read(1 << 24), two.read(1 << 24)
            if x != y:
                return False
            if not x:
                return True


def _iterations(text):
    return AUTO if str(text).strip().lower() == AUTO else int(text)


PARAMETERS = (
    Parameter("compare", None, "vertices of the mesh run whole and tiled", count),
    Parameter("big", None, "vertices of the mesh run tiled only", count),
    Parameter("obj", None, "vertices of the OBJ file run whole and tiled (its own report)", count),
    Parameter("obj_limit", "1G", "the --obj tiled run's --memory-limit"),
    Parameter("memory_limit", "4G", "the --big run's --memory-limit"),
    Parameter("compare_limit", "2G", "the --compare tiled run's --memory-limit"),
    Parameter(
        "iterations", 10, f"HC iterations, or {AUTO!r}: the Automatic Amount (report bench_tiled_auto)", _iterations
    ),
    repeats(3, "runs of each kind in --compare (medians)"),
    Parameter("big_repeats", 1, "runs of --big (median)"),
    Parameter("folder", None, "where the files go (default: a temporary folder)"),
    Parameter("jobs", 1, "--compare: also run the tiled file with --jobs N (its tiles on N local workers)", int),
)
QUICK = {"compare": "200k", "compare_limit": "380M", "iterations": 2, "repeats": 1}


def report_name(args):
    return "bench_tiled_obj" if args.obj else "bench_tiled_auto" if args.iterations == AUTO else "bench_tiled"


def run(args, out):
    folder = tempfile.mkdtemp(prefix="bench_tiled_", dir=args.folder)
    try:
        amount = f"{args.iterations} iterations"
        if args.iterations == AUTO:
            amount = "the Automatic Amount (closed parts given their volume back)"
        out(f"Noisy torus (noise 0.2 edge lengths), {amount}.")
        out()
        if args.obj:
            obj(args, folder, out)
            return out.rows
        whole = compare(args, folder, out) if args.compare else None
        if args.big:
            big(args, folder, out, whole)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return out.rows


def header(out):
    return out.table("run", "vertices", "tiles (largest)", "time", "time per vertex", "peak memory")


def row(table, label, n, seconds, peak, tiles):
    tiles = f"{tiles[0]} ({int(tiles[1]):,})" if tiles else "-"
    table.row(label, f"{n:,}", tiles, f"{seconds:.1f} s", f"{seconds / n * 1e6:.2f} us", f"{peak / 2**30:.2f} GiB")


def whole_and_tiled(args, source, folder, n, table, whole_limit, limit):
    """((median seconds, peak bytes) of the whole runs, the same of the tiled runs, the tiled runs) of
    ``source``, --repeats of each, into subfolders whole/ and tiled/ of ``folder``, each a row of ``table``;
    the whole runs with ``whole_limit`` (None: the default) must not go in tiles."""
    whole = [
        command_run(source, os.path.join(folder, "whole"), args.iterations, whole_limit) for _ in range(args.repeats)
    ]
    if any(r[2] for r in whole):
        raise SystemExit("the whole run went in tiles")
    tiled = [command_run(source, os.path.join(folder, "tiled"), args.iterations, limit) for _ in range(args.repeats)]
    figures = [(statistics.median(r[0] for r in runs), max(r[1] for r in runs)) for runs in (whole, tiled)]
    row(table, "whole", n, *figures[0], None)
    row(table, f"tiled, --memory-limit {limit}", n, *figures[1], tiled[0][2])
    return (*figures, tiled)


def compare(args, folder, out):
    source = os.path.join(folder, "compare.ply")
    n, _ = write_torus(source, args.compare)
    table = header(out)
    (time_whole, _), (time_tiled, _), tiled_runs = whole_and_tiled(
        args, source, folder, n, table, None, args.compare_limit
    )
    a, b = os.path.join(folder, "whole", "compare.ply"), os.path.join(folder, "tiled", "compare.ply")
    words = spread(args, source, folder, n, table, b, tiled_runs) if args.jobs > 1 else None
    one, two = positions(a), positions(b)
    diagonal = float(np.linalg.norm(one.max(axis=0) - one.min(axis=0)))
    difference = float(np.abs(one - two).max()) / diagonal
    out()
    out(
        f"Tiled against whole at {n:,} vertices: largest difference {difference:.3g} of the diagonal; files "
        f"{'byte for byte the same' if same_bytes(a, b) else 'differ'}; time per vertex "
        f"{time_tiled / time_whole:.2f}x the whole run's (medians of {args.repeats})."
    )
    out()
    if words:
        out(words)
        out()
    for path in (source, a, b):
        os.remove(path)
    return time_whole / n


def spread(args, source, folder, n, table, tiled, serial):
    """The tiled run again with --jobs (its tiles on a LocalCluster's workers, the cluster's start included),
    a row of ``table``, against the serial tiled run's file ``tiled`` and its runs ``serial`` (command_run's);
    returns the sentence that says how it compares."""
    time_tiled = statistics.median(r[0] for r in serial)
    there = os.path.join(folder, "jobs")
    runs = [command_run(source, there, args.iterations, args.compare_limit, args.jobs) for _ in range(args.repeats)]
    seconds, peak = statistics.median(r[0] for r in runs), max(r[1] for r in runs)
    row(table, f"tiled, --memory-limit {args.compare_limit}, --jobs {args.jobs}", n, seconds, peak, runs[0][2])
    result = os.path.join(there, os.path.basename(source))
    same = same_bytes(result, tiled)
    os.remove(result)
    phase = statistics.median(float(r[2][2]) for r in runs) / statistics.median(float(r[2][2]) for r in serial)
    return (
        f"Tiles on {args.jobs} workers (--jobs {args.jobs}): files {'byte for byte the same' if same else 'differ'} "
        f"as the serial tiled run's; time {seconds / time_tiled:.2f}x its with the cluster's start, the tiled run "
        f"itself (its reading, tiles and writing) {phase:.2f}x (medians of {args.repeats}); peak memory: the "
        "largest process's."
    )


def big(args, folder, out, whole):
    """The --big run; ``whole``: the --compare whole run's seconds per vertex, if it ran."""
    source = os.path.join(folder, "big.ply")
    n, _ = write_torus(source, args.big)
    table = header(out)
    limit = args.memory_limit
    runs = [command_run(source, os.path.join(folder, "big"), args.iterations, limit) for _ in range(args.big_repeats)]
    seconds, peak = statistics.median(r[0] for r in runs), max(r[1] for r in runs)
    row(table, f"tiled, --memory-limit {limit}", n, seconds, peak, runs[0][2])
    out()
    words = f"{n:,} vertices tiled within --memory-limit {limit}: peak memory {peak / 2**30:.2f} GiB"
    if whole:
        words += f", time per vertex {seconds / n / whole:.2f}x the whole run's at {args.compare:,} vertices"
    out(words + ".")


def obj(args, folder, out):
    """The --obj runs: whole and tiled on one OBJ file, medians of --repeats; whether the files are the same."""
    source = os.path.join(folder, "scan.obj")
    n = write_torus_obj(source, args.obj)
    out(f"OBJ file of {n:,} vertices, {os.path.getsize(source) / 2**20:.0f} MB.")
    out()
    table = header(out)
    # The whole run with a limit above its need: by the estimate (a vertex per 12 bytes of text) the default
    # limit would send a large OBJ into tiles.
    (time_whole, peak_whole), (time_tiled, peak_tiled), _ = whole_and_tiled(
        args, source, folder, n, table, WHOLE, args.obj_limit
    )
    a, b = os.path.join(folder, "whole", "scan.obj"), os.path.join(folder, "tiled", "scan.obj")
    out()
    out(
        f"Tiled against whole at {n:,} vertices (OBJ): files "
        f"{'byte for byte the same' if same_bytes(a, b) else 'differ'}; "
        f"time per vertex {time_tiled / time_whole:.2f}x the whole run's, peak memory "
        f"{peak_tiled / peak_whole:.2f}x (medians of {args.repeats})."
    )
