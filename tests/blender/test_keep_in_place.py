"""Keep in Place through the add-on: the default moves vertices across the surface only, so a UV
map's texture stays where it was on the surface; off, the operator runs core's sliding default; set
numbers run the paper's algorithm; the command line's --slide switches it off."""

import sys

import bpy
import numpy as np
import pytest
from blender_scene import ADDON, edges_of, faces_of, positions_of, select_only

import core


def noisy_uv_sphere(name="Textured", sigma=0.01, seed=3):
    """Blender's UV Sphere (64 x 32, with its UV map) with noise along its normals."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=1.0)
    obj = bpy.context.active_object
    obj.name = obj.data.name = name
    positions = positions_of(obj.data).astype(np.float64)
    normals = positions / np.linalg.norm(positions, axis=1, keepdims=True)
    positions += normals * np.random.default_rng(seed).normal(0.0, sigma, (len(positions), 1))
    obj.data.vertices.foreach_set("co", positions.astype(np.float32).ravel())
    obj.data.update()
    return obj


def texture_v(obj):
    """Each vertex's v in the UV sphere's own UV map (v reads latitude: 0 at the south pole, 1 at the north)."""
    mesh = obj.data
    loops = np.empty(len(mesh.loops), dtype=np.int64)
    mesh.loops.foreach_get("vertex_index", loops)
    uv = np.empty(2 * len(mesh.loops), dtype=np.float32)
    mesh.uv_layers.active.data.foreach_get("uv", uv)
    v = np.zeros(len(mesh.vertices))
    v[loops] = uv.reshape(-1, 2)[:, 1]
    return v


def latitude_v(positions):
    """The v a position's direction reads in that map."""
    direction = positions / np.linalg.norm(positions, axis=1, keepdims=True)
    return np.arcsin(np.clip(direction[:, 2], -1, 1)) / np.pi + 0.5


def slide(before, after):
    """RMS along-surface part of each vertex's move (the unit sphere's normals are its directions)."""
    normals = before / np.linalg.norm(before, axis=1, keepdims=True)
    move = after - before
    tangent = move - np.einsum("ij,ij->i", move, normals)[:, None] * normals
    return float(np.sqrt(np.mean(np.sum(tangent**2, axis=1))))


def texture_shift(before, after):
    """RMS change, in v, of the point of the texture under each vertex, away from the poles: how far the
    texture swims under the vertices."""
    body = np.abs(before[:, 2]) < 0.9
    return float(np.sqrt(np.mean((latitude_v(after) - latitude_v(before))[body] ** 2)))


@pytest.mark.filterwarnings("ignore:HC is proven to converge only")
def test_the_default_keeps_the_texture_in_place(scene, capfd):
    """The textured sphere: the default's texture shift is a small share of the sliding default's, and
    the report says the vertices were kept in place."""
    kept, sliding = noisy_uv_sphere("Kept"), noisy_uv_sphere("Sliding")
    before = positions_of(kept.data).astype(np.float64)
    select_only(kept)
    assert bpy.ops.object.hc_smooth() == {"FINISHED"}
    assert "kept in place" in capfd.readouterr().out
    select_only(sliding)
    assert bpy.ops.object.hc_smooth(keep_in_place=False) == {"FINISHED"}
    assert "kept in place" not in capfd.readouterr().out
    after_kept = positions_of(kept.data).astype(np.float64)
    after_sliding = positions_of(sliding.data).astype(np.float64)
    # The measure reads the mesh's own UV map: each vertex's v is its input's latitude, to the noise.
    assert np.abs(texture_v(kept) - latitude_v(before))[np.abs(before[:, 2]) < 0.9].max() < 0.02
    assert slide(before, after_kept) <= 0.4 * slide(before, after_sliding)
    assert texture_shift(before, after_kept) <= 0.4 * texture_shift(before, after_sliding)
    # The noise goes all the same: the radius is nearer 1.
    radius_error = lambda points: np.abs(np.linalg.norm(points, axis=1) - 1.0).mean()  # noqa: E731
    assert radius_error(after_kept) < 0.6 * radius_error(before)


def test_off_and_set_numbers_equal_core(scene):
    """Keep in Place off runs core's sliding default; with numbers set it does not apply (the paper's
    algorithm, bit for bit), whether on or off."""
    obj = noisy_uv_sphere()
    before = positions_of(obj.data)
    triangles = core.geometry.fan_triangles(faces_of(obj.data))
    edges = edges_of(obj.data)
    assert bpy.ops.object.hc_smooth(keep_in_place=False) == {"FINISHED"}
    expected = core.smooth_mesh(before, edges, faces=triangles, weld=True, keep_in_place=False)
    np.testing.assert_allclose(positions_of(obj.data), expected, rtol=0, atol=1e-6)
    for keep in (True, False):
        obj.data.vertices.foreach_set("co", before.ravel())
        obj.data.update()
        assert bpy.ops.object.hc_smooth(auto_amount=False, iterations=5, keep_in_place=keep) == {"FINISHED"}
        paper = core.hc_smooth(before, edges, alpha=float(np.float32(0.1)), beta=float(np.float32(0.6)), iterations=5)
        assert np.array_equal(positions_of(obj.data), paper)


def test_the_panel_greys_keep_in_place_where_it_does_not_apply():
    spec = sys.modules[ADDON + ".settings_spec"]
    values = {s.name: s.default for s in spec.MESH}
    assert spec.KEEP_IN_PLACE.active(values)
    assert not spec.KEEP_IN_PLACE.active({**values, "auto_amount": False})
    assert not spec.KEEP_IN_PLACE.active({**values, "keep_sharp_edges": True})
    assert not spec.KEEP_IN_PLACE.active({**values, "method": "LAPLACIAN"})
