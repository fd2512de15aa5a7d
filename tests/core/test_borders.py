"""Borders hold (core.mesh.borders, MeshSmoother(border=...)): open-border vertices follow their border as a
curve ("curve"), stay ("fixed") or average all neighbours ("free", the paper's algorithm)."""

import numpy as np
import pytest
import small_meshes as sm
from paper_reference import smooth_loop
from test_welding import first_appearance, soup_of

import core
from core.geometry import fan_triangles
from core.mesh import amount as mesh_amount
from core.mesh.borders import apply_border, border_edges


def quad_grid(nx, ny):
    """An open grid of quads (fan-triangulated by the pipeline: its diagonals must not count as border)."""
    positions = np.array([[x, y, 0.0] for y in range(ny) for x in range(nx)], float)
    faces = [
        [y * nx + x, y * nx + x + 1, (y + 1) * nx + x + 1, (y + 1) * nx + x]
        for y in range(ny - 1)
        for x in range(nx - 1)
    ]
    return positions, faces


def outline(nx, ny):
    """The boundary edges of an nx x ny grid numbered row by row, as (low, high) pairs."""
    pairs = set()
    for x in range(nx - 1):
        pairs |= {(x, x + 1), ((ny - 1) * nx + x, (ny - 1) * nx + x + 1)}
    for y in range(ny - 1):
        pairs |= {(y * nx, (y + 1) * nx), (y * nx + nx - 1, (y + 1) * nx + nx - 1)}
    return pairs


@pytest.mark.parametrize("mesh", [sm.grid(6, 4), quad_grid(5, 4)], ids=["triangles", "quads"])
def test_border_edges_are_the_edges_of_one_face(mesh):
    positions, faces = mesh
    found = border_edges(fan_triangles(faces), len(positions))
    assert set(map(tuple, found.tolist())) == outline(*((6, 4) if len(positions) == 24 else (5, 4)))
    for closed in (sm.pentagonal_prism(), sm.cube_quads(), sm.uv_sphere(4, 6)):
        assert border_edges(fan_triangles(closed[1]), len(closed[0])).size == 0


def test_curve_rows_are_the_border_neighbours():
    positions, faces = sm.grid(6, 4)
    n = len(positions)
    operator = core.umbrella_operator(sm.edges_of(faces), n)
    curve, fixed = apply_border("curve", operator, fan_triangles(faces), np.zeros(n, dtype=bool))
    assert not fixed.any()  # every border vertex of a rectangle has two border neighbours
    pairs = outline(6, 4)
    on_border = {v for pair in pairs for v in pair}
    for i in range(n):
        row = set(curve.indices[curve.indptr[i] : curve.indptr[i + 1]].tolist())
        if i in on_border:
            assert row == {b if a == i else a for a, b in pairs if i in (a, b)}
        else:  # interior rows keep every neighbour, border ones included
            assert row == set(operator.indices[operator.indptr[i] : operator.indptr[i + 1]].tolist())


def test_where_the_border_is_no_simple_curve_the_vertex_stays():
    # Two triangles meeting at one vertex (a bow tie): four border edges meet there. A lone edge's end
    # without faces is no border.
    positions = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [-1, 0, 0], [-1, -1, 0], [0, 2, 0]], float)
    faces = [[0, 1, 2], [0, 3, 4]]
    edges = np.concatenate([sm.edges_of(faces), [[2, 5]]])
    operator = core.umbrella_operator(edges, 6)
    curve, fixed = apply_border("curve", operator, fan_triangles(faces), np.zeros(6, dtype=bool))
    assert fixed.tolist() == [True, False, False, False, False, False]
    noisy = sm.noisy(positions, seed=2)
    result = core.smooth_mesh(noisy, edges, faces=faces, border="curve", iterations=3)
    assert np.array_equal(result[0], noisy[0])
    assert np.abs(result[1:5] - noisy[1:5]).max() > 1e-3


@pytest.mark.parametrize("mode", core.MODES)
def test_fixed_border_is_pin_boundary(mode):
    positions, faces = sm.grid(8, 6)
    noisy = sm.noisy(positions, seed=4)
    edges = sm.edges_of(faces)
    pinned = border_mask(faces, len(noisy))  # the vertices on an edge of one face
    for numbers in ({}, dict(iterations=6)):
        fixed = core.smooth_mesh(noisy, edges, faces=faces, border="fixed", mode=mode, **numbers)
        pin = core.smooth_mesh(noisy, edges, faces=faces, fixed=pinned, mode=mode, **numbers)
        assert np.array_equal(fixed, pin)
        assert np.array_equal(fixed[pinned], noisy[pinned])


