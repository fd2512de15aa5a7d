"""End-to-end speed of the installed operators against Blender's own smoothing, in one run.

    .envs/bpy45/bin/python bench/run.py blender [--size 1000] [--torus 1M] [--repeats 3]
                                                [--modifier 100k,1M] [--only-modifier]

On a noisy grid of (size+1)² vertices (1000 → 1,002,001 vertices, 2M faces) it times, median of
--repeats runs, 10 iterations each:
  - object.hc_smooth in Object mode, end to end (read, build the operator, smooth, write, report);
  - the same with a vertex group of fixed vertices (30 % of the vertices), and the group read alone;
  - Blender's Smooth modifier (factor 0.5, 10 repeats), the time to evaluate it;
  - Blender's Smooth Vertices operator (mesh.vertices_smooth, repeat=10) in Edit mode, all selected;
  - mesh.hc_smooth in Edit mode with everything selected, end to end (from Edit mode back to Edit mode).
Then, on closed triangulated tori of --torus vertices (what photogrammetry and Poisson reconstruction
produce), once in grid order and once numbered at random, it times object.hc_smooth end to end, the
report after the run (the result's volume and displacements; the input's side is measured during the
run, on the core the run's single-threaded start leaves free), the Smooth modifier and mesh.hc_smooth in
Edit mode (its first call, and the median) beside Blender's own Edit → Object → Edit round trip, which
every Edit-mode tool that reads the mesh arrays pays. Then the HC Smooth modifier (the Geometry Nodes
group of nodes/hc_group.py) on closed tori of each --modifier size: its evaluation per method against the
Smooth modifier's, wall and CPU time, and what its parts cost (an umbrella step, Set Position, Blur
Attribute per call, ...; see modifier_tables). It prints markdown tables and the ratios set as targets. Run
it with either test environment (Blender 4.5 or 5.2 as the bpy module);
it installs the extension itself.
"""

import platform
import statistics
import sys
import time

from scripts.extension_session import (  # before bpy
    ADDON,
    install_extension,
)

# isort: split

import bpy
import numpy as np

from bench import meshes
from bench.common import ROOT, Parameter, count, counts, median_time, repeats

ITERATIONS = 10


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
    jobs, mesh_objects = sys.modules[ADDON + ".jobs.mesh"], sys.modules[ADDON + ".operators.mesh_objects"]
    bpy.ops.wm.read_homefile(use_empty=True)
    obj, original = closed_torus(n_vertices, shuffle)
    reset = lambda: restore(obj, original)  # noqa: E731
    times = {}

    def hc_object():
        assert bpy.ops.object.hc_smooth(auto_amount=False, iterations=ITERATIONS) == {"FINISHED"}

    times["object"] = median_time(hc_object, repeats, reset)
    reset()
    props = sys.modules[ADDON + ".cli.arguments"].Settings(iterations=ITERATIONS, auto_amount=False)
    (job,) = [mesh_objects.make_job(obj, props)]
    list(jobs.run([job], props))

    def report():
        job.change = None
        jobs.summary([job], props)

    times["report"] = median_time(report, repeats)
    assert job.change.volume_change is not None  # the report measured a volume: the torus is closed
    times["modifier"] = smooth_modifier_time(obj, repeats)

    def enter_edit_mode_all_selected():
        edit_mode_all_selected(reset)

    def hc_edit():
        assert bpy.ops.mesh.hc_smooth(auto_amount=False, iterations=ITERATIONS) == {"FINISHED"}

    enter_edit_mode_all_selected()
    start = time.perf_counter()
    hc_edit()
    times["edit first"] = time.perf_counter() - start
    times["edit"] = median_time(hc_edit, repeats, enter_edit_mode_all_selected)

    def round_trip():  # what Blender itself takes: Edit-mode data out to the mesh and back in
        bpy.ops.object.mode_set(mode="OBJECT")
        bpy.ops.object.mode_set(mode="EDIT")

    times["round trip"] = median_time(round_trip, repeats, enter_edit_mode_all_selected)
    reset()
    return times


