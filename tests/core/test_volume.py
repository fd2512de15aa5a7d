"""core.volume.restore_volume: each closed part back to its volume by a uniform offset along the normals."""

import numpy as np
import pytest
from test_mesh_amount import icosphere

import core
from core.volume import restore_volume, vertex_normals


def volume(points, triangles):
    return core.metrics.enclosed_volume(points, triangles)


def test_shrunk_sphere_gets_its_volume_and_radius_back():
    vertices, faces = icosphere(3)
    shrunk = vertices * 0.95
    restored, offsets = restore_volume(vertices, shrunk, faces)
    assert volume(restored, faces) == pytest.approx(volume(vertices, faces), rel=1e-10)
    assert offsets.shape == (1,) and offsets[0] > 0
    # A uniform offset of a sphere is a sphere (the area-weighted normals are radial to ~1e-6).
    radii = np.linalg.norm(restored, axis=1)
    assert np.ptp(radii) < 1e-5


def test_each_part_separately_and_fixed_vertices_stay():
    vertices, faces = icosphere(2)
    n = len(vertices)
    before = np.concatenate([vertices, vertices * 0.5 + [3.0, 0.0, 0.0]])
    triangles = np.concatenate([faces, faces + n])
    after = np.concatenate([vertices * 0.9, (vertices * 0.5) * 1.02 + [3.0, 0.0, 0.0]])
    movable = np.ones(2 * n, bool)
    movable[:5] = False
    restored, offsets = restore_volume(before, after, triangles, movable=movable)
    assert offsets[0] > 0 > offsets[1]
    assert np.array_equal(restored[:5], after[:5])
    for part in (slice(0, n), slice(n, 2 * n)):
        assert volume(restored[part], faces) == pytest.approx(volume(before[part], faces), rel=1e-9)


def test_scale_and_nothing_to_do():
    vertices, faces = icosphere(2)
    for scale in (1e-5, 1e4):
        before = vertices * scale
        restored, offsets = restore_volume(before, before * 0.97, faces)
        assert volume(restored, faces) == pytest.approx(volume(before, faces), rel=1e-9)
        assert offsets[0] / scale == pytest.approx(restore_volume(vertices, vertices * 0.97, faces)[1][0], rel=1e-9)
    same, offsets = restore_volume(vertices, vertices, faces)
    assert np.allclose(same, vertices, atol=1e-15) and abs(offsets[0]) < 1e-15
    fixed, offsets = restore_volume(vertices, vertices * 0.9, faces, movable=np.zeros(len(vertices), bool))
    assert np.array_equal(fixed, vertices * 0.9)


def test_float32_in_float64_out_and_normals():
    vertices, faces = icosphere(2)
    restored, _ = restore_volume(vertices.astype(np.float32), (vertices * 0.9).astype(np.float32), faces)
    assert restored.dtype == np.float64
    normals = vertex_normals(vertices, faces)
    assert np.allclose(np.einsum("ij,ij->i", normals, vertices), 1.0, atol=0.02)
