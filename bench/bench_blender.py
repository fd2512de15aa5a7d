"""End-to-end speed of the installed operators against Blender's own smoothing, in one run.

    .envs/bpy45/bin/python bench/bench_blender.py [--size 1000] [--torus 1M] [--repeats 3]

On a noisy grid of (size+1)² vertices (1000 → 1,002,001 vertices, 2M faces) it times, median of
--repeats runs, 10 iterations each:
  - object.hc_smooth in Object mode, end to end (read, build the operator, smooth, write, report);
  - the same with a vertex group of fixed vertices (30 % of the vertices), and the group read alone;
  - Blender's Smooth modifier (factor 0.5, 10 repeats), the time to evaluate it;
  - Blender's Smooth Vertices operator (mesh.vertices_smooth, repeat=10) in Edit mode, all selected;
  - mesh.hc_smooth in Edit mode with everything selected, end to end (from Edit mode back to Edit mode).
Then, on closed triangulated tori of --torus vertices (what photogrammetry and Poisson reconstruction
produce), once in grid order and once numbered at random, it times object.hc_smooth end to end, the
report alone (measuring the change: the enclosed volume before and after), the Smooth modifier and
mesh.hc_smooth in Edit mode (its first call, and the median). It prints markdown tables and the
ratios set as targets. Run it with either test environment (Blender 4.5 or 5.2 as the bpy module);
it installs the extension itself.
"""

import argparse
import pathlib
import platform
import statistics
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "scripts")]

from extension_session import ADDON, install_extension, run_and_exit  # noqa: E402  (before bpy)

import bpy  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(ROOT / "bench"))
import meshes  # noqa: E402

ITERATIONS = 10


def median_time(run, repeats, setup=None):
    times = []
    for _ in range(repeats):
        if setup is not None:
            setup()
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def noisy_grid(size, seed=0):
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=size, y_subdivisions=size, size=2.0)
    obj = bpy.context.active_object
    mesh = obj.data
    points = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.attributes["position"].data.foreach_get("vector", points)
    points = points.reshape(-1, 3)
    points[:, 2] += np.random.default_rng(seed).normal(0.0, 0.5 / size, len(points)).astype(np.float32)
    mesh.attributes["position"].data.foreach_set("vector", points.ravel())
    mesh.update()
    return obj, points.copy()


def closed_torus(n_vertices, shuffle, seed=0):
    """A noisy closed triangle torus as a mesh object, built in bulk (foreach_set, no Python loops)."""
    vertices, faces = meshes.torus(n_vertices)
    if shuffle:
        vertices, faces = meshes.shuffled(vertices, faces, seed=seed)
    diagonal = np.linalg.norm(np.ptp(vertices, axis=0))
    vertices = vertices + np.random.default_rng(seed).normal(0.0, 0.002 * diagonal, vertices.shape)
    mesh = bpy.data.meshes.new("Torus")
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set("co", vertices.astype(np.float32).ravel())
    mesh.loops.add(faces.size)
    mesh.loops.foreach_set("vertex_index", faces.astype(np.int32).ravel())
    mesh.polygons.add(len(faces))
    mesh.polygons.foreach_set("loop_start", np.arange(0, faces.size, 3, dtype=np.int32))
    mesh.update(calc_edges=True)
    obj = bpy.data.objects.new("Scan", mesh)
    bpy.context.scene.collection.objects.link(obj)
    for other in bpy.context.scene.objects:
        other.select_set(other == obj)
    bpy.context.view_layer.objects.active = obj
    return obj, vertices.astype(np.float32)


