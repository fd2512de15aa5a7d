"""Render docs/images/deviation_map.png: a noisy scan and the same smoothed by object.hc_smooth (default
settings) with Deviation Map on, coloured by the colour attribute the operator stores, with the ramp's legend
as the operator reports it (Cycles, headless bpy).

    .envs/bpy45/bin/python docs/render_deviation_map_picture.py --scan PATH [--output docs/images/deviation_map.png]

``--scan``: an OBJ or PLY scan (the picture of docs/deviation_map.md: the pymeshlab wheel's bunny.obj, a range scan
merged into one closed mesh, ``<site-packages>/pymeshlab/tests/sample_meshes/bunny.obj``); without it, a
closed subdivided Suzanne. Gaussian noise of NOISE times the bounding-box diagonal is added along the
normals. The right panel is what the operator wrote: the mesh's ``hc_deviation_color`` attribute, rendered
through a material's Attribute node, and the legend bar holds the same ramp (core.deviation_colors).
"""

import argparse
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "scripts"), str(ROOT / "demo"), str(ROOT)]  # scene_setup imports core

from extension_session import ADDON, install_extension, run_and_exit  # noqa: E402  (before bpy)

# isort: split

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import scene_setup  # noqa: E402

NOISE = 0.002  # of the bounding-box diagonal, along the normals
SEED = 7
SIZE = 2.4  # the objects' largest extent in the picture (object scale: the mesh keeps its units)
SPACING = 2.9


def load_scan(path):
    """The scan as the active object, its coincident vertices merged (an OBJ splits them at its seams)."""
    if path is None:
        return scene_setup.closed_suzanne(level=3)
    importer = bpy.ops.wm.ply_import if path.suffix.lower() == ".ply" else bpy.ops.wm.obj_import
    importer(filepath=str(path))
    obj = next(obj for obj in bpy.context.scene.objects if obj.type == "MESH")
    scene_setup.select_only(obj)
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.mesh.remove_doubles(threshold=0.0)
    bpy.ops.object.mode_set(mode="OBJECT")
    return obj


def placed(obj, x, size):
    """Scale and move ``obj`` (object transform only) so that its box is centred at (x, 0, 0), ``size`` wide."""
    points = scene_setup.positions(obj.data)
    low, high = points.min(axis=0), points.max(axis=0)
    scale = SIZE / float((high - low).max())
    obj.scale = (scale,) * 3
    obj.location = (
        x - scale * (low[0] + high[0]) / 2,
        -scale * (low[1] + high[1]) / 2,
        -scale * (low[2] + high[2]) / 2,
    )


def _shaded(name, emission):
    """(material, its node tree, its shader, the shader's colour input): a new material of one shader,
    emission or Principled BSDF, linked to the output."""
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    shader = tree.nodes.new("ShaderNodeEmission" if emission else "ShaderNodeBsdfPrincipled")
    tree.links.new(shader.outputs[0], output.inputs["Surface"])
    return material, tree, shader, shader.inputs["Color" if emission else "Base Color"]


def attribute_material(name, attribute, emission=False):
    """A material coloured by a colour attribute (linear RGB, as the operator stores it)."""
    material, tree, shader, colour_input = _shaded(name, emission)
    if not emission:
        shader.inputs["Roughness"].default_value = 0.5
    colour = tree.nodes.new("ShaderNodeAttribute")
    colour.attribute_name = attribute
    tree.links.new(colour.outputs["Color"], colour_input)
    return material


def plain_material(name, rgb, emission=False):
    material, _, _, colour_input = _shaded(name, emission)
    colour_input.default_value = (*rgb, 1.0)
    return material


