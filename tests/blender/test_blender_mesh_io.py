"""Blender-side readers agree with the core's own definitions."""

import importlib

import bmesh
import bpy
import numpy as np
import pytest
from blender_scene import ADDON, noisy_grid, noisy_sphere

import core


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


@pytest.mark.parametrize(
    "make, change, expected",
    [
        (noisy_sphere, None, True),
        (noisy_grid, None, False),
        (noisy_sphere, flip_first_face, False),
        (noisy_sphere, add_loose_edge, True),  # a loose edge does not open the surface
        (lambda: (bpy.ops.mesh.primitive_monkey_add(), bpy.context.active_object)[1], None, False),
    ],
)
def test_closedness_from_corner_edges_matches_the_core(scene, make, change, expected):
    obj = make()
    if change is not None:
        change(obj)
    mesh = obj.data
    faces = mesh_io().read_faces(mesh)
    edges = mesh_io().read_edges(mesh)
    corner_verts, corner_edges = mesh_io().read_corners(mesh)
    np.testing.assert_array_equal(corner_verts, np.ravel(faces if isinstance(faces, np.ndarray) else faces[1]))
    assert core.mesh.topology.closed_from_corners(edges, corner_verts, corner_edges) is expected
    assert core.mesh.topology.closed_from_triangles(core.geometry.fan_triangles(faces)) is expected


@pytest.mark.parametrize(
    "make", [noisy_sphere, noisy_grid, lambda: (bpy.ops.mesh.primitive_monkey_add(), bpy.context.active_object)[1]]
)
def test_border_of_the_fanned_faces_matches_the_faces(scene, make):
    # Reference: an edge of exactly one face, counted from the faces' own corner pairs.
    mesh = make().data
    faces = mesh_io().read_faces(mesh)
    if isinstance(faces, np.ndarray):  # all triangles
        faces = np.arange(0, faces.size + 1, 3), faces.ravel()
    offsets, corners = faces
    following = np.arange(1, corners.size + 1)
    following[offsets[1:] - 1] = offsets[:-1]
    pairs = np.sort(np.stack([corners, corners[following]], axis=1), axis=1)
    unique, counts = np.unique(pairs, axis=0, return_counts=True)
    expected = np.zeros(len(mesh.vertices), dtype=bool)
    expected[unique[counts == 1].ravel()] = True
    got = np.zeros(len(mesh.vertices), dtype=bool)  # what the border rules hold (core.mesh.borders)
    got[core.mesh.borders.border_edges(core.geometry.fan_triangles(mesh_io().read_faces(mesh)), len(got)).ravel()] = (
        True
    )
    np.testing.assert_array_equal(got, expected)
    assert got.any() != (make is noisy_sphere)
