"""Keep in Place (core.mesh.in_place): the default moves vertices across the surface, not along it, so
textures, UVs and open outlines stay where they were; set numbers still run the paper's algorithm."""

import warnings

import numpy as np
import pytest

import core
from bench.primitives import grid, ico_sphere
from core import parallel
from core.geometry import vertex_normals
from core.mesh.borders import border_edges
from core.mesh.in_place import (
    Outline,
    curve_labels,
    inward_directions,
    keep_in_place,
    keep_in_place_steps,
    outline_curves,
)


def _noisy_along_normals(part, sigma, seed=0):
    triangles = part.triangles()
    normals = vertex_normals(part.positions, triangles)
    rng = np.random.default_rng(seed)
    return part.positions + normals * rng.normal(0.0, sigma, (len(normals), 1)), triangles


def _slide(start, result, normals):
    """RMS of the along-surface part of each vertex's move (against the given unit normals)."""
    move = result - start
    tangent = move - np.einsum("ij,ij->i", move, normals)[:, None] * normals
    return float(np.sqrt(np.mean(np.sum(tangent**2, axis=1))))


@pytest.fixture(scope="module")
def sphere():
    """A noisy unit Ico Sphere (2,562 vertices), noise along the normals."""
    part = ico_sphere(5)
    noisy, triangles = _noisy_along_normals(part, 0.01)
    return part, noisy, triangles


def test_each_move_is_along_the_result_normal():
    """keep_in_place keeps exactly the normal part of each move: what is left is parallel to the normal."""
    part = ico_sphere(3)
    rng = np.random.default_rng(1)
    start = part.positions + rng.normal(0, 0.02, part.positions.shape)
    result = part.positions * 1.01
    kept = keep_in_place(start, result, part.triangles())
    normals = vertex_normals(result, part.triangles())
    move = kept - start
    assert np.abs(np.cross(move, normals)).max() < 1e-12
    assert np.allclose(np.einsum("ij,ij->i", move, normals), np.einsum("ij,ij->i", result - start, normals))


def test_a_crease_vertex_keeps_its_move_across_both_faces():
    """Two faces meeting at 90 degrees along the y axis: a vertex on the crease keeps the part of its move that
    its faces face (x and z), and gives up the part along the crease (y); a vertex inside a face keeps the
    part along its normal only."""
    ys = np.arange(5.0)
    floor = [(x, y, 0.0) for y in ys for x in (-2.0, -1.0, 0.0)]  # the crease: x = 0, z = 0
    wall = [(0.0, y, z) for y in ys for z in (1.0, 2.0)]
    result = np.array(floor + wall)
    index = {tuple(p): i for i, p in enumerate(floor + wall)}
    triangles = []
    for y in ys[:-1]:
        for strip in ([(-2.0, 0.0), (-1.0, 0.0), (0.0, 0.0)], [(0.0, 0.0), (0.0, 1.0), (0.0, 2.0)]):
            for (a, b), (c, d) in zip(strip, strip[1:]):
                p, q = (a, y, b), (c, y, d)
                r, s = (c, y + 1, d), (a, y + 1, b)
                triangles += [(index[p], index[q], index[r]), (index[p], index[r], index[s])]
    triangles = np.array(triangles)
    move = np.zeros_like(result)
    crease, inside = index[(0.0, 2.0, 0.0)], index[(-1.0, 2.0, 0.0)]
    move[crease] = move[inside] = [0.01, 0.02, 0.03]
    kept = keep_in_place(result - move, result, triangles)
    np.testing.assert_allclose(kept[crease] - (result - move)[crease], [0.01, 0.0, 0.03], atol=1e-12)
    normal = vertex_normals(result, triangles)[inside]
    np.testing.assert_allclose(kept[inside] - (result - move)[inside], (move[inside] @ normal) * normal, atol=1e-12)


def test_still_and_faceless_vertices_keep_their_result():
    part = ico_sphere(2)
    positions = np.vstack([part.positions, [[5.0, 5.0, 5.0]]])  # a loose vertex, in no triangle
    result = positions * 1.1
    result[3] = positions[3]  # did not move
    kept = keep_in_place(positions, result, part.triangles())
    assert np.array_equal(kept[3], positions[3]) and np.array_equal(kept[-1], result[-1])
    assert kept.dtype == result.dtype
    as_float32 = keep_in_place(positions.astype(np.float32), result.astype(np.float32), part.triangles())
    assert as_float32.dtype == np.float32