def legend(core, centre_x, top, width, extent, length, label_material):
    """The ramp as a bar of the operator's colours (emission: exact), ticks at -extent, 0, +extent."""
    columns = 254
    xs = np.linspace(-width / 2, width / 2, columns + 1)
    height = 0.16
    mesh = bpy.data.meshes.new("Legend")
    mesh.from_pydata(
        [(x, 0.0, z) for x in xs for z in (0.0, -height)],
        [],
        [(2 * i, 2 * i + 1, 2 * i + 3, 2 * i + 2) for i in range(columns)],
    )
    colours = core.deviation_colors(np.repeat(np.linspace(-extent, extent, columns + 1), 2), extent, linear=True)
    attribute = mesh.attributes.new("ramp", "FLOAT_COLOR", "POINT")
    attribute.data.foreach_set("color", colours.ravel())
    mesh.materials.append(attribute_material("Legend", "ramp", emission=True))
    bar = bpy.data.objects.new("Legend", mesh)
    bar.location = (centre_x, 0.0, top)
    bpy.context.scene.collection.objects.link(bar)
    for value, text in ((-extent, f"\u2212{length(extent)}"), (0.0, "0"), (extent, f"+{length(extent)}")):
        scene_setup._text(text, (centre_x + value / extent * width / 2, 0.0, top - height - 0.06), 0.15, label_material)
    scene_setup._text("inwards", (centre_x - width / 2 - 0.15, 0.0, top), 0.15, label_material, align="RIGHT")
    scene_setup._text("outwards", (centre_x + width / 2 + 0.15, 0.0, top), 0.15, label_material, align="LEFT")


def render(filepath, centre_x, width, samples, resolution):
    scene_setup.render_front(filepath, centre_x, width, 1.5, samples=samples, resolution=resolution)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scan", type=pathlib.Path, help="an OBJ or PLY scan (default: a closed Suzanne)")
    parser.add_argument("--output", default=str(ROOT / "docs" / "images" / "deviation_map.png"))
    parser.add_argument("--samples", type=int, default=16)
    args = parser.parse_args()
    install_extension(ROOT / "build" / "docs")
    core = sys.modules[ADDON + ".core"]
    mesh_smooth = sys.modules[ADDON + ".operators.mesh_smooth"]

    bpy.ops.wm.read_homefile(use_empty=True)
    noisy = load_scan(args.scan)
    points = scene_setup.positions(noisy.data)
    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    scene_setup.add_normal_noise(noisy, NOISE * diagonal, np.random.default_rng(SEED))
    noisy.name = noisy.data.name = "Noisy"
    smoothed = scene_setup.copy_object(noisy, "Smoothed", (0, 0, 0))
    scene_setup.select_only(smoothed)
    assert bpy.ops.object.hc_smooth(deviation_map=True) == {"FINISHED"}

    values = np.empty(len(smoothed.data.vertices), dtype=np.float32)
    smoothed.data.attributes["hc_deviation"].data.foreach_get("value", values)
    extent = core.deviation_extent(values)
    length = mesh_smooth.scene_length(bpy.context.scene)
    words = core.DeviationMap(values, None, extent, min(0.0, float(values.min())), max(0.0, float(values.max())))
    said = words.legend(length)
    print(said)

    label = plain_material("Label", (0.92, 0.92, 0.92), emission=True)
    noisy.data.materials.clear()
    noisy.data.materials.append(plain_material("Scan", (0.6, 0.6, 0.6)))
    smoothed.data.materials.clear()
    smoothed.data.materials.append(attribute_material("Deviation", "hc_deviation_color"))
    for obj in (noisy, smoothed):
        obj.data.polygons.foreach_set("use_smooth", np.ones(len(obj.data.polygons), dtype=bool))
        obj.data.update()
    placed(noisy, 0.0, SIZE)
    placed(smoothed, SPACING, SIZE)
    name = f"{args.scan.stem} scan" if args.scan else "Suzanne"
    scene_setup._text(f"{name}, noise \u03c3 {NOISE:.1%} of its size", (0.0, 0.0, -1.5), 0.18, label)
    scene_setup._text("HC Smooth with Deviation Map", (SPACING, 0.0, -1.5), 0.18, label)
    centre = SPACING / 2
    legend(core, centre, -2.05, 3.6, extent, length or (lambda x: f"{x:.3g}"), label)
    scene_setup._text("the report: " + said.replace(" (", "\n("), (centre, 0.0, -2.65), 0.14, label)
    render(args.output, centre, SPACING + SIZE + 0.6, args.samples, (820, 640))
    print(f"picture: {args.output}")


if __name__ == "__main__":
    run_and_exit(main)
