"""The demo's scene: a closed Suzanne, noise, copies, distances to the clean surface, and a Cycles
picture of several objects side by side, coloured by that distance on one scale, with a legend."""

import math

import bmesh
import bpy
import numpy as np
from mathutils import Vector
from mathutils.bvhtree import BVHTree

import core  # the repository's own (demo.py puts the root on sys.path)

ERROR_ATTRIBUTE = "distance_to_clean"
SPACING = 2.9  # between the heads' centres (Suzanne of size 2 is 2.7 wide)


def positions(mesh):
    buffer = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.attributes["position"].data.foreach_get("vector", buffer)
    return buffer.reshape(-1, 3)


def set_positions(mesh, points):
    mesh.attributes["position"].data.foreach_set("vector", np.ascontiguousarray(points, np.float32).ravel())
    mesh.update()


def faces(mesh):
    """(offsets, corner_verts): the face layout core.mesh.metrics accepts."""
    starts = np.empty(len(mesh.polygons), dtype=np.int64)
    mesh.polygons.foreach_get("loop_start", starts)
    corners = np.empty(len(mesh.loops), dtype=np.int64)
    mesh.loops.foreach_get("vertex_index", corners)
    return np.append(starts, corners.size), corners


def normals(mesh):
    buffer = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("normal", buffer)
    return buffer.reshape(-1, 3).astype(np.float64)


def select_only(obj):
    for other in bpy.context.scene.objects:
        other.select_set(other is obj)
    bpy.context.view_layer.objects.active = obj


def closed_suzanne(level):
    """Blender's monkey with its four holes (behind the eyes, the eye sockets) capped, then Catmull-Clark
    subdivided: a closed surface, so that the operator and the demo both measure its volume."""
    bpy.ops.mesh.primitive_monkey_add(size=2.0)
    obj = bpy.context.active_object
    mesh = bmesh.new()
    mesh.from_mesh(obj.data)
    bmesh.ops.holes_fill(mesh, edges=[edge for edge in mesh.edges if edge.is_boundary], sides=0)
    bmesh.ops.recalc_face_normals(mesh, faces=mesh.faces)
    mesh.to_mesh(obj.data)
    mesh.free()
    modifier = obj.modifiers.new("Subdivision", "SUBSURF")
    modifier.levels = modifier.render_levels = level
    bpy.ops.object.modifier_apply(modifier=modifier.name)
    return obj


def add_normal_noise(obj, sigma, rng):
    """Scanner-like noise: each vertex moved along its normal by a Gaussian amount (std ``sigma``)."""
    mesh = obj.data
    points = positions(mesh).astype(np.float64)
    points += normals(mesh) * rng.normal(0.0, sigma, size=(len(points), 1))
    set_positions(mesh, points)
    return obj


def copy_object(source, name, location):
    obj = source.copy()
    obj.data = source.data.copy()
    obj.name = obj.data.name = name
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    return obj


def object_from_mesh(mesh, name, location):
    obj = bpy.data.objects.new(name, mesh)
    mesh.name = name
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    return obj


class CleanSurface:
    """Signed distance of points to the clean mesh (negative inside), in its own coordinates."""

    def __init__(self, points, face_layout):
        offsets, corners = face_layout
        polygons = [corners[offsets[i] : offsets[i + 1]].tolist() for i in range(len(offsets) - 1)]
        self.tree = BVHTree.FromPolygons([Vector(p) for p in points.tolist()], polygons)

    def signed_distance(self, points):
        out = np.empty(len(points))
        for i, point in enumerate(points.tolist()):
            point = Vector(point)
            nearest, normal, _index, distance = self.tree.find_nearest(point)
            out[i] = math.copysign(distance, (point - nearest).dot(normal))
        return out


def set_point_attribute(obj, name, values):
    attribute = obj.data.attributes.get(name) or obj.data.attributes.new(name, "FLOAT", "POINT")
    attribute.data.foreach_set("value", np.ascontiguousarray(values, np.float32))