def test_default_keeps_vertices_in_place_and_removes_the_noise(sphere):
    """On a noisy sphere the default's slide is a small share of the sliding default's, the noise goes
    as well (distance to the clean sphere), and the report says the vertices were kept in place."""
    part, noisy, triangles = sphere
    edges = part.edges
    kept, report = core.smooth_mesh(noisy, edges, faces=triangles, return_report=True)
    sliding, slid_report = core.smooth_mesh(noisy, edges, faces=triangles, keep_in_place=False, return_report=True)
    assert report.kept_in_place and not slid_report.kept_in_place
    clean_normals = part.positions  # the unit sphere's normals
    assert _slide(noisy, kept, clean_normals) <= 0.4 * _slide(noisy, sliding, clean_normals)

    def error(points):
        return float(np.sqrt(np.mean((np.linalg.norm(points, axis=1) - 1.0) ** 2)))

    assert error(kept) < 0.5 * error(noisy)
    assert error(kept) <= 1.05 * error(sliding)
    # Each vertex's own clean position: the kept default is nearer than the sliding one.
    assert np.linalg.norm(kept - part.positions) < np.linalg.norm(sliding - part.positions)


def test_texture_stays_where_it_was(sphere):
    """A texture's point on each vertex is where the vertex sits on the surface (here: its direction on
    the unit sphere, as a spherical UV map reads it). Smoothing noise along the normals must not move it:
    the default shifts it by a small share of the noise, the sliding default by far more."""
    part, noisy, triangles = sphere

    def texture_shift(points):  # angle between each vertex's texture point before and after, RMS
        before = noisy / np.linalg.norm(noisy, axis=1, keepdims=True)
        after = points / np.linalg.norm(points, axis=1, keepdims=True)
        return float(np.sqrt(np.mean(np.arccos(np.clip(np.einsum("ij,ij->i", before, after), -1, 1)) ** 2)))

    kept = core.smooth_mesh(noisy, part.edges, faces=triangles)
    sliding = core.smooth_mesh(noisy, part.edges, faces=triangles, keep_in_place=False)
    sigma = 0.01
    assert texture_shift(kept) <= 0.4 * texture_shift(sliding)
    assert texture_shift(kept) < 0.25 * sigma  # radians on a unit sphere: distance along it


def test_a_georeferenced_mesh_is_kept_in_place_as_at_the_origin(sphere):
    """A scan millions of units from the origin (georeferenced, in double precision) keeps its vertices
    in place as the same scan at the origin does: the fold check reads each triangle's shape, not where
    it lies."""
    part, noisy, triangles = sphere
    offset = np.array([500_000.0, 5_000_000.0, 0.0])
    here, report = core.smooth_mesh(noisy, part.edges, faces=triangles, return_report=True)
    far = core.smooth_mesh(noisy + offset, part.edges, faces=triangles) - offset
    assert report.kept_in_place
    assert np.abs(far - here).max() < 1e-6 * 0.01  # a millionth of the noise: double rounding at 5e6
    result = keep_in_place(noisy + offset, here + offset, triangles) - offset
    assert np.abs(result - keep_in_place(noisy, here, triangles)).max() < 1e-8


