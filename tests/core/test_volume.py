"""core.mesh.volume.restore_volume: each closed part back to its volume by a uniform offset along the normals."""

import numpy as np
import pytest
from test_mesh_amount import icosphere

import core
from core.geometry import vertex_normals
from core.mesh.volume import restore_volume


def volume(points, triangles):
    return core.mesh.metrics.enclosed_volume(points, triangles)


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


@pytest.mark.parametrize("kept", [1e-3, 0.4])
def test_a_collapsed_part_is_not_blown_up(kept):
    """A part flattened to less than half its volume collapsed: its volume's root lies far away, and no
    offset is made; one that kept more is restored within bounds."""
    vertices, faces = icosphere(2)
    flat = vertices * [1.0, 1.0, kept]
    restored, offsets = restore_volume(vertices, flat, faces)
    assert offsets[0] == 0.0 and np.array_equal(restored, flat)
    _, offsets = restore_volume(vertices, vertices * [1.0, 1.0, 0.6], faces)
    assert 0.0 < offsets[0] <= 0.01 + 1e-12


def test_the_offset_is_bounded_by_the_box_and_the_limit():
    vertices, faces = icosphere(3)
    # Flattened by 20 %: the root (~0.07) would widen the box by 7 %; the offset stops at 1 % (0.01 a side).
    restored, offsets = restore_volume(vertices, vertices * [1.0, 1.0, 0.8], faces)
    assert offsets[0] == pytest.approx(0.01, rel=1e-9)
    assert np.ptp(restored[:, :2], axis=0) == pytest.approx(1.01 * np.ptp(vertices[:, :2], axis=0), rel=1e-3)
    assert volume(restored, faces) < volume(vertices, faces)
    _, limited = restore_volume(vertices, vertices * 0.99, faces, limit=0.004)
    assert limited[0] == 0.004
    _, free = restore_volume(vertices, vertices * 0.99, faces, limit=0.02)
    assert 0.0 < free[0] < 0.02
    inward, shrunk = restore_volume(vertices, vertices * 1.05, faces, limit=0.01)
    assert shrunk[0] == -0.01 and np.all(np.ptp(inward, axis=0) < np.ptp(vertices * 1.05, axis=0))


def test_only_closed_parts_with_a_volume_and_more_than_four_vertices():
    """An open part, a tetrahedron, a closed part with no volume (two faces back to back) and an
    inside-out part beside a sphere: only the sphere is restored; the inside-out one too (its volume is
    negative, the offset along its inward normals still gives it back)."""
    vertices, faces = icosphere(2)
    n = len(vertices)
    tetrahedron = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float) * 0.5 + [3, 0, 0]
    sheet = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float) + [6, 0, 0]
    parts = [
        (vertices, faces),  # closed sphere
        (vertices + [0, 3, 0], faces[1:]),  # open: one face less
        (tetrahedron, np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])),
        (sheet, np.array([[0, 1, 2], [0, 2, 1]])),  # closed, no volume
        (vertices + [0, -3, 0], faces[:, ::-1]),  # inside out
    ]
    before, triangles, offset = [], [], 0
    for points, tris in parts:
        before.append(points)
        triangles.append(tris + offset)
        offset += len(points)
    before, triangles = np.concatenate(before), np.concatenate(triangles)
    centres = np.repeat([[0, 0, 0], [0, 3, 0], [3, 0, 0], [6, 0, 0], [0, -3, 0]], [n, n, 4, 3, n], axis=0)
    after = centres + (before - centres) * 0.995
    restored, offsets = restore_volume(before, after, triangles)
    assert offsets[0] > 0 and offsets[4] < 0 and np.all(offsets[1:4] == 0.0)
    assert np.array_equal(restored[n : 2 * n + 7], after[n : 2 * n + 7])
    for part, sign in ((slice(0, n), 1), (slice(2 * n + 7, 3 * n + 7), -1)):
        local = faces if sign > 0 else faces[:, ::-1]
        assert volume(restored[part], local) == pytest.approx(volume(before[part], local), rel=1e-9)


def test_given_directions_make_the_measures_and_the_cubic_in_one_pass():
    """Offset directions given (Keep in Place's normals): the measures and the cubic come from one pass over
    the triangles, the same numbers as the two passes that make the normals first: given the normals those
    passes make, the restore is bit for bit the one without them (two parts, fixed vertices)."""
    from core.geometry import normals_and_measures
    from core.mesh import topology
    from core.mesh import volume as restore
    from core.slices import to_end

    vertices, triangles = icosphere(3)
    before = np.r_[vertices, vertices * 0.5 + 3.0]
    faces = np.r_[triangles, triangles + len(vertices)]
    rng = np.random.default_rng(2)
    after = 0.97 * before + rng.normal(scale=0.01, size=before.shape)
    movable = rng.random(len(before)) > 0.1
    surface = topology.surface(faces, len(before))
    measured = restore.measure_before(before, faces, surface)
    planar = restore.as_planar(after)
    normals = to_end(
        normals_and_measures(planar, faces, surface.part_of_vertex, surface.parts, measured.centre, restore.BLOCK)
    )[0]
    two = to_end(restore.restore_steps(before, after, faces, movable, None, np.float64, surface, measured))
    one = to_end(restore.restore_steps(before, after, faces, movable, None, np.float64, surface, measured, normals))
    assert np.array_equal(one[0], two[0]) and np.array_equal(one[1], two[1]) and np.all(one[1] > 0.0)