# --- the picture --------------------------------------------------------------------------------------

OUTLINE_COLOUR = (1.0, 0.78, 0.05)
# A diverging map (ColorBrewer RdBu, reversed): blue inside the clean surface, near-white on it, red outside.
DIVERGING = ("#053061", "#2166ac", "#4393c3", "#92c5de", "#f7f7f7", "#f4a582", "#d6604d", "#b2182b", "#67001f")


def _linear(hex_colour):
    """An sRGB hex colour as scene-linear RGBA (what node sockets hold)."""
    channels = [int(hex_colour[i : i + 2], 16) / 255 for i in (1, 3, 5)]
    return tuple(c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4 for c in channels) + (1.0,)


def _colour_of_error(tree, limit):
    """Nodes: the point attribute, mapped from [-limit, limit] onto the diverging map; returns the colour socket."""
    nodes, links = tree.nodes, tree.links
    attribute = nodes.new("ShaderNodeAttribute")
    attribute.attribute_name = ERROR_ATTRIBUTE
    scale = nodes.new("ShaderNodeMapRange")
    scale.inputs["From Min"].default_value = -limit
    scale.inputs["From Max"].default_value = limit
    ramp = nodes.new("ShaderNodeValToRGB")
    elements = ramp.color_ramp.elements
    while len(elements) < len(DIVERGING):
        elements.new(0.5)
    for element, (k, colour) in zip(elements, enumerate(DIVERGING), strict=True):
        element.position = k / (len(DIVERGING) - 1)
        element.color = _linear(colour)
    links.new(attribute.outputs["Fac"], scale.inputs["Value"])
    links.new(scale.outputs["Result"], ramp.inputs["Fac"])
    return ramp.outputs["Color"]


def _material(name, limit=None, emission=None):
    """Principled coloured by the error (``limit``), or a flat emission (``emission``: an RGB or, with
    ``limit``, the error colour): emission is lit evenly whatever the lights."""
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    if emission is None:
        shader = tree.nodes.new("ShaderNodeBsdfPrincipled")
        shader.inputs["Roughness"].default_value = 0.5
        tree.links.new(_colour_of_error(tree, limit), shader.inputs["Base Color"])
    else:
        shader = tree.nodes.new("ShaderNodeEmission")
        if limit is None:
            shader.inputs["Color"].default_value = (*emission, 1.0)
        else:
            tree.links.new(_colour_of_error(tree, limit), shader.inputs["Color"])
    tree.links.new(shader.outputs[0], output.inputs["Surface"])
    return material


def _text(body, location, size, material, align="CENTER"):
    curve = bpy.data.curves.new(f"Text {body[:20]}", "FONT")
    curve.body = body
    curve.align_x = align
    curve.align_y = "TOP"
    curve.size = size
    curve.materials.append(material)
    text = bpy.data.objects.new(curve.name, curve)
    text.location = location
    text.rotation_euler = (math.pi / 2, 0.0, 0.0)  # upright, facing the camera (which looks along +Y)
    bpy.context.scene.collection.objects.link(text)
    return text


def _legend(centre_x, top, width, limit, title, label_material):
    """A colour bar of the error scale (emission: the map's exact colours) with ticks and a title."""
    columns = 64
    xs = np.linspace(-width / 2, width / 2, columns + 1)
    height = 0.16
    verts = [(x, 0.0, z) for x in xs for z in (0.0, -height)]
    quads = [(2 * i, 2 * i + 1, 2 * i + 3, 2 * i + 2) for i in range(columns)]
    mesh = bpy.data.meshes.new("Legend")
    mesh.from_pydata(verts, [], quads)
    bar = bpy.data.objects.new("Legend", mesh)
    bar.location = (centre_x, 0.0, top)
    bpy.context.scene.collection.objects.link(bar)
    set_point_attribute(bar, ERROR_ATTRIBUTE, np.repeat(np.linspace(-limit, limit, columns + 1), 2))
    mesh.materials.append(_material("Legend", limit=limit, emission=True))
    _text(title, (centre_x, 0.0, top + 0.42), 0.17, label_material)
    for value in np.linspace(-limit, limit, 5):
        tick = f"{value:+.2g} %".replace("-", "\u2212") if value else "0"
        _text(tick, (centre_x + value / limit * width / 2, 0.0, top - height - 0.06), 0.15, label_material)
    _text("inside (shrunk)", (centre_x - width / 2 - 0.15, 0.0, top), 0.15, label_material, align="RIGHT")
    _text("outside", (centre_x + width / 2 + 0.15, 0.0, top), 0.15, label_material, align="LEFT")


