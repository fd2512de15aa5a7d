"""What the HC Smooth modifier's limits rest on: seconds per 1000 iterations, and what its guards cost.

    .envs/bpy45/bin/python bench/run.py modifier_limits [--sizes 10k,100k] [--iterations 200] [--repeats 3]

A Geometry Nodes evaluation cannot be cancelled, so the modifier's Iterations has a hard maximum
(settings_spec.MODIFIER_MAX_ITERATIONS). On noisy closed triangle tori of each size it times one evaluation
of the modifier (median of --repeats, after a warm-up), per method, with --iterations iterations, and prints
the seconds per 1000 iterations; then the same for HC with a Deviation Limit, and the evaluation at 0
iterations (the guards and the group's set-up alone) beside the input passed through (HC with Beta 0, refused).
Last, the price of welding coincident vertices inside Geometry Nodes: Merge by Distance, then each vertex
takes its merged vertex's position back (Sample Nearest, Sample Index), timed alone beside 10 HC iterations.
Run it with either test environment (Blender 4.5 or 5.2 as the bpy module); it installs the extension itself.
"""

import platform
import sys

from scripts.extension_session import ADDON, install_extension  # before bpy

# isort: split

import bpy

from bench.bench_blender import closed_torus, timed_evaluation
from bench.common import ROOT, Parameter, repeats, sizes

METHODS = ("HC", "LAPLACIAN", "LAPLACIAN_CENTRAL", "LAPLACIAN_ORIGINAL")


def evaluation_seconds(obj, repeats):
    """Median wall seconds of re-evaluating ``obj``'s modifier stack, after one warm-up."""
    return timed_evaluation(obj, repeats)[0]


PARAMETERS = (
    sizes("10k,100k", "torus vertex counts, comma-separated"),
    Parameter("iterations", 200, "iterations per timed evaluation"),
    repeats(3),
)
QUICK = {"sizes": "2k", "iterations": 20, "repeats": 1}


def run(args, out):
    install_extension(ROOT / "build" / "bench")
    inputs = sys.modules[ADDON + ".nodes.inputs"]
    settings_spec = sys.modules[ADDON + ".settings_spec"]
    out(
        f"Blender {bpy.app.version_string}, {platform.processor() or platform.machine()}, "
        f"{args.iterations} iterations per evaluation, median of {args.repeats}\n"
    )
    table = out.table("vertices", "case", "s per evaluation", "s per 1000 iterations", align="rlrr")
    for size in args.sizes:
        bpy.ops.wm.read_homefile(use_empty=True)
        obj = closed_torus(size, shuffle=False)[0]  # as bench_blender.py times the operator
        assert bpy.ops.object.hc_smooth_modifier_add(iterations=args.iterations) == {"FINISHED"}
        modifier = obj.modifiers[-1]
        n = len(obj.data.vertices)
        cases = [(method, dict(Method=_menu_name(settings_spec, method))) for method in METHODS]
        cases.append(("HC, Deviation Limit 0.001", dict(Method="HC", **{"Deviation Limit": 0.001})))
        cases.append(("Laplacian, Deviation Limit 0.001", dict(Method="Laplacian", **{"Deviation Limit": 0.001})))
        for name, values in cases:
            inputs.set_input(modifier, "Deviation Limit", 0.0)
            for key, value in values.items():
                inputs.set_input(modifier, key, value)
            seconds = evaluation_seconds(obj, args.repeats)
            table.row(f"{n:,}", name, f"{seconds:.3f}", f"{1000 * seconds / args.iterations:.2f}")
        inputs.set_input(modifier, "Deviation Limit", 0.0)
        inputs.set_input(modifier, "Method", "HC")
        inputs.set_input(modifier, "Iterations", 0)
        table.row(f"{n:,}", "HC, 0 iterations (set-up and guards)", f"{evaluation_seconds(obj, args.repeats):.3f}", "")
        inputs.set_input(modifier, "Iterations", args.iterations)
        inputs.set_input(modifier, "Beta", 0.0)
        table.row(f"{n:,}", "HC, Beta 0 (refused: passed through)", f"{evaluation_seconds(obj, args.repeats):.3f}", "")
        inputs.set_input(modifier, "Beta", 0.6)
        inputs.set_input(modifier, "Iterations", 10)
        table.row(f"{n:,}", "HC, 10 iterations", f"{evaluation_seconds(obj, args.repeats):.3f}", "")
        modifier.show_viewport = False
        obj.modifiers.new("Weld", "NODES").node_group = weld_tree()
        seconds = evaluation_seconds(obj, args.repeats)
        table.row(f"{n:,}", "welding alone (Merge by Distance, sampled back)", f"{seconds:.3f}", "")
    return out.rows


def weld_tree():
    """Merge by Distance, then every vertex reads back the position of the merged vertex nearest to it: what
    welding inside the modifier would add to each evaluation (without the smoothing in between)."""
    tree = bpy.data.node_groups.new("Weld and sample back", "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    nodes, links = tree.nodes, tree.links
    group_input, group_output = nodes.new("NodeGroupInput"), nodes.new("NodeGroupOutput")
    merge = nodes.new("GeometryNodeMergeByDistance")
    merge.inputs["Distance"].default_value = 1e-6
    nearest = nodes.new("GeometryNodeSampleNearest")
    sample = nodes.new("GeometryNodeSampleIndex")
    sample.data_type, sample.domain = "FLOAT_VECTOR", "POINT"
    move = nodes.new("GeometryNodeSetPosition")
    links.new(group_input.outputs[0], merge.inputs["Geometry"])
    links.new(merge.outputs["Geometry"], nearest.inputs["Geometry"])
    links.new(merge.outputs["Geometry"], sample.inputs["Geometry"])
    links.new(nodes.new("GeometryNodeInputPosition").outputs[0], sample.inputs["Value"])
    links.new(nearest.outputs["Index"], sample.inputs["Index"])
    links.new(group_input.outputs[0], move.inputs["Geometry"])
    links.new(sample.outputs[0], move.inputs["Position"])
    links.new(move.outputs["Geometry"], group_output.inputs[0])
    return tree


def _menu_name(settings_spec, identifier):
    return next(choice.label for choice in settings_spec.METHOD.items if choice.identifier == identifier)
