"""Split vertices are one surface (core.mesh.welding, MeshSmoother(weld=True)): UV seams and triangle soups
smooth like the welded mesh, copies move alike, the caller keeps every vertex."""

import numpy as np
import pytest
import scipy.sparse as sp
import small_meshes as sm
from scipy.sparse.csgraph import connected_components

import core
from core.mesh import welding


def noisy_sphere(rings=10, segments=16, sigma=0.08, seed=1):
    positions, faces = sm.uv_sphere(rings, segments)
    return sm.noisy(positions, sigma=sigma, seed=seed), np.array(faces)


def soup_of(positions, faces):
    """Every face with its own three vertices (an STL file, a flat-shaded PLY)."""
    return positions[faces].reshape(-1, 3), np.arange(faces.size).reshape(faces.shape)


def first_appearance(positions, faces):
    """The mesh renumbered in the order its vertices first appear in ``faces`` (a soup's welded order)."""
    order = np.unique(faces.ravel(), return_index=True)[1]
    seen = faces.ravel()[np.sort(order)]
    number = np.empty(len(positions), dtype=np.int64)
    number[seen] = np.arange(seen.size)
    return positions[seen], number[faces], number


def seam_split(positions, faces):
    """The sphere cut along a meridian as a UV seam cuts it: faces on one side of the meridian x > 0,
    y = 0 (poles excluded) use copies of its vertices, appended after the others."""
    on_seam = np.flatnonzero((np.abs(positions[:, 1]) < 1e-12) & (positions[:, 0] > 0.0))
    copy = np.full(len(positions), -1)
    copy[on_seam] = len(positions) + np.arange(on_seam.size)
    centroid_y = positions[faces].mean(axis=1)[:, 1]
    split = faces.copy()
    side = centroid_y < 0.0
    uses = side[:, None] & (copy[faces] >= 0)
    split[uses] = copy[faces][uses]
    return np.concatenate([positions, positions[on_seam]]), split, on_seam


def edges(faces):
    return sm.edges_of(faces.tolist())


@pytest.fixture(scope="module")
def sphere():
    return noisy_sphere()


@pytest.mark.parametrize("numbers", [{}, dict(alpha=0.1, beta=0.6, iterations=10)], ids=["automatic", "given"])
def test_a_uv_seam_does_not_open(sphere, numbers):
    clean, faces = sm.uv_sphere(10, 16)
    faces = np.array(faces)
    seam_positions, seam_faces, on_seam = seam_split(clean, faces)
    noisy = sphere[0]
    seam_noisy = np.concatenate([noisy, noisy[on_seam]])  # copies coincide, as in a file
    n = len(noisy)
    welded = core.smooth_mesh(seam_noisy, edges(seam_faces), faces=seam_faces, weld=True, **numbers)
    whole = core.smooth_mesh(noisy, edges(faces), faces=faces, **numbers)
    assert np.array_equal(welded[:n], whole)  # the welded mesh, bit for bit
    assert np.array_equal(welded[n:], welded[on_seam])  # the copies move as one
    apart = core.smooth_mesh(seam_noisy, edges(seam_faces), faces=seam_faces, **numbers)
    diagonal = np.linalg.norm(np.ptp(noisy, axis=0))
    gap = np.linalg.norm(apart[n:] - apart[on_seam], axis=1).max()
    assert gap > 1e-3 * diagonal  # without welding the seam opens


@pytest.mark.parametrize("mode", core.MODES)
@pytest.mark.parametrize("numbers", [{}, dict(alpha=0.1, beta=0.6, iterations=8)], ids=["automatic", "given"])
def test_a_triangle_soup_smooths_like_its_welded_mesh(sphere, mode, numbers):
    noisy, faces = sphere
    soup, soup_faces = soup_of(noisy, faces)
    result, report = core.smooth_mesh(
        soup, edges(soup_faces), faces=soup_faces, weld=True, mode=mode, return_report=True, **numbers
    )
    welded, welded_faces, number = first_appearance(noisy, faces)
    expected, expected_report = core.smooth_mesh(
        welded, edges(welded_faces), faces=welded_faces, mode=mode, return_report=True, **numbers
    )
    assert result.shape == soup.shape  # the caller keeps every vertex
    assert np.array_equal(result, expected[number[faces].ravel()])
    timings = {name: getattr(report, name) for name in ("seconds", "choosing_seconds", "finishing_seconds")}
    assert report == expected_report.__class__(**{**expected_report.__dict__, **timings})
    if not numbers:  # the soup's welded faces close: its volume is given back
        assert report.volume_offset > 0.0
        volumes = core.mesh.metrics.enclosed_volumes(soup_faces, soup, result)
        assert volumes[1] == pytest.approx(volumes[0], rel=1e-9)