@pytest.mark.parametrize("border", ["curve", "fixed"])
def test_a_border_rule_needs_faces(border):
    positions, faces = sm.grid(4, 4)
    with pytest.raises(ValueError, match="needs the faces"):
        core.smooth_mesh(positions, sm.edges_of(faces), border=border)
    with pytest.raises(ValueError, match="border must be one of"):
        core.smooth_mesh(positions, sm.edges_of(faces), faces=faces, border="pinned")
    core.smooth_mesh(positions, sm.edges_of(faces), border="free", iterations=2)  # no faces needed


def test_closed_meshes_have_no_border_to_hold():
    positions, faces = sm.uv_sphere(6, 9)
    noisy, edges = sm.noisy(positions, seed=5), sm.edges_of(faces)
    for border in ("curve", "fixed"):
        for numbers in ({}, dict(iterations=5, mode="sequential")):
            plain = core.smooth_mesh(noisy, edges, faces=faces, **numbers)
            assert np.array_equal(core.smooth_mesh(noisy, edges, faces=faces, border=border, **numbers), plain)


@pytest.mark.parametrize("mode", core.MODES)
def test_the_pipeline_runs_the_paper_on_the_curve_adjacency(mode):
    positions, faces = sm.grid(7, 6)
    noisy, edges = sm.noisy(positions, seed=6), sm.edges_of(faces)
    n = len(noisy)
    operator, fixed = apply_border(
        "curve", core.umbrella_operator(edges, n), fan_triangles(faces), np.zeros(n, dtype=bool)
    )
    adj = [set(operator.indices[operator.indptr[i] : operator.indptr[i + 1]].tolist()) for i in range(n)]
    expected = smooth_loop(noisy, None, method="hc", alpha=0.1, beta=0.6, iterations=5, mode=mode, adj=adj)
    got = core.smooth_mesh(noisy, edges, faces=faces, border="curve", mode=mode, alpha=0.1, beta=0.6, iterations=5)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)


def wavy_disc(rings=12, segments=48, sigma=0.0, seed=0):
    """An open, gently curved disc whose border is a smooth curve (a regular polygon seen from above):
    a centre vertex and ``rings`` rings of ``segments`` vertices, spacing 1, noise along z."""
    angle = 2 * np.pi * np.arange(segments) / segments
    radius = np.repeat(np.arange(1, rings + 1), segments).astype(float)
    x, y = radius * np.tile(np.cos(angle), rings), radius * np.tile(np.sin(angle), rings)
    positions = np.concatenate([[[0.0, 0.0, 0.0]], np.stack([x, y, np.zeros_like(x)], axis=1)])
    positions[:, 2] = 2.0 * np.sin(positions[:, 0] / 5.0) * np.cos(positions[:, 1] / 7.0)
    ring = lambda r, s: 1 + r * segments + s % segments  # noqa: E731
    faces = [[0, ring(0, s), ring(0, s + 1)] for s in range(segments)]
    for r in range(rings - 1):
        for s in range(segments):
            faces += [
                [ring(r, s), ring(r + 1, s), ring(r + 1, s + 1)],
                [ring(r, s), ring(r + 1, s + 1), ring(r, s + 1)],
            ]
    noisy = positions + [0, 0, 1] * np.random.default_rng(seed).normal(0.0, sigma, (len(positions), 1))
    return noisy, faces


def border_mask(faces, n):
    mask = np.zeros(n, dtype=bool)
    mask[border_edges(fan_triangles(faces), n).ravel()] = True
    return mask


