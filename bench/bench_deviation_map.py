"""What the Deviation Map costs: object.hc_smooth with and without it on a big noisy scan, in one run.

    .envs/bpy45/bin/python bench/run.py deviation_map [--vertices 1M] [--repeats 5]

On a closed noisy triangle torus (isotropic noise of 0.2 % of the bounding-box diagonal, as bench_blender.py
makes it) it times object.hc_smooth end to end (read, smooth, write, report) with Deviation Map off and on,
alternating, median of --repeats runs each: at the add-on's default (Automatic Amount) and at 10 fixed
iterations (the cheaper run, so the larger share). Between runs the positions are put back and the map's
attributes removed. Then the map's own parts, median of --repeats: core.deviation_map on the run's arrays
(with the normals the report measured) and the two attributes written (operators/mesh_io.write_deviation).
Target: the map costs at most 10 % of the run. Last, the HC Smooth modifier (HC, 10 iterations) with its
Deviation Map input off and on: one evaluation through the depsgraph each, alternating, median of --repeats.
Installs the extension itself; runs with either test environment (Blender 4.5 or 5.2 as the bpy module).
"""

import platform
import statistics
import sys
import time

from scripts.extension_session import ADDON, install_extension  # before bpy

# isort: split

import bpy

from bench.bench_blender import closed_torus  # a noisy torus, as the other Blender benchmarks use
from bench.common import ROOT, Parameter, count, repeats

TARGET = 0.10  # the map's cost, a share of the run without it


def restore(obj, points, mesh_io):
    """The input again: its positions, without the map's attributes."""
    mesh = obj.data
    for name in (mesh_io.DEVIATION_ATTRIBUTE, mesh_io.DEVIATION_COLOR_ATTRIBUTE):
        if mesh.attributes.get(name) is not None:
            mesh.attributes.remove(mesh.attributes[name])
    mesh.attributes["position"].data.foreach_set("vector", points.ravel())
    mesh.update()


def alternating(runs, repeats, setup):
    """{name: median seconds} of each run, the runs taken in turn ``repeats`` times (after one warm-up each)."""
    times = {name: [] for name in runs}
    for round_ in range(repeats + 1):
        for name, run in runs.items():
            setup()
            start = time.perf_counter()
            run()
            if round_:
                times[name].append(time.perf_counter() - start)
    return {name: statistics.median(values) for name, values in times.items()}


PARAMETERS = (Parameter("vertices", "1M", "torus vertices, e.g. 1M, 250k", count), repeats(5))
QUICK = {"vertices": "2k", "repeats": 1}


def run(args, out):
    install_extension(ROOT / "build" / "bench")
    jobs, mesh_objects = sys.modules[ADDON + ".jobs.mesh"], sys.modules[ADDON + ".operators.mesh_objects"]
    mesh_io = sys.modules[ADDON + ".operators.mesh_io"]
    core = sys.modules[ADDON + ".core"]
    bpy.ops.wm.read_homefile(use_empty=True)
    obj, points = closed_torus(args.vertices, shuffle=False)
    n = len(points)

    def reset():
        restore(obj, points, mesh_io)

    def smooth(**settings):
        return lambda: bpy.ops.object.hc_smooth(**settings)

    configurations = {"Automatic Amount (default)": {}, "10 iterations": dict(auto_amount=False, iterations=10)}
    rows = []
    for label, settings in configurations.items():
        medians = alternating(
            {"off": smooth(**settings), "on": smooth(deviation_map=True, **settings)}, args.repeats, reset
        )
        rows.append((label, medians["off"], medians["on"]))

    # The map's parts, on one run's arrays.
    reset()
    props = sys.modules[ADDON + ".cli.arguments"].Settings(deviation_map=True)
    (job,) = [mesh_objects.make_job(obj, props)]
    list(jobs.run([job], props))
    normals = jobs.input_measure(job).result().normals
    parts = {"core.deviation_map": [], "attributes written": []}
    for _ in range(args.repeats):
        start = time.perf_counter()
        deviation_map = core.deviation_map(job.positions, job.result, normals=normals, linear=True)
        parts["core.deviation_map"].append(time.perf_counter() - start)
        start = time.perf_counter()
        mesh_io.write_deviation(obj.data, job.map_names, deviation_map.deviation, deviation_map.colors)
        parts["attributes written"].append(time.perf_counter() - start)
    parts = {name: statistics.median(values) for name, values in parts.items()}
    reset()

    # The modifier: each evaluation from scratch (the input tagged as changed).
    inputs = sys.modules[ADDON + ".nodes.inputs"]
    assert bpy.ops.object.hc_smooth_modifier_add(iterations=10) == {"FINISHED"}
    modifier = obj.modifiers[-1]

    def evaluate(on):
        def run():
            inputs.set_input(modifier, "Deviation Map", on)
            obj.data.update_tag()
            depsgraph = bpy.context.evaluated_depsgraph_get()
            depsgraph.update()
            mesh = obj.evaluated_get(depsgraph).data
            assert (mesh.attributes.get(mesh_io.DEVIATION_ATTRIBUTE) is not None) == on

        return run

    medians = alternating({"off": evaluate(False), "on": evaluate(True)}, args.repeats, lambda: None)
    rows.append(("HC Smooth modifier, HC, 10 iterations", medians["off"], medians["on"]))
    obj.modifiers.remove(modifier)

    out("# Deviation Map cost")
    out()
    out(
        f"Blender {bpy.app.version_string}, {platform.python_implementation()} {platform.python_version()}; "
        f"closed triangle torus of {n:,} vertices, isotropic noise 0.2% of the diagonal "
        f"(bench_blender.closed_torus); object.hc_smooth end to end, median of {args.repeats} alternating runs."
    )
    out()
    table = out.table(
        "run (object.hc_smooth unless named)",
        "map off (s)",
        "map on (s)",
        "map's cost",
        "share of the run",
        align="lrrrr",
    )
    worst = 0.0
    for label, off, on in rows:
        share = (on - off) / off
        worst = max(worst, share)
        table.row(label, f"{off:.3f}", f"{on:.3f}", f"{on - off:+.3f} s", f"{share:+.1%}")
    out()
    table = out.table("part of the map", "median (s)", align="lr")
    for name, seconds in parts.items():
        table.row(name, f"{seconds:.4f}")
    fastest = min(off for _, off, _ in rows[:2])
    out()
    out(
        f"Parts together: {sum(parts.values()):.3f} s, {sum(parts.values()) / fastest:.1%} of the fastest operator "
        f"run without the map. Target: at most {TARGET:.0%} of the run: "
        + ("met" if worst <= TARGET else f"missed (up to {worst:.1%} end to end)")
        + "."
    )
    return out.rows