def test_keep_in_place_yields_between_its_passes():
    """Keep in Place runs in slices (a cancel or a progress line waits for one slice, not the whole
    projection: seconds on a 5M-vertex scan): it yields at least once per round of blocks of triangles of
    the vertex normals and after the projection, the crease rule and the fold check, and ends with
    keep_in_place's result; the default's steps yield as many more where it runs (on an open grid: on a
    closed mesh the volume restore then makes its measures in one pass instead of two, a round fewer)."""
    part = ico_sphere(7)  # 327,680 triangles: more than one round of blocks
    noisy, triangles = _noisy_along_normals(part, 0.002)
    result = core.smooth_mesh(noisy, part.edges, faces=triangles, alpha=0.0, beta=0.6, iterations=10)
    steps, yields = keep_in_place_steps(noisy, result, triangles), 0
    while True:
        try:
            next(steps)
        except StopIteration as done:
            kept = done.value
            break
        yields += 1
    rounds = -(-len(triangles) // (parallel.TRIANGLE_BLOCK * parallel.thread_count()))
    assert rounds >= 2 and yields >= rounds + 3
    assert np.array_equal(kept, keep_in_place(noisy, result, triangles))

    sheet = grid(410)  # 336,200 triangles, open
    flat, flat_triangles = _noisy_along_normals(sheet, 0.002)
    rounds = -(-len(flat_triangles) // (parallel.TRIANGLE_BLOCK * parallel.thread_count()))

    def slices(**options):
        return sum(1 for _ in core.MeshSmoother(flat, sheet.edges, faces=flat_triangles, **options).steps(1))

    assert rounds >= 2 and slices() >= slices(keep_in_place=False) + rounds + 3


def test_open_outline_is_not_pulled_in():
    """Blender's Grid (40 quads a side) with noise along z: the default keeps the outline's length and the
    enclosed area within 1 % of the clean ones; without Keep in Place the border is pulled in."""
    part = grid(40)
    rng = np.random.default_rng(2)
    noisy = part.positions + [0, 0, 1] * rng.normal(0.0, 0.01, (len(part.positions), 1))
    triangles = part.triangles()
    kept = core.smooth_mesh(noisy, part.edges, faces=triangles, weld=True)
    sliding = core.smooth_mesh(noisy, part.edges, faces=triangles, weld=True, keep_in_place=False)
    assert np.std(kept[:, 2]) < 0.5 * np.std(noisy[:, 2])

    def area(points):  # the xy area the border encloses: the grid's xy extent, as its outline is a square
        border = (np.abs(part.positions[:, :2]) == 1.0).any(axis=1)
        return float(np.ptp(points[border, 0]) * np.ptp(points[border, 1])), np.abs(points[border, :2]).mean()

    clean_area, clean_reach = area(part.positions)
    kept_area, kept_reach = area(kept)
    assert abs(kept_area / clean_area - 1) < 0.01 and abs(kept_reach / clean_reach - 1) < 0.01
    sliding_reach = area(sliding)[1]
    assert sliding_reach < kept_reach


def test_outline_is_smoothed_as_a_curve_where_noise_folds_the_layout():
    """Grid with noise along every axis at 0.6 edge lengths: the layout folds, so vertices take their slide
    back, but the outline takes back only its move across the border curve: no pull-in, half its jaggies
    gone; sliding, it is pulled in by more than the noise."""
    part = grid(40)
    sigma = 0.03
    noisy = part.positions + np.random.default_rng(2).normal(0.0, sigma, part.positions.shape)
    triangles = part.triangles()
    on_side = (np.abs(part.positions[:, :2]) == 1.0).any(axis=1) & ~(np.abs(part.positions[:, :2]) == 1.0).all(axis=1)
    axis = np.abs(part.positions[on_side, :2]).argmax(axis=1)

    def inward(points):  # each side vertex's offset from its clean side line, into the grid
        return 1.0 - np.abs(points[on_side][np.arange(axis.size), axis])

    kept = core.smooth_mesh(noisy, part.edges, faces=triangles, weld=True)
    sliding = core.smooth_mesh(noisy, part.edges, faces=triangles, weld=True, keep_in_place=False)
    assert abs(inward(kept).mean()) < 0.1 * sigma < sigma < inward(sliding).mean()
    assert np.sqrt(np.mean(inward(kept) ** 2)) < 0.5 * np.sqrt(np.mean(inward(noisy) ** 2))


def test_an_outline_vertex_takes_back_no_more_across_its_curve_than_the_smoother_moved_it():
    """A ragged outline (a jag of the grid's rim pulled out by two edges): smoothing the rim as a curve
    rounds the jag off by about that much, where the smoother moved the vertex by the noise alone. What the
    jag's vertex takes back across its curve (where keeping folds) is at most its whole move; the other
    outline vertices, whose curve moves are within their moves, keep theirs."""
    part = grid(6)
    positions = part.positions.copy()
    triangles = part.triangles()
    n = len(positions)
    edges = border_edges(triangles, n)
    vertices, before, after = outline_curves(edges, n)
    jag = vertices[np.argmin(np.abs(positions[vertices, 0] - 1.0) + np.abs(positions[vertices, 1]))]  # mid right side
    positions[jag, 0] += 2.0 * (2.0 / 6)  # two edges out
    border = np.unique(edges)
    curve = positions[border].copy()
    curve[np.searchsorted(border, jag), 0] -= 2.0 * (2.0 / 6)  # the curve smoothing rounds the jag off
    operator = core.umbrella_operator(part.edges, n)
    outline = Outline(
        vertices,
        before,
        after,
        inward_directions(positions, operator, vertices),
        curve_labels(edges, vertices),
        border,
        curve,
    )
    move = np.tile([0.01, 0.02, 0.05], (n, 1))  # the smoother's move: noise along z, a little slide
    result = positions + move
    normals = np.tile([0.0, 0.0, 1.0], (vertices.size, 1))
    target = outline.across(positions, result, normals)
    across = np.linalg.norm((target - positions)[vertices, :2], axis=1)  # the in-plane part: across the curve
    reach = np.linalg.norm(move[vertices], axis=1)
    assert np.all(across <= reach + 1e-12)
    assert across[vertices == jag][0] == pytest.approx(reach[vertices == jag][0])  # rounded back by all it may
    others = vertices != jag
    assert np.allclose(across[others], 0.0)  # the rest of the rim's curve stayed: nothing to take back
    assert np.allclose((target - positions)[vertices, 2], 0.05)  # the move along the normal stays whole


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_no_vertex_of_a_ragged_open_grid_moves_much_farther_than_the_smoother_moved_it(seed):
    """A 30 x 30 grid whose rim juts out by 0.8 edges at random, noise of 0.3 edges along every axis (the layout
    folds): kept in place, a vertex moves at most its smoother's move along its normal, and an outline vertex
    that takes its slide back at most its whole move across its curve besides: never more than sqrt(2) times
    what the sliding default moved it (the rim's jags were rounded off by up to three times that)."""
    part = grid(30)
    positions = part.positions.copy()
    edge = 2.0 / 30
    rng = np.random.default_rng(seed)
    on_side = (np.abs(positions[:, :2]) == 1.0).any(axis=1) & ~(np.abs(positions[:, :2]) == 1.0).all(axis=1)
    side = np.flatnonzero(on_side)
    axis = np.abs(positions[side, :2]).argmax(axis=1)
    positions[side, axis] += np.sign(positions[side, axis]) * rng.choice([0.0, 0.8 * edge], side.size)
    noisy = positions + rng.normal(0.0, 0.3 * edge, positions.shape)
    triangles = part.triangles()
    kept = core.smooth_mesh(noisy, part.edges, faces=triangles, weld=True)
    sliding = core.smooth_mesh(noisy, part.edges, faces=triangles, weld=True, keep_in_place=False)
    moved, slid = np.linalg.norm(kept - noisy, axis=1), np.linalg.norm(sliding - noisy, axis=1)
    assert np.all(moved <= np.sqrt(2.0) * slid * (1 + 1e-9) + 1e-15)


def test_outline_curves_lists_each_border_vertex_between_its_two_neighbours():
    """A strip of two quads: six border vertices in one loop; an extra triangle on a corner makes a vertex
    where four border edges meet, which ends the curves there."""
    strip = np.array([[0, 1, 3], [0, 3, 2], [2, 3, 5], [2, 5, 4]])
    vertices, before, after = outline_curves(border_edges(strip, 6), 6)
    assert vertices.tolist() == [0, 1, 2, 3, 4, 5]
    neighbours = {v: {b, a} for v, b, a in zip(vertices.tolist(), before.tolist(), after.tolist())}
    assert neighbours == {0: {1, 2}, 1: {0, 3}, 2: {0, 4}, 3: {1, 5}, 4: {2, 5}, 5: {3, 4}}
    bowtie = np.concatenate([strip, [[5, 6, 7]]])
    vertices, _, _ = outline_curves(border_edges(bowtie, 8), 8)
    assert 5 not in vertices.tolist() and {6, 7} <= set(vertices.tolist())


def test_set_numbers_run_the_paper_algorithm_unless_asked(sphere):
    part, noisy, triangles = sphere
    numbers = dict(alpha=0.1, beta=0.6, iterations=8)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)
        paper = core.hc_smooth(noisy, part.edges, **numbers)
    given, report = core.smooth_mesh(noisy, part.edges, faces=triangles, return_report=True, **numbers)
    assert np.array_equal(given, paper) and not report.kept_in_place
    asked = core.smooth_mesh(noisy, part.edges, faces=triangles, keep_in_place=True, **numbers)
    assert np.array_equal(asked, keep_in_place(noisy, paper, triangles))


def test_fixed_vertices_influence_and_limit_hold(sphere):
    part, noisy, triangles = sphere
    fixed = np.zeros(len(noisy), bool)
    fixed[::7] = True
    influence = np.ones(len(noisy))
    influence[1::7] = 0.0
    limit = 0.004
    result = core.smooth_mesh(noisy, part.edges, faces=triangles, fixed=fixed, influence=influence, max_deviation=limit)
    assert np.array_equal(result[fixed], noisy[fixed]) and np.array_equal(result[1::7], noisy[1::7])
    assert np.linalg.norm(result - noisy, axis=1).max() <= limit * (1 + 1e-9)


def test_welded_copies_move_alike():
    """A UV seam (split vertices) moves as the welded mesh does, kept in place there too."""
    part = ico_sphere(3)
    noisy, triangles = _noisy_along_normals(part, 0.01, seed=4)
    split_triangles = triangles.copy()
    copies = np.arange(0, len(noisy), 5)
    positions = np.vstack([noisy, noisy[copies]])
    remap = np.arange(len(noisy))
    remap[copies] = len(noisy) + np.arange(len(copies))
    half = len(triangles) // 2
    split_triangles[:half] = remap[triangles[:half]]  # half the faces use the copies
    edges = np.concatenate([split_triangles[:, [0, 1]], split_triangles[:, [1, 2]], split_triangles[:, [2, 0]]])
    split = core.smooth_mesh(positions, edges, faces=split_triangles, weld=True)
    whole = core.smooth_mesh(noisy, part.edges, faces=triangles)
    assert np.array_equal(split[copies], split[len(noisy) :])
    assert np.allclose(split[: len(noisy)], whole, atol=1e-12)


def test_bad_keep_in_place_is_refused(sphere):
    part, noisy, triangles = sphere
    with pytest.raises(ValueError, match="needs the faces"):
        core.smooth_mesh(noisy, part.edges, keep_in_place=True)
    with pytest.raises(ValueError, match="keep_in_place must be"):
        core.smooth_mesh(noisy, part.edges, faces=triangles, keep_in_place="yes")
    faceless = core.smooth_mesh(noisy, part.edges, return_report=True)[1]
    assert not faceless.kept_in_place  # no faces, no normals: the paper's moves


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_vertex_normal_pass_writes_the_face_normals_and_areas(dtype):
    """Keep in Place reads the result's unit face normals and twice-areas from the vertex normals' own pass
    (``faces``): they are core.face_normals' and the cross products' lengths, (0, 0, 0) without area, and
    the vertex normals are those of the pass without them."""
    from core.geometry import vertex_normal_steps
    from core.slices import to_end

    part = ico_sphere(2)
    rng = np.random.default_rng(3)
    points = (part.positions + rng.normal(scale=0.05, size=part.positions.shape)).astype(dtype)
    triangles = np.r_[part.triangles(), [[0, 0, 1]]]  # and one without area
    facing, area = np.empty((3, len(triangles)), np.float32), np.empty(len(triangles), np.float32)
    rows = to_end(vertex_normal_steps(points, triangles, agreement=True, faces=(facing, area)))
    assert np.array_equal(rows, to_end(vertex_normal_steps(points, triangles, agreement=True)))
    np.testing.assert_allclose(facing.T, core.face_normals(points.astype(np.float64), triangles), atol=1e-6)
    a, b, c = (points[triangles[:, k]].astype(np.float64) for k in range(3))
    np.testing.assert_allclose(area, np.linalg.norm(np.cross(b - a, c - a), axis=1), rtol=1e-6)
    assert not facing[:, -1].any() and area[-1] == 0.0
