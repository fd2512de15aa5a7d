"""Blender-side readers agree with the core's own definitions."""

import importlib

import bmesh
import bpy
import numpy as np
import pytest

import core
from blender_scene import noisy_grid, noisy_sphere
from blender_scene import ADDON


def mesh_io():
    return importlib.import_module(f"{ADDON}.operators.mesh_io")


def flip_first_face(obj):
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    bm.faces.ensure_lookup_table()
    bm.faces[0].normal_flip()
    bm.to_mesh(obj.data)
    bm.free()


def add_loose_edge(obj):
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    bm.verts.ensure_lookup_table()
    first = bm.verts[0]
    bm.edges.new((first, bm.verts.new((5.0, 5.0, 5.0))))
    bm.to_mesh(obj.data)
    bm.free()


@pytest.mark.parametrize("make, change, expected", [
    (noisy_sphere, None, True),
    (noisy_grid, None, False),
    (noisy_sphere, flip_first_face, False),
    (noisy_sphere, add_loose_edge, True),  # a loose edge does not open the surface
    (lambda: (bpy.ops.mesh.primitive_monkey_add(), bpy.context.active_object)[1], None, False),
])
def test_closedness_from_corner_edges_matches_the_core(scene, make, change, expected):
    obj = make()
    if change is not None:
        change(obj)
    mesh = obj.data
    faces = mesh_io().read_faces(mesh)
    edges = mesh_io().read_edges(mesh)
    assert mesh_io().is_closed(mesh, edges, faces) is expected
    assert core.metrics.is_closed(core.metrics.fan_triangles(faces)) is expected