@pytest.mark.parametrize("numbers", [{}, dict(alpha=0.1, beta=0.6, iterations=10)], ids=["automatic", "given"])
def test_a_smooth_open_border_holds_its_place(numbers):
    """On a noisy open disc whose border is a smooth curve, the curve rule moves the border no more than
    the interior, and the bounding box stays, as with the default's Keep in Place; all neighbours (the paper
    as it stands) pull the border in."""
    noisy, faces = wavy_disc(sigma=0.3, seed=7)
    edges, n = sm.edges_of(faces), len(noisy)
    border = border_mask(faces, n)

    def moves(result):
        move = np.linalg.norm(result - noisy, axis=1)
        return np.sqrt(np.mean(move[border] ** 2)), np.sqrt(np.mean(move[~border] ** 2))

    diagonal = np.linalg.norm(np.ptp(noisy[:, :2], axis=0))
    curve = core.smooth_mesh(noisy, edges, faces=faces, border="curve", **numbers)
    free = core.smooth_mesh(noisy, edges, faces=faces, max_deviation=0.0, keep_in_place=False, **numbers)  # the paper
    border_move, interior_move = moves(curve)
    assert border_move <= 1.5 * interior_move
    if not numbers:  # the default keeps every move across the surface: its border is not pulled in either
        kept = core.smooth_mesh(noisy, edges, faces=faces)
        assert moves(kept)[0] <= 1.5 * moves(kept)[1]
        assert np.abs(np.ptp(kept[:, :2], axis=0) - np.ptp(noisy[:, :2], axis=0)).max() <= 3e-3 * diagonal
    free_border, free_interior = moves(free)
    assert free_border > 1.5 * free_interior
    in_plane = np.abs(np.ptp(curve[:, :2], axis=0) - np.ptp(noisy[:, :2], axis=0)).max()
    assert in_plane <= 3e-3 * diagonal
    assert np.abs(np.ptp(free[:, :2], axis=0) - np.ptp(noisy[:, :2], axis=0)).max() > 1e-2 * diagonal


def test_the_automatic_amount_chooses_on_the_surface_umbrella():
    """The noise test and GCV read 1-rings: a border rule changes how the run smooths, not the amount the
    surface's noise asks for (the disc's border is one simple curve: no vertex is held)."""
    noisy, faces = wavy_disc(sigma=0.3, seed=7)
    edges = sm.edges_of(faces)
    reports = {
        border: core.smooth_mesh(noisy, edges, faces=faces, border=border, return_report=True)[1]
        for border in ("free", "curve")
    }
    assert reports["curve"].amount == reports["free"].amount
    assert reports["curve"].iterations == reports["free"].iterations > 1


def test_a_soup_of_an_open_patch_finds_its_border_after_welding():
    noisy, faces = wavy_disc(5, 12, sigma=0.3, seed=8)
    faces = np.array(faces)
    soup, soup_faces = soup_of(noisy, faces)
    for numbers in ({}, dict(iterations=6)):
        result = core.smooth_mesh(
            soup, sm.edges_of(soup_faces.tolist()), faces=soup_faces, weld=True, border="curve", **numbers
        )
        welded, welded_faces, number = first_appearance(noisy, faces)
        expected = core.smooth_mesh(
            welded, sm.edges_of(welded_faces.tolist()), faces=welded_faces, border="curve", **numbers
        )
        assert np.array_equal(result, expected[number[faces].ravel()])


def test_the_automatic_amount_probes_patches_of_the_curve_adjacency(monkeypatch):
    """On big meshes the choice runs on patches: they keep the operator's own (directed) rows."""
    noisy, faces = wavy_disc(20, 64, sigma=0.3, seed=9)
    n = len(noisy)
    operator, fixed = apply_border(
        "curve", core.umbrella_operator(sm.edges_of(faces), n), fan_triangles(faces), np.zeros(n, dtype=bool)
    )
    monkeypatch.setattr(mesh_amount, "PATCH_RINGS", 6)
    monkeypatch.setattr(mesh_amount, "PATCH_MARGIN", 2)
    patches, patch_fixed, inner, _ = mesh_amount._patches(operator, fixed, np.flatnonzero(~fixed))
    assert not patches.symmetric and inner.size > 0
    symmetric = mesh_amount._patches(core.umbrella_operator(sm.edges_of(faces), n), fixed, np.arange(n))[0]
    assert symmetric.symmetric
    monkeypatch.setattr(mesh_amount, "PATCH_FROM", 100)
    result, report = core.smooth_mesh(noisy, sm.edges_of(faces), faces=faces, border="curve", return_report=True)
    assert report.amount is not None and report.iterations >= 1
    assert np.isfinite(result).all()


def test_border_edges_without_scipys_private_kernels(monkeypatch):
    from core import adjacency

    positions, faces = wavy_disc(6, 20)
    triangles = np.concatenate([fan_triangles(faces), [[3, 3, 4]]])  # and a degenerate triangle
    fast = border_edges(triangles, len(positions))
    monkeypatch.setattr(adjacency, "_coo_tocsr", None)
    public = border_edges(triangles, len(positions))
    np.testing.assert_array_equal(fast, public)
    assert len(fast) == 20 and set(np.unique(fast).tolist()) == set(range(1 + 5 * 20, 1 + 6 * 20))
