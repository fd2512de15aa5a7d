"""core.measure_change: displacement, bounding box, closed-mesh volume."""

import numpy as np
import pytest
import small_meshes as sm

import core
from core.geometry import fan_triangles
from core.mesh.topology import closed_from_triangles as is_closed


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
    assert change.rms_displacement == pytest.approx(2.0 / np.sqrt(len(positions)))
    assert abs(change.normal_displacement) == pytest.approx(2.0 / len(positions))  # the grid is flat: all along
    text = change.summary()
    assert text.startswith(f"1 of {len(positions)} vertices moved, largest move ")
    assert f"({2.0:.3g})" in text and "along the normals" in text and "volume" not in text


def test_a_uniform_shrink_shows_as_a_negative_move_along_the_normals():
    """Open: the mean move along the normals says it; closed: the volume does (no pass of normals)."""
    positions, faces = sm.uv_sphere(24, 48)
    faces = np.array(faces)
    open_faces = faces[positions[faces][:, :, 2].max(axis=1) < positions[:, 2].max()]  # the top pole's fan gone
    change = core.measure_change(positions, positions * 0.99, faces=open_faces)
    assert not change.closed and change.normal_displacement == pytest.approx(-0.01, rel=2e-3)
    assert "along the normals -0.2" in change.summary() and "volume" not in change.summary()
    change = core.measure_change(positions, positions * 0.99, faces=faces)
    assert change.closed and change.normal_displacement is None
    assert change.rms_displacement == pytest.approx(0.01, rel=1e-3)
    assert "volume -2.97%" in change.summary() and "along the normals" not in change.summary()
    assert core.measure_change(positions, positions * 0.99).normal_displacement is None  # no faces, no normals


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


def test_triangles_come_back_without_a_copy_in_either_layout():
    positions, faces = sm.octahedron()
    triangles = np.array(faces, dtype=np.int32)
    assert fan_triangles(triangles) is triangles
    same = fan_triangles(polygons(faces))
    assert np.array_equal(same, triangles) and same.base is not None  # a view of the corner array


def test_a_list_of_faces_of_mixed_sizes_is_fanned_like_its_polygons():
    positions, faces = sm.pentagonal_prism()
    as_lists = [list(face) for face in faces]
    assert len({len(face) for face in as_lists}) > 1
    assert np.array_equal(fan_triangles(as_lists), fan_triangles(polygons(faces)))
    change = core.measure_change(positions, positions * 1.1, faces=as_lists)
    assert change.volume_change == pytest.approx(1.1**3 - 1)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("offset", [0.0, 1e3])
def test_volume_in_the_arrays_precision_far_from_the_origin(dtype, offset):
    """Single precision keeps its digits: the terms are measured from the box centre, not the origin."""
    positions, faces = sm.uv_sphere(40, 80)
    triangles = fan_triangles(np.array(faces))
    exact = core.mesh.metrics.enclosed_volumes(triangles, positions)[0]
    moved = (positions + offset).astype(dtype)
    got, scaled = core.mesh.metrics.enclosed_volumes(triangles, moved, (positions * 1.1 + offset).astype(dtype))
    assert got == pytest.approx(exact, rel=1e-5 if dtype == np.float32 else 1e-12)
    assert scaled == pytest.approx(exact * 1.1**3, rel=1e-5 if dtype == np.float32 else 1e-12)


def test_volume_blocks_and_threads_add_up(monkeypatch):
    positions, faces = sm.uv_sphere(60, 120)
    triangles = fan_triangles(np.array(faces))
    whole = core.mesh.metrics.enclosed_volumes(triangles, positions, positions * 2)
    monkeypatch.setattr(core.mesh.metrics, "_VOLUME_BLOCK", 7)  # many blocks, and sets side by side on threads
    blocks = core.mesh.metrics.enclosed_volumes(triangles, positions, positions * 2)
    np.testing.assert_allclose(blocks, whole, rtol=1e-12)
    assert whole[1] == pytest.approx(8 * whole[0], rel=1e-12)


def blender_layout(faces, extra_edges=()):
    """edges, corner_verts, corner_edges as Blender stores a mesh of these faces."""
    pairs = {}
    corner_verts, corner_edges = [], []
    for face in faces:
        for a, b in zip(face, list(face[1:]) + [face[0]]):
            key = (min(a, b), max(a, b))
            pairs.setdefault(key, len(pairs))
            corner_verts.append(a)
            corner_edges.append(pairs[key])
    for a, b in extra_edges:
        pairs.setdefault((a, b), len(pairs))
    edges = np.array(sorted(pairs, key=pairs.get))
    return edges, np.array(corner_verts, dtype=np.int32), np.array(corner_edges, dtype=np.int32)