def test_an_unwelded_soup_collapses_and_a_welded_one_keeps_its_area(sphere):
    noisy, faces = sphere
    soup, soup_faces = soup_of(noisy, faces)

    def area(points):
        a, b, c = (points[soup_faces[:, k]] for k in range(3))
        return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()

    welded = core.smooth_mesh(soup, edges(soup_faces), faces=soup_faces, weld=True)
    apart = core.smooth_mesh(soup, edges(soup_faces), faces=soup_faces, alpha=0.1, beta=0.6, iterations=10)
    assert area(welded) > 0.8 * area(soup)
    assert area(apart) < 0.5 * area(soup)


def test_float32_soup(sphere):
    noisy, faces = sphere
    soup, soup_faces = soup_of(noisy.astype(np.float32), faces)
    result = core.smooth_mesh(soup, edges(soup_faces), faces=soup_faces, weld=True, iterations=6)
    welded, welded_faces, number = first_appearance(noisy.astype(np.float32), faces)
    expected = core.smooth_mesh(welded, edges(welded_faces), faces=welded_faces, iterations=6)
    assert result.dtype == np.float32
    assert np.array_equal(result, expected[number[faces].ravel()])


def test_copies_within_the_tolerance_move_alike_and_keep_their_offset(sphere):
    noisy, faces = sphere
    seam_positions, seam_faces, on_seam = seam_split(sm.uv_sphere(10, 16)[0], faces)
    n = len(noisy)
    edge = core.geometry.median_edge_length(noisy, core.umbrella_operator(edges(faces), n))
    offset = np.random.default_rng(3).normal(size=(on_seam.size, 3))
    offset *= 0.3 * welding.TOLERANCE * edge / np.linalg.norm(offset, axis=1, keepdims=True)
    positions = np.concatenate([noisy, noisy[on_seam] + offset])
    result = core.smooth_mesh(positions, edges(seam_faces), faces=seam_faces, weld=True, iterations=5)
    moves = result - positions
    np.testing.assert_allclose(moves[n:], moves[on_seam], rtol=0, atol=1e-15)
    diagonal = np.linalg.norm(np.ptp(noisy, axis=0))
    assert np.linalg.norm(result[n:] - result[on_seam], axis=1).max() <= 1e-6 * diagonal
    # Ten times the tolerance apart: separate vertices, and the seam opens.
    positions = np.concatenate([noisy, noisy[on_seam] + 33 * offset])
    result = core.smooth_mesh(positions, edges(seam_faces), faces=seam_faces, weld=True, iterations=5)
    assert np.linalg.norm(result[n:] - result[on_seam], axis=1).max() > 1e-3 * diagonal


def test_a_copy_fixed_or_of_influence_zero_keeps_every_copy(sphere):
    clean, faces = sm.uv_sphere(10, 16)
    seam_positions, seam_faces, on_seam = seam_split(clean, np.array(faces))
    noisy = np.concatenate([sphere[0], sphere[0][on_seam]])
    n = len(sphere[0])
    pinned = [on_seam[2], n + 4]  # an original and a copy
    together = [on_seam[2], n + 2, on_seam[4], n + 4]
    fixed = np.zeros(len(noisy), dtype=bool)
    fixed[pinned] = True
    result = core.smooth_mesh(noisy, edges(seam_faces), faces=seam_faces, weld=True, fixed=fixed, iterations=5)
    assert np.array_equal(result[together].view(np.uint8), noisy[together].view(np.uint8))
    influence = np.ones(len(noisy))
    influence[pinned] = 0.0
    result = core.smooth_mesh(noisy, edges(seam_faces), faces=seam_faces, weld=True, influence=influence, iterations=5)
    assert np.array_equal(result[together].view(np.uint8), noisy[together].view(np.uint8))
    # Partial influence: the least of the copies'.
    influence[pinned] = 1.0
    influence[n + 4] = 0.25
    result = core.smooth_mesh(noisy, edges(seam_faces), faces=seam_faces, weld=True, influence=influence, iterations=5)
    whole_influence = np.ones(n)
    whole_influence[on_seam[4]] = 0.25
    whole = core.smooth_mesh(sphere[0], edges(np.array(faces)), faces=faces, influence=whole_influence, iterations=5)
    assert np.array_equal(result[:n], whole)


