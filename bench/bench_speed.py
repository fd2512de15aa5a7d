"""Speed at a million: the four comparisons a user feels, each against its peer in the same run, one table.

    .envs/bench/bin/python bench/run.py speed                  # 1M, medians of 3 (~15-25 min on 2 cores)
    .envs/bench/bin/python bench/run.py speed --quick          # 5k, one repeat, Blender 4.5 only

1. Object mode, explicit numbers (10 HC iterations): object.hc_smooth end to end against Blender's Smooth
   modifier (factor 0.5, 10 repeats) on a closed triangulated torus, in Blender 4.5 and 5.2
   (bench_speed_blender.py, run in .envs/bpy45 and .envs/bpy52).
2. Keep Sharp Edges (``core.smooth_mesh(..., keep_sharp_edges=True)``, its Automatic Amount) against HC's
   default (``core.smooth_mesh`` with nothing set) on the same noisy torus (noise 0.1 % of the diagonal,
   float32 as Blender hands it over, faces given).
3. Point clouds: ``core.smooth_point_cloud`` at its defaults against CGAL's jet smoothing (k 24), the
   insertion into CGAL's point set included (reading the points back is not), on a noisy sphere
   (bench_points: σ 0.5 % of the diagonal, float32).
4. The default against the fixed 10-iteration HC run (alpha 0.1, beta 0.6) on the torus of 2. Its choosing
   alone: ``core.AmountChooser`` on the same mesh (the noise estimate and the iteration choice, without the
   run's welding check, volume restore and Keep in Place), given the umbrella operator the run builds for
   the smoothing anyway (what the choosing adds to a run), and with an operator of its own built in the
   timing. The split inside the default's own run (set-up and choosing, then the iterations chosen and what
   follows) is read from its report where core gives it (``choosing_seconds``), else "–".

Every figure is a median of --repeats runs, alternating within a comparison so both sides see the same load.
"""

import pathlib
import statistics
import subprocess
import tempfile
import time
import warnings

import numpy as np

import core
from bench import bench_points, meshes, report
from bench.common import ROOT, Parameter, repeats, sizes

PARAMETERS = (
    sizes("1M", "vertices and points, comma-separated"),
    repeats(3),
    Parameter("blenders", "bpy45,bpy52", "the environments in .envs/ whose Blender runs comparison 1"),
    Parameter("only", "", "only these comparisons: blender, sharp, points, default (default all)"),
)
QUICK = {"sizes": "5k", "repeats": 1, "blenders": "bpy45"}
FIXED = dict(alpha=0.1, beta=0.6, iterations=10)


def alternating(runs, repeats):
    """{name: median seconds, ...} of ``runs`` (name -> function returning its result), taken in turn;
    the last result of each under ``(name, "result")``."""
    times, results = {name: [] for name in runs}, {}
    for _ in range(repeats):
        for name, function in runs.items():
            start = time.perf_counter()
            results[name] = function()
            times[name].append(time.perf_counter() - start)
    return {name: statistics.median(values) for name, values in times.items()}, results


def noisy_torus(size):
    vertices, faces = meshes.torus(size)
    noisy = meshes.add_noise(vertices, 0.001, seed=1).astype(np.float32)
    return noisy, meshes.edges_from_faces(faces), faces


def blender_rows(size, repeats, environment):
    """bench_speed_blender's rows from the Blender of ``.envs/<environment>``."""
    python = ROOT / ".envs" / environment / "bin" / "python"
    with tempfile.TemporaryDirectory() as folder:
        command = [str(python), str(ROOT / "bench" / "run.py"), "speed_blender", "--sizes", str(size)]
        command += ["--repeats", str(repeats), "--output", folder]
        subprocess.run(command, check=True, capture_output=True, timeout=3600)
        (path,) = pathlib.Path(folder).glob("bench_speed_blender_*-*.md")
        return report.read_rows(path)


def cgal_jet_with_insertion(points, k=24):
    from CGAL import CGAL_Point_set_processing_3 as processing

    point_set = bench_points._cgal_point_set(points)
    processing.jet_smooth_point_set(point_set, k)
    return point_set


