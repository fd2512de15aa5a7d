"""Split vertices are one surface: a UV seam does not open, a flat-shaded soup smooths like its mesh."""

import sys

import bmesh
import bpy
import numpy as np
import pytest
from blender_scene import ADDON, noisy_grid, noisy_sphere, positions_of, select_only


def split(obj, every_edge=False):
    """Split the mesh along one meridian (a UV seam) or along every edge (a soup: every face its own
    vertices), as importers of glTF, PLY with UVs and STL hand meshes over. Returns the mesh's positions
    before the split, and for each vertex after it, the vertex it was."""
    mesh = obj.data
    before = positions_of(mesh)
    bm = bmesh.new()
    bm.from_mesh(mesh)
    bm.verts.ensure_lookup_table()
    for index, vertex in enumerate(bm.verts):
        vertex.index = index
    layer = bm.verts.layers.int.new("origin")
    for vertex in bm.verts:
        vertex[layer] = vertex.index
    if every_edge:
        edges = list(bm.edges)
    else:  # the edges on the half-plane y = 0, x > 0: one meridian
        edges = [e for e in bm.edges if all(abs(v.co.y) < 1e-6 and v.co.x > 1e-6 for v in e.verts)]
        assert edges
    bmesh.ops.split_edges(bm, edges=edges)
    bm.verts.ensure_lookup_table()
    origin = np.array([vertex[layer] for vertex in bm.verts])
    bm.to_mesh(mesh)
    bm.free()
    mesh.update()
    assert len(mesh.vertices) > len(before)
    return before, origin


def seamed_uv_sphere(name, seed=3):
    """A UV sphere split along a meridian, then made noisy: the copies of a vertex get the same noise."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=1.0)
    obj = bpy.context.active_object
    obj.name = obj.data.name = name
    before, origin = split(obj)
    noise = np.random.default_rng(seed).normal(scale=0.01, size=before.shape).astype(np.float32)
    positions = positions_of(obj.data) + noise[origin]
    obj.data.vertices.foreach_set("co", positions.ravel())
    obj.data.update()
    return obj, origin


@pytest.mark.parametrize("given", [{}, dict(iterations=10)], ids=["automatic", "iterations"])
def test_a_uv_seam_does_not_open(scene, given):
    obj, origin = seamed_uv_sphere("Seam")
    select_only(obj)
    assert bpy.ops.object.hc_smooth(**given) == {"FINISHED"}
    after = positions_of(obj.data).astype(np.float64)
    diagonal = np.linalg.norm(np.ptp(after, axis=0))
    gaps = [np.ptp(after[origin == k], axis=0).max() for k in np.unique(origin) if np.count_nonzero(origin == k) > 1]
    assert len(gaps) > 10 and max(gaps) <= 1e-6 * diagonal


@pytest.mark.parametrize("given", [{}, dict(iterations=10)], ids=["automatic", "iterations"])
def test_a_soup_smooths_like_its_mesh(scene, given):
    """Every face with its own vertices: the result is the welded mesh's, vertex for vertex."""
    mesh_object = noisy_sphere("Whole", seed=4)
    soup_object = noisy_sphere("Soup", seed=4)
    _, origin = split(soup_object, every_edge=True)
    assert len(soup_object.data.vertices) == 3 * len(soup_object.data.polygons)
    for obj in (mesh_object, soup_object):
        select_only(obj)
        assert bpy.ops.object.hc_smooth(**given) == {"FINISHED"}
    whole, soup = positions_of(mesh_object.data), positions_of(soup_object.data)
    assert np.abs(whole[origin] - soup).max() <= 1e-6
    noisy = noisy_sphere("Noisy", seed=4)
    assert np.abs(whole - positions_of(noisy.data)).max() > 1e-3  # it did smooth


def test_only_a_mesh_with_a_face_edge_on_one_face_is_searched_for_copies(scene):
    """A closed mesh has no seam an exporter split: the welding's search is skipped; a seam or an open
    border keeps it (the tests above show what it finds)."""
    jobs = sys.modules[ADDON + ".operators.mesh_objects"]
    settings = sys.modules[ADDON + ".cli.arguments"].Settings(iterations=10, auto_amount=False)
    seams = {}
    for name, obj in (
        ("closed", noisy_sphere("Closed")),
        ("seam", seamed_uv_sphere("Seam")[0]),
        ("open", noisy_grid("Open")),
    ):
        seams[name] = jobs.make_job(obj, settings).seams
    assert seams == {"closed": False, "seam": True, "open": True}
