"""Building test scenes: meshes from arrays, noisy primitives, selection, bulk reads."""

import bpy
import numpy as np

ADDON = "bl_ext.user_default.hc_smooth"  # the module name Blender gives the installed extension


def make_mesh_object(name, positions, faces=(), edges=(), link=True):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([tuple(map(float, p)) for p in positions], [tuple(e) for e in edges], [tuple(f) for f in faces])
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    if link:
        bpy.context.scene.collection.objects.link(obj)
    return obj


def select_only(*objects):
    for obj in bpy.context.scene.objects:
        obj.select_set(obj in objects)
    if objects:
        bpy.context.view_layer.objects.active = objects[0]


def positions_of(mesh):
    buffer = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", buffer)
    return buffer.reshape(-1, 3)


def edges_of(mesh):
    buffer = np.empty(len(mesh.edges) * 2, dtype=np.int64)
    mesh.edges.foreach_get("vertices", buffer)
    return buffer.reshape(-1, 2)


def faces_of(mesh):
    return [tuple(p.vertices) for p in mesh.polygons]


def noisy_sphere(name="Sphere", subdivisions=3, sigma=0.08, seed=0):
    """An icosphere of radius 1 with Gaussian noise, as a new selected, active object."""
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=subdivisions, radius=1.0)
    obj = bpy.context.active_object
    obj.name = obj.data.name = name
    positions = positions_of(obj.data)
    positions += np.random.default_rng(seed).normal(scale=sigma, size=positions.shape).astype(np.float32)
    obj.data.vertices.foreach_set("co", positions.ravel())
    obj.data.update()
    return obj


def noisy_grid(name="Grid", size=12, sigma=0.05, seed=1):
    """An open patch (it has a boundary), noisy in z."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=size, y_subdivisions=size, size=2.0)
    obj = bpy.context.active_object
    obj.name = obj.data.name = name
    positions = positions_of(obj.data)
    positions[:, 2] += np.random.default_rng(seed).normal(scale=sigma, size=len(positions)).astype(np.float32)
    obj.data.vertices.foreach_set("co", positions.ravel())
    obj.data.update()
    return obj


def transformed(obj, **transform):
    """``obj`` with its transform set (scale, rotation_euler, location, ...) and its world matrix up to date."""
    for name, value in transform.items():
        setattr(obj, name, value)
    bpy.context.view_layer.update()
    return obj


def in_world(obj, positions):
    """Object-space ``positions`` in world space, without the translation (float64): what a world-space length
    is measured on."""
    linear = np.array(obj.matrix_world, dtype=np.float64)[:3, :3]
    return positions.astype(np.float64) @ linear.T