def smooth_modifier_time(obj, repeats):
    """Median time to evaluate Blender's Smooth modifier (factor 0.5, 10 repeats) on ``obj``."""
    modifier = obj.modifiers.new("Smooth", "SMOOTH")
    modifier.factor, modifier.iterations = 0.5, ITERATIONS
    seconds, _ = timed_evaluation(obj, repeats)
    obj.modifiers.remove(modifier)
    return seconds


def edit_mode_all_selected(reset):
    """The mesh back to its noisy start, in Edit mode with everything selected."""
    reset()
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")


def restore(obj, points):
    if obj.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")
    obj.data.attributes["position"].data.foreach_set("vector", points.ravel())
    obj.data.update()


PARAMETERS = (
    Parameter("size", 1000, "grid subdivisions per side"),
    Parameter("torus", "1M", "vertices of the closed triangle tori (0 skips them)", count),
    repeats(3),
    Parameter("modifier", "100k,1M", "vertices of the tori for the HC Smooth modifier (0 skips it)", counts),
    Parameter("only_modifier", False, "run the modifier section alone"),
)
QUICK = {"size": 30, "torus": "2k", "modifier": "2k", "repeats": 1}


def run(args, out):
    args.modifier = [n for n in args.modifier if n]
    install_extension(ROOT / "build" / "bench")
    if args.only_modifier:
        modifier_tables(out, args.modifier, args.repeats)
        return out.rows
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
        assert bpy.ops.object.hc_smooth(auto_amount=False, iterations=ITERATIONS, **extra) == {"FINISHED"}

    rows.append(("object.hc_smooth (Object mode, HC, simultaneous)", median_time(hc_object, repeats, reset)))
    rows.append(("object.hc_smooth, sequential", median_time(lambda: hc_object(mode="SEQUENTIAL"), repeats, reset)))
    rows.append(
        (
            "object.hc_smooth with a fixed vertex group (30 %)",
            median_time(lambda: hc_object(vertex_group="Fixed"), repeats, reset),
        )
    )
    rows.append(
        (
            "  vertex group read alone (bulk path)",
            median_time(lambda: mesh_io.vertex_group_members(obj, group.index), repeats),
        )
    )
    rows.append(
        (
            "  vertex group read alone (per-vertex loop)",
            median_time(lambda: mesh_io._vertex_group_weights_loop(obj.data, group.index), 1),
        )
    )

    reset()
    rows.append(("Smooth modifier (10 repeats, evaluated)", smooth_modifier_time(obj, repeats)))

    def enter_edit_mode_all_selected():
        edit_mode_all_selected(reset)

    rows.append(
        (
            "mesh.vertices_smooth (Smooth Vertices, repeat=10, Edit mode)",
            median_time(
                lambda: bpy.ops.mesh.vertices_smooth(factor=0.5, repeat=ITERATIONS),
                repeats,
                enter_edit_mode_all_selected,
            ),
        )
    )

    def hc_edit():
        assert bpy.ops.mesh.hc_smooth(auto_amount=False, iterations=ITERATIONS) == {"FINISHED"}
        assert obj.mode == "EDIT"

    rows.append(
        (
            "mesh.hc_smooth (Edit mode, all selected, end to end)",
            median_time(hc_edit, repeats, enter_edit_mode_all_selected),
        )
    )
    reset()

    times = dict(rows)
    hc = times["object.hc_smooth (Object mode, HC, simultaneous)"]
    out(
        f"\n# HC Smooth in Blender {bpy.app.version_string}, {platform.python_version()}, {n:,} vertices, "
        f"{len(obj.data.polygons):,} faces, {ITERATIONS} iterations, median of {repeats}\n"
    )
    table = out.table("what", "median time (s)", align="lr")
    for name, seconds in rows:
        table.row(name, f"{seconds:.3f}")
    modifier_time = times["Smooth modifier (10 repeats, evaluated)"]
    vertices_smooth = times["mesh.vertices_smooth (Smooth Vertices, repeat=10, Edit mode)"]
    edit = times["mesh.hc_smooth (Edit mode, all selected, end to end)"]
    group_read = times["  vertex group read alone (bulk path)"]
    with_group = times["object.hc_smooth with a fixed vertex group (30 %)"]
    checks = [
        ("Object mode HC / Smooth modifier", f"{hc / modifier_time:.2f}×", "≤ 2×", hc <= 2 * modifier_time),
        ("Smooth Vertices / Object mode HC", f"{vertices_smooth / hc:.2f}×", "≥ 5×", vertices_smooth >= 5 * hc),
        ("Edit mode HC, end to end", f"{edit:.2f} s", "≤ 2.5 s", edit <= 2.5),
        (
            "vertex group read / run with the group",
            f"{group_read / with_group:.1%}",
            "not dominant",
            group_read < 0.25 * with_group,
        ),
    ]
    out("\n| check | value | target | |\n|---|---:|---:|---|")
    for name, value, target, ok in checks:
        out(f"| {name} | {value} | {target} | {'ok' if ok else 'MISSED'} |")
    if args.torus:
        closed_tables(out, args.torus, repeats)
    if args.modifier:
        modifier_tables(out, args.modifier, repeats)
    return out.rows