def run(args, out):
    only = set(args.only.split(",")) - {""} or {"blender", "sharp", "points", "default"}
    table = out.table("comparison", "size", "ours (s)", "peer", "peer (s)", "ratio", "notes", align="lrrlrrl")
    for size in args.sizes:
        if "blender" in only:
            for environment in args.blenders.split(","):
                for row in blender_rows(size, args.repeats, environment):
                    table.row(
                        "Object mode, 10 iterations",
                        f"{row['vertices']:,}",
                        row["object.hc_smooth (s)"],
                        f"Smooth modifier, Blender {row['Blender']}",
                        row["Smooth modifier (s)"],
                        row["ratio"],
                        "closed triangulated torus, end to end",
                    )
        noisy, edges, faces = noisy_torus(size)
        if "sharp" in only:
            sharp_row(table, noisy, edges, faces, args.repeats)
        if "points" in only:
            points_row(table, size, args.repeats)
        if "default" in only:
            default_row(table, noisy, edges, faces, args.repeats)
    return out.rows


def sharp_row(table, noisy, edges, faces, repeats):
    """Keep Sharp Edges against HC's default on the same mesh."""
    medians, results = alternating(
        {
            "sharp": lambda: core.smooth_mesh(noisy, edges, faces=faces, keep_sharp_edges=True, return_report=True),
            "default": lambda: core.smooth_mesh(noisy, edges, faces=faces, return_report=True),
        },
        repeats,
    )
    table.row(
        "Keep Sharp Edges",
        f"{len(noisy):,}",
        f"{medians['sharp']:.3f}",
        "HC's default, same mesh",
        f"{medians['default']:.3f}",
        f"{medians['sharp'] / medians['default']:.2f}×",
        f"{results['sharp'][1].iterations} steps; default {results['default'][1].iterations} iterations",
    )


def points_row(table, size, repeats):
    """core.smooth_point_cloud against CGAL jet on a noisy sphere."""
    points, _ = bench_points.noisy("sphere", size, 0.005, seed=0)
    points = points.astype(np.float32)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)
        medians, _ = alternating(
            {"ours": lambda: core.smooth_point_cloud(points), "jet": lambda: cgal_jet_with_insertion(points)},
            repeats,
        )
    table.row(
        "Point cloud",
        f"{len(points):,}",
        f"{medians['ours']:.3f}",
        "CGAL jet (k 24), insertion included",
        f"{medians['jet']:.3f}",
        f"{medians['ours'] / medians['jet']:.2f}×",
        "noisy sphere, σ 0.5 %",
    )


def default_row(table, noisy, edges, faces, repeats):
    """The default against the fixed run, its choosing alone beside it."""

    operator = core.umbrella_operator(edges, len(noisy))

    def choose(**given):
        chooser = core.AmountChooser(noisy, **given)
        for _ in chooser.steps():
            pass
        return chooser.amount

    medians, results = alternating(
        {
            "default": lambda: core.smooth_mesh(noisy, edges, faces=faces, return_report=True),
            "fixed": lambda: core.smooth_mesh(noisy, edges, faces=faces, return_report=True, **FIXED),
            "choose": lambda: choose(operator=operator),
            "choose_built": lambda: choose(edges=edges),
        },
        repeats,
    )
    report = results["default"][1]
    inside = getattr(report, "choosing_seconds", None)
    split = "–" if inside is None else f"{inside:.2f} s choosing + {report.seconds - inside:.2f} s"
    table.row(
        "The default (Automatic Amount)",
        f"{len(noisy):,}",
        f"{medians['default']:.3f}",
        "fixed 10 iterations (α 0.1, β 0.6)",
        f"{medians['fixed']:.3f}",
        f"{medians['default'] / medians['fixed']:.2f}×",
        f"{report.iterations} iterations; choosing alone (AmountChooser, the run's operator given) "
        f"{medians['choose']:.3f} s = {medians['choose'] / medians['fixed']:.2f}× the fixed run (its own operator "
        f"built: {medians['choose_built']:.3f} s = {medians['choose_built'] / medians['fixed']:.2f}×); "
        f"split in the run: {split}",
    )