def test_without_coincident_vertices_welding_changes_nothing(sphere):
    noisy, faces = sphere
    operator = core.umbrella_operator(edges(faces), len(noisy))
    assert welding.weld(noisy, operator) is None
    for numbers in ({}, dict(iterations=5, mode="sequential")):
        plain = core.smooth_mesh(noisy, edges(faces), faces=faces, **numbers)
        assert np.array_equal(core.smooth_mesh(noisy, edges(faces), faces=faces, weld=True, **numbers), plain)


def brute_force_groups(points, radius):
    difference = points[:, None, :] - points[None, :, :]
    close = np.sqrt((difference**2).sum(axis=2)) <= radius
    return connected_components(sp.csr_matrix(close), directed=False)[1]


def same_partition(a, b):
    pairs = set(zip(a.tolist(), b.tolist()))
    return len(pairs) == len(set(a.tolist())) == len(set(b.tolist()))


@pytest.mark.parametrize("slot_bits", [welding._SLOT_BITS, 1], ids=["screened", "every point sorted"])
@pytest.mark.parametrize("spread", [1.0, 1e9], ids=["packed keys", "hashed keys"])
@pytest.mark.parametrize("seed", range(4))
def test_coincident_vertices_are_those_within_the_radius(monkeypatch, spread, seed, slot_bits):
    """Planted copies at 0, 0.5 and 0.99 of the radius (joined) and 1.5 and 3 radii (not), many of them
    across the sides of the cells the search sorts into; a brute-force union of all close pairs agrees,
    whether the hash table screens most points out of the sort or (two slots) sorts them all."""
    monkeypatch.setattr(welding, "_SLOT_BITS", slot_bits)
    rng = np.random.default_rng(seed)
    edge, tolerance = 0.01, 1e-3
    radius = edge * tolerance
    base = rng.random((150, 3))
    base[::5] = np.round(base[::5] / (edge * welding.CELL_EDGES)) * (edge * welding.CELL_EDGES)  # on cell sides
    base[-1] = spread  # far away: the cell coordinates outgrow the packed keys
    copies = [base]
    for distance in (0.0, 0.5, 0.99, 1.5, 3.0):
        direction = rng.normal(size=(30, 3))
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        copies.append(base[rng.integers(0, 149, 30)] + distance * radius * direction)
    points = np.concatenate(copies)[rng.permutation(150 + 5 * 30)]
    labels = core.slices.to_end(welding._coincident(points, edge, tolerance))
    expected = brute_force_groups(points, radius)
    assert labels is not None and same_partition(labels, expected)
    assert len(set(labels.tolist())) < len(points) - 60  # the planted copies within the radius joined


def test_weld_map_numbers_welded_vertices_by_their_first_copy():
    points = np.array([[1, 0, 0], [0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 0, 0], [-0.0, 0, 0]], dtype=float)
    operator = core.umbrella_operator([[0, 1], [1, 3], [2, 3], [3, 4]], 6)
    weld = welding.weld(points, operator)
    np.testing.assert_array_equal(weld.label, [0, 1, 0, 2, 1, 1])  # -0.0 equals 0.0
    np.testing.assert_array_equal(weld.first, [0, 1, 3])
    assert weld.near.size == 0
    assert welding.weld(points[:1], core.umbrella_operator(np.empty((0, 2), int), 1)) is None
    same = welding.weld(np.zeros((3, 3)), core.umbrella_operator([[0, 1]], 3))
    np.testing.assert_array_equal(same.label, [0, 0, 0])