def closed_tables(out, n_vertices, repeats):
    results = {
        order: bench_closed(n_vertices, order == "random order", repeats) for order in ("grid order", "random order")
    }
    out(f"\n# Closed triangle torus, {n_vertices:,} vertices, {ITERATIONS} iterations, median of {repeats}\n")
    out(
        "| vertex order | object.hc_smooth | report after the run | Smooth modifier "
        "| Edit mode, first call | Edit mode | Edit → Object → Edit alone |\n|---|---:|---:|---:|---:|---:|---:|"
    )
    for order, times in results.items():
        out(
            f"| {order} | {times['object']:.3f} s | {times['report']:.3f} s | {times['modifier']:.3f} s "
            f"| {times['edit first']:.2f} s | {times['edit']:.2f} s | {times['round trip']:.2f} s |"
        )
    out("\n| check | value | target | |\n|---|---:|---:|---|")
    for order, times in results.items():
        ratio, share = times["object"] / times["modifier"], times["report"] / times["object"]
        for name, value, target, ok in (
            (f"{order}: Object mode HC / Smooth modifier", f"{ratio:.2f}×", "≤ 2×", ratio <= 2),
            (f"{order}: report / Object mode run", f"{share:.1%}", "≤ 10 %", share <= 0.1),
            (f"{order}: Edit mode, first call", f"{times['edit first']:.2f} s", "≤ 2.5 s", times["edit first"] <= 2.5),
        ):
            out(f"| {name} | {value} | {target} | {'ok' if ok else 'MISSED'} |")


# --- the HC Smooth modifier -------------------------------------------------------------------------------

METHODS = ("HC", "LAPLACIAN", "LAPLACIAN_CENTRAL", "LAPLACIAN_ORIGINAL")


def timed_evaluation(obj, repeats):
    """Median wall and CPU seconds (all threads) of re-evaluating ``obj``'s modifier stack, after one warm-up."""
    depsgraph = bpy.context.evaluated_depsgraph_get()

    def evaluate():
        obj.update_tag(refresh={"DATA"})
        depsgraph.update()
        obj.evaluated_get(depsgraph).data  # noqa: B018 - the evaluated mesh is the product

    evaluate()
    walls, cpus = [], []
    for _ in range(repeats):
        wall, cpu = time.perf_counter(), time.process_time()
        evaluate()
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    return statistics.median(walls), statistics.median(cpus)