def bench_closed(n_vertices, shuffle, repeats):
    """Object mode end to end, the report alone, the Smooth modifier and Edit mode on a closed torus."""
    jobs = sys.modules[ADDON + ".operators.jobs"]
    bpy.ops.wm.read_homefile(use_empty=True)
    obj, original = closed_torus(n_vertices, shuffle)
    reset = lambda: restore(obj, original)  # noqa: E731
    times = {}

    def hc_object():
        assert bpy.ops.object.hc_smooth(iterations=ITERATIONS) == {"FINISHED"}

    times["object"] = median_time(hc_object, repeats, reset)
    reset()
    props = sys.modules[ADDON + ".cli.arguments"].Settings(iterations=ITERATIONS)  # the declared defaults
    (job,) = [jobs.make_job(obj, props)]
    list(jobs.run([job], props))

    def report():
        job.change = None
        jobs.summary([job], props)

    times["report"] = median_time(report, repeats)
    assert job.change.volume_change is not None  # the report measured a volume: the torus is closed
    modifier = obj.modifiers.new("Smooth", "SMOOTH")
    modifier.factor, modifier.iterations = 0.5, ITERATIONS
    depsgraph = bpy.context.evaluated_depsgraph_get()

    def evaluate_modifier():
        obj.update_tag(refresh={"DATA"})
        depsgraph.update()
        obj.evaluated_get(depsgraph).data  # noqa: B018 - the evaluated mesh is the product

    evaluate_modifier()
    times["modifier"] = median_time(evaluate_modifier, repeats)
    obj.modifiers.remove(modifier)

    def enter_edit_mode_all_selected():
        reset()
        bpy.ops.object.mode_set(mode="EDIT")
        bpy.ops.mesh.select_all(action="SELECT")

    def hc_edit():
        assert bpy.ops.mesh.hc_smooth(iterations=ITERATIONS) == {"FINISHED"}

    enter_edit_mode_all_selected()
    start = time.perf_counter()
    hc_edit()
    times["edit first"] = time.perf_counter() - start
    times["edit"] = median_time(hc_edit, repeats, enter_edit_mode_all_selected)
    reset()
    return times