def test_closed_from_corners_agrees_with_the_triangles():
    _, octahedron = sm.octahedron()
    _, cube = sm.cube_quads()
    flipped = [octahedron[0][::-1]] + octahedron[1:]
    three_faces_on_an_edge = octahedron + [[0, 2, 5]]
    cases = [
        (octahedron, True),
        (cube, True),
        (octahedron[1:], False),
        (flipped, False),
        (three_faces_on_an_edge, False),
    ]
    for faces, expected in cases:
        edges, corner_verts, corner_edges = blender_layout(faces, extra_edges=[(0, 1)])  # a loose edge
        assert core.mesh.topology.closed_from_corners(edges, corner_verts, corner_edges) is expected, faces
        assert is_closed(fan_triangles(polygons(faces))) is expected, faces


def test_border_vertices_are_those_of_one_face_edges():
    _, faces = sm.grid(4, 3)
    boundary = np.zeros(12, dtype=bool)
    boundary[core.mesh.borders.border_edges(fan_triangles(polygons(faces)), 12).ravel()] = True
    assert np.array_equal(np.flatnonzero(~boundary), [5, 6])  # the two inner vertices of a 4 x 3 grid


@pytest.mark.parametrize("scale", [2.0**-540, 1.0, 2.0**540])
def test_displacements_at_any_scale(scale):
    positions, faces = sm.uv_sphere(8, 12)
    moved = positions.copy()
    moved[3] += [0.0, 0.0, 0.5]
    moved[7] += [0.3, 0.4, 0.0]
    change = core.measure_change(positions * scale, moved * scale, faces=np.array(faces))
    unit = core.measure_change(positions, moved, faces=np.array(faces))
    assert change.volume_change == pytest.approx(unit.volume_change, rel=1e-12) and unit.volume_change > 0
    assert change.moved == 2
    assert change.max_displacement == pytest.approx(0.5 * scale, rel=1e-12)
    assert change.mean_displacement == pytest.approx(1.0 / len(positions) * scale, rel=1e-12)


@pytest.mark.parametrize("shape", ["closed", "open"])
def test_a_measured_input_gives_the_same_change(shape):
    """measure_input done first (as the operators do, on another thread) changes nothing in the report."""
    positions, faces = sm.uv_sphere(20, 40)
    faces = np.array(faces)
    if shape == "open":
        faces = faces[1:]
    moved = positions + np.random.default_rng(3).normal(0.0, 0.01, positions.shape)
    direct = core.measure_change(positions, moved, faces=faces)
    measured = core.mesh.metrics.measure_input(positions, faces)
    assert measured.closed is (shape == "closed")
    assert core.measure_change(positions, moved, measured=measured) == direct
    assert (direct.volume_change is not None) is (shape == "closed")
    with pytest.raises(ValueError, match="measured is of"):
        core.measure_change(positions[:-1], moved[:-1], measured=measured)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_volume_near_and_far_from_the_origin_agree(dtype):
    """Near the origin the positions are used in place, far away a centred copy: the same volume."""
    positions, faces = sm.uv_sphere(30, 60)
    triangles = fan_triangles(np.array(faces))
    near = core.mesh.metrics.enclosed_volume(positions.astype(dtype), triangles)
    far = core.mesh.metrics.enclosed_volume((positions + 50.0).astype(dtype), triangles)
    assert near == pytest.approx(far, rel=1e-6 if dtype == np.float32 else 1e-12)


def test_the_report_is_the_same_on_any_number_of_threads(monkeypatch):
    """measure_change spreads a big mesh's volume over the threads: the same bits as on one."""
    positions, faces = sm.uv_sphere(60, 120)
    moved = positions * 1.01 + np.random.default_rng(2).normal(0.0, 1e-3, positions.shape)
    monkeypatch.setattr(core.mesh.metrics, "_VOLUME_BLOCK", 64)  # many blocks: a big mesh in miniature
    changes = []
    for threads in (1, 2, 3):
        monkeypatch.setattr(core.mesh.metrics.parallel, "thread_count", lambda threads=threads: threads)
        changes.append(core.measure_change(positions, moved, faces=np.array(faces)))
    assert changes[0] == changes[1] == changes[2]
    assert changes[0].volume_change == pytest.approx(1.01**3 - 1, rel=1e-2)