def edges(mesh):
    buffer = np.empty(len(mesh.edges) * 2, dtype=np.int64)
    mesh.edges.foreach_get("vertices", buffer)
    return buffer.reshape(-1, 2)


def outline_segments(surface, points, face_layout, reach=0.01):
    """The clean shape's outer contour as seen by the camera (looking along +Y): its silhouette edges
    (one front-facing, one back-facing triangle) with nothing of the shape just outside them.
    Returns (k, 2, 2) segments in x, z."""
    triangles = core.fan_triangles(face_layout)
    a, b, c = (points[triangles[:, k]] for k in range(3))
    facing = np.cross(b - a, c - a)[:, 1] < 0.0  # normal towards the camera
    pairs = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    order = np.lexsort((pairs[:, 1], pairs[:, 0]))
    pairs, owner = pairs[order], np.repeat(np.arange(len(triangles)), 3)[order]
    # A closed surface: every edge appears twice, its two triangles next to each other once sorted.
    first, second = owner[0::2], owner[1::2]
    silhouette = facing[first] != facing[second]
    ends = pairs[0::2][silhouette]
    centroid = (a + b + c)[first[silhouette]] / 3
    start, stop = points[ends[:, 0]][:, [0, 2]], points[ends[:, 1]][:, [0, 2]]
    along = stop - start
    across = np.stack([-along[:, 1], along[:, 0]], axis=1)
    across /= np.maximum(np.linalg.norm(across, axis=1, keepdims=True), 1e-12)
    middle = (start + stop) / 2
    # Outward: away from the triangles folding at the edge.
    across *= np.where(((centroid[:, [0, 2]] - middle) * across).sum(axis=1) > 0, -1.0, 1.0)[:, None]
    probes = middle + reach * across
    outer = [surface.tree.ray_cast(Vector((x, -100.0, z)), Vector((0.0, 1.0, 0.0)))[0] is None for x, z in probes]
    return np.stack([start, stop], axis=1)[np.asarray(outer, dtype=bool)]


def _outline(segments, location, width, material):
    """Segments (x, z) as flat ribbons ``width`` wide in front of everything at ``location``."""
    start, stop = segments[:, 0], segments[:, 1]
    along = stop - start
    along /= np.maximum(np.linalg.norm(along, axis=1, keepdims=True), 1e-12)
    across = np.stack([-along[:, 1], along[:, 0]], axis=1) * width / 2
    start, stop = start - along * width / 2, stop + along * width / 2  # overlap at the joints
    corners = np.stack([start - across, stop - across, stop + across, start + across], axis=1).reshape(-1, 2)
    verts = np.insert(corners, 1, -3.0, axis=1)  # y = -3: between the camera and the heads
    mesh = bpy.data.meshes.new("Clean outline")
    mesh.from_pydata(verts.tolist(), [], np.arange(len(verts)).reshape(-1, 4).tolist())
    mesh.materials.append(material)
    obj = bpy.data.objects.new("Clean outline", mesh)
    obj.location = location
    obj.visible_shadow = False
    bpy.context.scene.collection.objects.link(obj)
    return obj


