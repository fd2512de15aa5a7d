"""The demo's scene: Suzanne, noise, copies, and a Cycles picture of several objects side by side."""

import bpy
import numpy as np


def positions(mesh):
    buffer = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.attributes["position"].data.foreach_get("vector", buffer)
    return buffer.reshape(-1, 3)


def set_positions(mesh, points):
    mesh.attributes["position"].data.foreach_set("vector", np.ascontiguousarray(points, np.float32).ravel())
    mesh.update()


def faces(mesh):
    """(offsets, corner_verts): the face layout core.metrics accepts."""
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


def subdivided_suzanne(level):
    """Blender's monkey with a Catmull-Clark subdivision applied: the clean reference shape."""
    bpy.ops.mesh.primitive_monkey_add(size=2.0)
    obj = bpy.context.active_object
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


def _material():
    material = bpy.data.materials.new("Clay")
    material.diffuse_color = (0.8, 0.62, 0.45, 1.0)
    material.use_nodes = True
    shader = material.node_tree.nodes.get("Principled BSDF")
    shader.inputs["Base Color"].default_value = (0.8, 0.62, 0.45, 1.0)
    shader.inputs["Roughness"].default_value = 0.45
    return material


def _label(text, location, size):
    curve = bpy.data.curves.new(f"Label {text}", "FONT")
    curve.body = text
    curve.align_x = "CENTER"
    curve.size = size
    label = bpy.data.objects.new(f"Label {text}", curve)
    label.location = location
    label.rotation_euler = (1.5708, 0.0, 0.0)  # upright, facing the camera (which looks along +Y)
    bpy.context.scene.collection.objects.link(label)
    label.data.materials.append(bpy.data.materials.get("Clay"))
    return label


def render_side_by_side(objects, labels, filepath, samples=16, resolution=(1500, 620)):
    """Render ``objects`` (already placed along +X) facing the camera, each with a label below."""
    scene = bpy.context.scene
    material = _material()
    for obj in objects:
        obj.data.materials.clear()
        obj.data.materials.append(material)
        obj.data.polygons.foreach_set("use_smooth", np.ones(len(obj.data.polygons), dtype=bool))
        obj.data.update()
    xs = [obj.location.x for obj in objects]
    centre_x, width = (min(xs) + max(xs)) / 2, max(xs) - min(xs) + 2.9
    for obj, text in zip(objects, labels):
        _label(text, (obj.location.x, 0.0, -1.3), 0.3)

    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = width
    camera.location = (centre_x, -10.0, -0.3)
    camera.rotation_euler = (1.5708, 0.0, 0.0)
    scene.collection.objects.link(camera)
    scene.camera = camera
    for name, energy, rotation in (("Key", 4.0, (0.9, 0.2, -0.6)), ("Fill", 1.5, (1.2, -0.3, 0.9))):
        light = bpy.data.objects.new(name, bpy.data.lights.new(name, "SUN"))
        light.data.energy = energy
        light.rotation_euler = rotation
        scene.collection.objects.link(light)

    world = bpy.data.worlds.new("World")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.06, 0.06, 0.07, 1.0)
    scene.world = world
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = True
    scene.render.resolution_x, scene.render.resolution_y = resolution
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = str(filepath)
    bpy.ops.render.render(write_still=True)