def part_trees():
    """Geometry Nodes trees that repeat one part of the modifier's step ITERATIONS times, to price it alone."""
    hc_group = sys.modules[ADDON + ".nodes.hc_group"]

    def looped(name, body, before=None):
        tree = bpy.data.node_groups.new(name, "GeometryNodeTree")
        tree.is_modifier = True
        tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
        tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
        t = hc_group._Tree(tree)
        geometry = t.node("NodeGroupInput").outputs[0]
        output = t.node("NodeGroupOutput")
        extra = None
        if before is not None:
            geometry, extra = before(t, geometry)
        repeat_in, repeat_out = t.node("GeometryNodeRepeatInput"), t.node("GeometryNodeRepeatOutput")
        repeat_in.pair_with_output(repeat_out)
        repeat_in.inputs["Iterations"].default_value = ITERATIONS
        t.feed(repeat_in.inputs["Geometry"], geometry)
        t.feed(repeat_out.inputs["Geometry"], body(t, repeat_in.outputs["Geometry"], extra))
        t.feed(output.inputs[0], repeat_out.outputs["Geometry"])
        return tree

    def blur(t, iterations):
        node = t.node("GeometryNodeBlurAttribute", data_type="FLOAT_VECTOR")
        t.feed(node.inputs[0], t.position())
        t.feed(node.inputs["Iterations"], iterations)
        t.feed(node.inputs["Weight"], 1.0)
        return node.outputs[0]

    def gathered_umbrella(t, attribute):
        ends = t.node("GeometryNodeInputMeshEdgeVertices")
        pair = []
        for end in ("Vertex Index 1", "Vertex Index 2"):
            node = t.node("GeometryNodeFieldAtIndex", domain="POINT", data_type="FLOAT_VECTOR")
            t.feed(node.inputs["Value"], attribute)
            t.feed(node.inputs["Index"], ends.outputs[end])
            pair.append(node.outputs[0])
        return t.subtract(t.on_domain(t.add(*pair), "EDGE", "FLOAT_VECTOR"), attribute)

    def nested_umbrella(t):  # (q_i + q_j) / 2 on each edge, lazily; its mean over a vertex's edges; 2 m - q
        mean = t.on_domain(t.on_domain(t.position(), "POINT", "FLOAT_VECTOR"), "EDGE", "FLOAT_VECTOR")
        return t.subtract(t.scale(mean, 2.0), t.position())

    def split_umbrella(t):  # mean of Position 1 plus mean of Position 2: no edge array, two edge loops
        ends = t.node("GeometryNodeInputMeshEdgeVertices")
        means = [t.on_domain(ends.outputs[end], "EDGE", "FLOAT_VECTOR") for end in ("Position 1", "Position 2")]
        return t.subtract(t.add(*means), t.position())

    def capture_position(t, geometry):
        geometry, (captured,) = t.capture(geometry, [("VECTOR", "Value", t.position())])
        return geometry, captured

    shift = (0.0, 0.0, 1e-6)

    def captured_shift(t, geometry):
        geometry, (value,) = t.capture(geometry, [("VECTOR", "Value", t.add(t.position(), shift))])
        return t.set_position(geometry, value)

    return {
        "Set Position (q + c)": looped(
            "part: set position", lambda t, g, _: t.set_position(g, t.add(t.position(), shift))
        ),
        "Capture Attribute + Set Position from it": looped("part: capture", lambda t, g, _: captured_shift(t, g)),
        "umbrella of the positions (Edge Vertices, Evaluate on Domain) + Set Position": looped(
            "part: umbrella", lambda t, g, _: t.set_position(g, t.umbrella_of_positions())
        ),
        "umbrella of an attribute (2 × Evaluate at Index) + Set Position": looped(
            "part: gathered umbrella", lambda t, g, x: t.set_position(g, gathered_umbrella(t, x)), capture_position
        ),
        "umbrella, nested Evaluate on Domain (point → edge → point) + Set Position": looped(
            "part: nested umbrella", lambda t, g, _: t.set_position(g, nested_umbrella(t))
        ),
        "umbrella, each end position averaged onto the points alone + Set Position": looped(
            "part: split umbrella", lambda t, g, _: t.set_position(g, split_umbrella(t))
        ),
        "Blur Attribute, 1 iteration per call + Set Position": looped(
            "part: blur", lambda t, g, _: t.set_position(g, blur(t, 1))
        ),
    }


