"""core.measure_change: displacement, bounding box, closed-mesh volume."""

import numpy as np
import pytest

import core
import small_meshes as sm
from core.metrics import fan_triangles, is_closed


def polygons(faces):
    """Blender's layout: offsets (f + 1) and corner vertices."""
    sizes = [len(f) for f in faces]
    return np.concatenate([[0], np.cumsum(sizes)]), np.concatenate(faces)


def test_unit_cube_of_quads_has_volume_one_and_is_closed():
    positions, faces = sm.cube_quads()
    change = core.measure_change(positions, positions * 2.0, faces=np.array(faces))
    assert change.closed
    assert change.volume_before == pytest.approx(1.0) and change.volume_after == pytest.approx(8.0)
    assert change.volume_change == pytest.approx(7.0)
    assert change.bbox_change == pytest.approx(1.0)


def test_ngons_in_blender_layout():
    positions, faces = sm.pentagonal_prism()
    change = core.measure_change(positions, positions, faces=polygons(faces))
    area = 5 / 2 * np.sin(2 * np.pi / 5)  # regular pentagon of circumradius 1
    assert change.closed and change.volume_before == pytest.approx(area)
    assert change.moved == 0 and change.volume_change == 0.0


def test_open_mesh_reports_no_volume():
    positions, faces = sm.grid(4, 3)
    moved = positions.copy()
    moved[5] += [0, 0, 2.0]
    change = core.measure_change(positions, moved, faces=np.array(faces))
    assert not change.closed and change.volume_change is None
    assert change.moved == 1 and change.max_displacement == pytest.approx(2.0)
    assert change.mean_displacement == pytest.approx(2.0 / len(positions))
    assert "bounding box" in change.summary()


def test_sphere_volume_and_orientation():
    positions, faces = sm.uv_sphere(24, 48)
    change = core.measure_change(positions, positions, faces=np.array(faces))
    assert change.closed and change.volume_before == pytest.approx(4 / 3 * np.pi, rel=0.02)
    flipped = [f[::-1] for f in faces]
    assert core.measure_change(positions, positions, faces=np.array(flipped)).volume_before < 0


def test_inconsistent_orientation_or_hole_is_not_closed():
    positions, faces = sm.octahedron()
    faces = np.array(faces)
    assert is_closed(fan_triangles(faces))
    assert not is_closed(fan_triangles(faces[1:]))
    bad = faces.copy()
    bad[0] = bad[0][::-1]
    assert not is_closed(fan_triangles(bad))


def test_bad_faces_and_shapes():
    positions, faces = sm.octahedron()
    with pytest.raises(ValueError, match="same shape"):
        core.measure_change(positions, positions[:3])
    with pytest.raises(ValueError, match="do not exist"):
        core.measure_change(positions, positions, faces=np.array([[0, 1, 9]]))
    with pytest.raises(ValueError, match="offsets"):
        core.measure_change(positions, positions, faces=(np.array([0, 2]), np.array([0, 1])))