def restore(obj, points):
    if obj.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")
    obj.data.attributes["position"].data.foreach_set("vector", points.ravel())
    obj.data.update()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=1000, help="grid subdivisions per side")
    parser.add_argument("--torus", type=lambda text: int(float(text.upper().replace("M", "e6").replace("K", "e3"))),
                        default=1_000_000, help="vertices of the closed triangle tori (1M; 0 skips them)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    install_extension(ROOT / "build" / "bench")
    mesh_io = sys.modules[ADDON + ".operators.mesh_io"]

    bpy.ops.wm.read_homefile(use_empty=True)
    obj, original = noisy_grid(args.size)
    n = len(obj.data.vertices)
    group = obj.vertex_groups.new(name="Fixed")
    members = np.flatnonzero(np.random.default_rng(1).random(n) < 0.3)
    group.add(members.tolist(), 1.0, "REPLACE")
    reset = lambda: restore(obj, original)  # noqa: E731
    repeats = args.repeats
    rows = []

    def hc_object(**extra):
        assert bpy.ops.object.hc_smooth(iterations=ITERATIONS, **extra) == {"FINISHED"}

    rows.append(("object.hc_smooth (Object mode, HC, simultaneous)", median_time(hc_object, repeats, reset)))
    rows.append(("object.hc_smooth, sequential", median_time(lambda: hc_object(mode="SEQUENTIAL"), repeats, reset)))
    rows.append(("object.hc_smooth with a fixed vertex group (30 %)",
                 median_time(lambda: hc_object(vertex_group="Fixed"), repeats, reset)))
    rows.append(("  vertex group read alone (bulk path)",
                 median_time(lambda: mesh_io.vertex_group_members(obj, group.index), repeats)))
    rows.append(("  vertex group read alone (per-vertex loop)",
                 median_time(lambda: mesh_io._vertex_group_weights_loop(obj.data, group.index), 1)))

    reset()
    modifier = obj.modifiers.new("Smooth", "SMOOTH")
    modifier.factor, modifier.iterations = 0.5, ITERATIONS
    depsgraph = bpy.context.evaluated_depsgraph_get()

    def evaluate_modifier():
        obj.update_tag(refresh={"DATA"})
        depsgraph.update()
        obj.evaluated_get(depsgraph).data  # noqa: B018 - the evaluated mesh is the product

    evaluate_modifier()
    rows.append(("Smooth modifier (10 repeats, evaluated)", median_time(evaluate_modifier, repeats)))
    obj.modifiers.remove(modifier)

    def enter_edit_mode_all_selected():
        reset()
        bpy.ops.object.mode_set(mode="EDIT")
        bpy.ops.mesh.select_all(action="SELECT")

    rows.append(("mesh.vertices_smooth (Smooth Vertices, repeat=10, Edit mode)",
                 median_time(lambda: bpy.ops.mesh.vertices_smooth(factor=0.5, repeat=ITERATIONS), repeats,
                             enter_edit_mode_all_selected)))

    def hc_edit():
        assert bpy.ops.mesh.hc_smooth(iterations=ITERATIONS) == {"FINISHED"}
        assert obj.mode == "EDIT"

    rows.append(("mesh.hc_smooth (Edit mode, all selected, end to end)",
                 median_time(hc_edit, repeats, enter_edit_mode_all_selected)))
    reset()

    times = dict(rows)
    hc = times["object.hc_smooth (Object mode, HC, simultaneous)"]
    print(f"\n# HC Smooth in Blender {bpy.app.version_string}, {platform.python_version()}, {n:,} vertices, "
          f"{len(obj.data.polygons):,} faces, {ITERATIONS} iterations, median of {repeats}\n")
    print("| what | median time (s) |\n|---|---:|")
    for name, seconds in rows:
        print(f"| {name} | {seconds:.3f} |")
    modifier_time = times["Smooth modifier (10 repeats, evaluated)"]
    vertices_smooth = times["mesh.vertices_smooth (Smooth Vertices, repeat=10, Edit mode)"]
    edit = times["mesh.hc_smooth (Edit mode, all selected, end to end)"]
    group_read = times["  vertex group read alone (bulk path)"]
    with_group = times["object.hc_smooth with a fixed vertex group (30 %)"]
    checks = [
        ("Object mode HC / Smooth modifier", f"{hc / modifier_time:.2f}×", "≤ 2×", hc <= 2 * modifier_time),
        ("Smooth Vertices / Object mode HC", f"{vertices_smooth / hc:.2f}×", "≥ 5×", vertices_smooth >= 5 * hc),
        ("Edit mode HC, end to end", f"{edit:.2f} s", "≤ 2.5 s", edit <= 2.5),
        ("vertex group read / run with the group", f"{group_read / with_group:.1%}", "not dominant",
         group_read < 0.25 * with_group),
    ]
    print("\n| check | value | target | |\n|---|---:|---:|---|")
    for name, value, target, ok in checks:
        print(f"| {name} | {value} | {target} | {'ok' if ok else 'MISSED'} |")
    if args.torus:
        closed_tables(args.torus, repeats)


def closed_tables(n_vertices, repeats):
    results = {order: bench_closed(n_vertices, order == "random order", repeats)
               for order in ("grid order", "random order")}
    print(f"\n# Closed triangle torus, {n_vertices:,} vertices, {ITERATIONS} iterations, median of {repeats}\n")
    print("| vertex order | object.hc_smooth | report (volume before/after) | Smooth modifier "
          "| Edit mode, first call | Edit mode |\n|---|---:|---:|---:|---:|---:|")
    for order, times in results.items():
        print(f"| {order} | {times['object']:.3f} s | {times['report']:.3f} s | {times['modifier']:.3f} s "
              f"| {times['edit first']:.2f} s | {times['edit']:.2f} s |")
    print("\n| check | value | target | |\n|---|---:|---:|---|")
    for order, times in results.items():
        ratio, share = times["object"] / times["modifier"], times["report"] / times["object"]
        for name, value, target, ok in (
                (f"{order}: Object mode HC / Smooth modifier", f"{ratio:.2f}×", "≤ 2×", ratio <= 2),
                (f"{order}: report / Object mode run", f"{share:.1%}", "≤ 10 %", share <= 0.1),
                (f"{order}: Edit mode, first call", f"{times['edit first']:.2f} s", "≤ 2.5 s",
                 times["edit first"] <= 2.5)):
            print(f"| {name} | {value} | {target} | {'ok' if ok else 'MISSED'} |")


if __name__ == "__main__":
    run_and_exit(main)