def modifier_tables(out, sizes, repeats):
    """The HC Smooth modifier against the Smooth modifier on closed tori, and the price of its parts."""
    inputs = sys.modules[ADDON + ".nodes.inputs"]
    method_names = sys.modules[ADDON + ".nodes.hc_group"].METHOD_NAMES
    out(
        f"\n# HC Smooth modifier, closed triangle tori, {ITERATIONS} iterations, Blender {bpy.app.version_string}, "
        f"median of {repeats}; wall / CPU seconds (CPU: all threads), ratio to the Smooth modifier of the same "
        "run\n"
    )
    out(
        "| vertices | Smooth modifier | "
        + " | ".join(METHODS)
        + " | HC, influence group (every other vertex 0.5) |\n|---:|---:|"
        + "---:|" * (len(METHODS) + 1)
    )
    checks, parts = [], {}
    for n_vertices in sizes:
        bpy.ops.wm.read_homefile(use_empty=True)
        obj, _ = closed_torus(n_vertices, shuffle=False)
        smooth = obj.modifiers.new("Smooth", "SMOOTH")
        smooth.factor, smooth.iterations = 0.5, ITERATIONS
        reference = timed_evaluation(obj, repeats)
        obj.modifiers.remove(smooth)
        assert bpy.ops.object.hc_smooth_modifier_add(iterations=ITERATIONS) == {"FINISHED"}
        modifier = obj.modifiers[-1]
        cells, hc = [], None
        for method in METHODS:
            inputs.set_input(modifier, "Method", method_names[method])
            wall, cpu = timed_evaluation(obj, repeats)
            hc = (wall, cpu) if method == "HC" else hc
            cells.append(f"{wall:.3f} / {cpu:.3f} ({wall / reference[0]:.1f}× / {cpu / reference[1]:.1f}×)")
        # Painted influence adds the weighted step to every iteration (the group is read once per evaluation).
        group = obj.vertex_groups.new(name="Paint")
        group.add(list(range(0, len(obj.data.vertices), 2)), 0.5, "REPLACE")
        inputs.set_input(modifier, "Method", method_names["HC"])
        inputs.set_input_attribute(modifier, "Influence", "Paint")
        wall, cpu = timed_evaluation(obj, repeats)
        cells.append(f"{wall:.3f} / {cpu:.3f} ({wall / reference[0]:.1f}× / {cpu / reference[1]:.1f}×)")
        inputs.set_input_attribute(modifier, "Influence", "")
        obj.vertex_groups.remove(group)
        out(f"| {len(obj.data.vertices):,} | {reference[0]:.3f} / {reference[1]:.3f} | " + " | ".join(cells) + " |")
        obj.modifiers.remove(modifier)
        if n_vertices >= 1_000_000:
            checks.append(
                (
                    f"{n_vertices:,}: HC / Smooth modifier (wall, CPU)",
                    f"{hc[0] / reference[0]:.1f}× / {hc[1] / reference[1]:.1f}×",
                    "≤ 4×",
                    hc[0] <= 4 * reference[0],
                )
            )
        if n_vertices <= 100_000:
            checks.append(
                (
                    f"{n_vertices:,}: HC, one evaluation (wall, CPU)",
                    f"{hc[0]:.3f} / {hc[1]:.3f} s",
                    "≤ 0.15 s",
                    hc[0] <= 0.15,
                )
            )
        part = obj.modifiers.new("Part", "NODES")
        for name, tree in part_trees().items():
            part.node_group = tree
            parts.setdefault(name, {})[n_vertices] = timed_evaluation(obj, repeats)
        part.node_group = None
        smooth = obj.modifiers.new("Smooth", "SMOOTH")  # the price of one Smooth iteration, same object
        smooth.factor, smooth.iterations = 0.5, ITERATIONS
        obj.modifiers.remove(part)
        parts.setdefault("Smooth modifier, one of its iterations (for scale)", {})[n_vertices] = timed_evaluation(
            obj, repeats
        )
    out("\n| check | value | target | |\n|---|---:|---:|---|")
    for name, value, target, ok in checks:
        out(f"| {name} | {value} | {target} | {'ok' if ok else 'MISSED'} |")
    out(
        f"\nWhere the time goes: each part repeated {ITERATIONS}× in a Repeat zone, milliseconds per repetition, "
        "wall / CPU\n"
    )
    out("| part | " + " | ".join(f"{n:,}" for n in sizes) + " |\n|---|" + "---:|" * len(sizes))
    for name, by_size in parts.items():
        out(
            f"| {name} | "
            + " | ".join(
                f"{1000 * by_size[n][0] / ITERATIONS:.1f} / {1000 * by_size[n][1] / ITERATIONS:.1f}" for n in sizes
            )
            + " |"
        )