def render_error_figure(
    panels, outline, outlined, filepath, *, limit, legend_title, samples=8, resolution=(1300, 471), percentage=100
):
    """Render ``panels`` [(object, label text)] (objects placed along +X, each with the point attribute
    ERROR_ATTRIBUTE) facing the camera, coloured on one scale [-limit, limit], a label under each, a
    legend under all, and the ``outline`` segments (from outline_segments) over the objects in ``outlined``."""
    surface = _material("Distance to clean", limit=limit)
    label_material = _material("Label", emission=(0.92, 0.92, 0.92))
    for obj, _label in panels:
        obj.data.materials.clear()
        obj.data.materials.append(surface)
        obj.data.polygons.foreach_set("use_smooth", np.ones(len(obj.data.polygons), dtype=bool))
        obj.data.update()
    xs = [obj.location.x for obj, _ in panels]
    centre_x, width = (min(xs) + max(xs)) / 2, max(xs) - min(xs) + SPACING
    for obj, text in panels:
        _text(text, (obj.location.x, 0.0, -1.12), 0.21, label_material)
    _legend(centre_x, -2.35, 4.0, limit, legend_title, label_material)
    line = _material("Outline", emission=OUTLINE_COLOUR)
    for obj in outlined:
        _outline(outline, obj.location, 0.018, line)

    render_front(filepath, centre_x, width, 1.12, samples=samples, resolution=resolution, percentage=percentage)


def figure_scene(samples):
    """The figures' look on the current scene: key and fill sun lights, a dark background, colours as given
    (no tone mapping), Cycles on the CPU with ``samples`` samples and denoising, PNG in RGB. Returns it."""
    scene = bpy.context.scene
    for name, energy, rotation in (("Key", 3.0, (0.9, 0.2, -0.6)), ("Fill", 1.2, (1.2, -0.3, 0.9))):
        light = bpy.data.objects.new(name, bpy.data.lights.new(name, "SUN"))
        light.data.energy = energy
        light.rotation_euler = rotation
        scene.collection.objects.link(light)
    world = bpy.data.worlds.new("World")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (0.045, 0.047, 0.052, 1.0)
    background.inputs["Strength"].default_value = 1.0
    scene.world = world
    scene.view_settings.view_transform = "Standard"  # the colour map's colours as given, no tone mapping
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = True
    # Direct light and one diffuse bounce are all these pictures need; deeper paths only cost time.
    scene.cycles.max_bounces, scene.cycles.diffuse_bounces, scene.cycles.glossy_bounces = 2, 1, 1
    scene.cycles.transmission_bounces = scene.cycles.volume_bounces = 0
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.dither_intensity = 0.0  # dither noise would double the PNG's size
    return scene


def render_front(filepath, centre_x, width, top, *, samples=8, resolution=(1300, 471), percentage=100):
    """Render the scene from the front (looking along +Y) with an orthographic camera ``width`` wide, centred
    on ``centre_x`` with its top edge at height ``top``, under the figures' key and fill lights and dark
    background, with Cycles on the CPU, to the PNG ``filepath`` (no stamps)."""
    scene = bpy.context.scene
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = width
    camera.location = (centre_x, -10.0, top - width * resolution[1] / resolution[0] / 2)
    camera.rotation_euler = (math.pi / 2, 0.0, 0.0)
    scene.collection.objects.link(camera)
    scene.camera = camera
    figure_scene(samples)
    scene.render.resolution_x, scene.render.resolution_y = resolution
    scene.render.resolution_percentage = percentage
    scene.render.image_settings.compression = 100
    for field in (
        "date",
        "time",
        "render_time",
        "frame",
        "camera",
        "scene",
        "filename",
        "memory",
        "hostname",
        "lens",
        "marker",
        "frame_range",
        "sequencer_strip",
        "note",
    ):
        setattr(scene.render, f"use_stamp_{field}", False)  # no file path, date or timings in the PNG
    scene.render.filepath = str(filepath)
    bpy.ops.render.render(write_still=True)
