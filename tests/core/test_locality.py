"""Scattered vertex numberings are smoothed in a cache-friendly order, with the same result."""

import numpy as np
import pytest

import core
from core import locality
from core.slices import to_end


def grid_mesh(side):
    """A triangulated side x side grid, numbered row by row (neighbours close in memory)."""
    index = np.arange(side * side).reshape(side, side)
    edges = np.concatenate(
        [
            np.stack([index[:, :-1].ravel(), index[:, 1:].ravel()], axis=1),
            np.stack([index[:-1, :].ravel(), index[1:, :].ravel()], axis=1),
            np.stack([index[:-1, :-1].ravel(), index[1:, 1:].ravel()], axis=1),
        ]
    )
    y, x = np.divmod(np.arange(side * side), side)
    rng = np.random.default_rng(side)
    positions = np.stack([x, y, rng.normal(0.0, 0.3, side * side)], axis=1).astype(float)
    return positions, edges


def shuffle(positions, edges, seed=0):
    order = np.random.default_rng(seed).permutation(len(positions))
    inverse = np.empty_like(order)
    inverse[order] = np.arange(len(order))
    return positions[order], inverse[edges], order


def test_row_by_row_numbering_is_not_scattered_but_a_shuffled_one_is():
    positions, edges = grid_mesh(460)  # 211,600 vertices: above MIN_VERTICES
    assert not locality.is_scattered(core.umbrella_operator(edges, len(positions)))
    shuffled, shuffled_edges, _ = shuffle(positions, edges)
    operator = core.umbrella_operator(shuffled_edges, len(positions))
    assert locality.median_gap(operator) > 0.25 * len(positions)  # random pairs: ~0.29 n
    assert locality.is_scattered(operator)
    renumbered = locality.renumbering(operator)
    assert locality.median_gap(renumbered.operator) < 1000  # neighbours close again
    assert locality.renumbering(operator) is renumbered  # built once per operator


@pytest.fixture
def small_scattered(monkeypatch):
    monkeypatch.setattr(locality, "MIN_VERTICES", 0)
    monkeypatch.setattr(locality, "SCATTERED_GAP", 10)
    positions, edges = grid_mesh(30)
    return shuffle(positions, edges, seed=3)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("method", ["hc", "plain", "central", "original"])
def test_renumbered_run_equals_the_plain_one(monkeypatch, small_scattered, method, dtype):
    positions, edges, _ = small_scattered
    positions = positions.astype(dtype)
    fixed = np.zeros(len(positions), dtype=bool)
    fixed[::7] = True
    kwargs = dict(method=method, alpha=0.2, beta=0.7, iterations=6, fixed=fixed)
    operator = core.umbrella_operator(edges, len(positions))
    got = core.smooth(positions, None, operator=operator, **kwargs).positions
    assert operator._renumbering  # the renumbered path ran
    monkeypatch.setattr(locality, "MIN_VERTICES", 10**9)
    expected = core.smooth(positions, edges, **kwargs).positions
    assert got.dtype == dtype
    tolerance = 1e-5 if dtype == np.float32 else 1e-12
    np.testing.assert_allclose(got, expected, rtol=0, atol=tolerance)
    assert np.array_equal(got[fixed].view(np.uint8), positions[fixed].view(np.uint8))


def test_renumbered_run_keeps_early_stop_progress_and_original(small_scattered):
    positions, edges, _ = small_scattered
    original = positions + 0.01
    seen = []
    result = core.smooth(
        positions,
        edges,
        method="hc",
        alpha=0.3,
        beta=0.7,
        iterations=200,
        tolerance=1e-4,
        original=original,
        progress=lambda done, total: seen.append(done),
    )
    plain = core.smooth(
        positions,
        edges,
        method="hc",
        alpha=0.3,
        beta=0.7,
        iterations=result.iterations,
        original=original,
        operator=_unscattered(edges, len(positions)),
    )
    assert result.stopped_early and seen == list(range(1, result.iterations + 1))
    np.testing.assert_allclose(result.positions, plain.positions, rtol=0, atol=1e-12)


def _unscattered(edges, n):
    operator = core.umbrella_operator(edges, n)
    operator._renumbering = False  # looked, and decided against
    return operator


def test_sequential_mode_is_never_renumbered(small_scattered):
    # Gauss-Seidel is defined by the vertex order: renumbering would change the result.
    positions, edges, _ = small_scattered
    operator = core.umbrella_operator(edges, len(positions))
    core.smooth(positions, None, operator=operator, method="hc", alpha=0.1, beta=0.6, iterations=3, mode="sequential")
    assert operator._renumbering is None


def grid_triangles(side):
    """The triangles of ``grid_mesh(side)`` (its diagonals run from (x, y) to (x + 1, y + 1))."""
    index = np.arange(side * side).reshape(side, side)
    low, right, up, across = index[:-1, :-1], index[:-1, 1:], index[1:, :-1], index[1:, 1:]
    return np.concatenate([np.stack([low, right, across], -1), np.stack([low, across, up], -1)]).reshape(-1, 3)


@pytest.fixture
def scattered_surface(monkeypatch):
    """A shuffled 40 x 40 grid with its triangles, scattered by thresholds its renumbering is not."""
    monkeypatch.setattr(locality, "MIN_VERTICES", 0)
    monkeypatch.setattr(locality, "SCATTERED_GAP", 100)  # shuffled: ~460; renumbered: ~40
    positions, edges = grid_mesh(40)
    shuffled, shuffled_edges, order = shuffle(positions, edges, seed=5)
    number = np.empty_like(order)
    number[order] = np.arange(order.size)
    return shuffled, shuffled_edges, number[grid_triangles(40)], order


@pytest.mark.parametrize(
    "options",
    [{}, {"border": "curve"}, {"border": "fixed"}, {"keep_sharp_edges": True}],
    ids=["default", "border curve", "border fixed", "keep sharp edges"],
)
def test_the_mesh_pipeline_runs_a_scattered_mesh_renumbered(scattered_surface, options):
    """Every pass of the pipeline (noise test, choice, border rule, Keep in Place or Keep Sharp Edges, volume,
    held parts) runs on the mesh renumbered once, and the result, and what it held still, come back in the
    caller's numbering: the run on the renumbered inputs, scattered back, bit for bit."""
    positions, edges, faces, _ = scattered_surface
    fixed = np.zeros(len(positions), dtype=bool)
    fixed[::11] = True
    influence = np.linspace(0.2, 1.0, len(positions))
    run = core.MeshSmoother(positions, edges, faces=faces, fixed=fixed, influence=influence, **options)
    to_end(run.steps())
    renumbering = run.renumbering
    assert renumbering is not None and not locality.is_scattered(renumbering.operator)
    order = renumbering.order
    alike = core.MeshSmoother(
        positions[order],
        renumbering.triangles(edges),
        faces=renumbering.triangles(faces),
        fixed=fixed[order],
        influence=influence[order],
        **options,
    )
    to_end(alike.steps())
    assert alike.renumbering is None and run.report.iterations > 0
    assert np.array_equal(run.result, renumbering.scatter(alike.result))
    assert np.array_equal(run.still(), renumbering.scatter(alike.still())) and run.still()[fixed].all()
    assert np.array_equal(run.result[fixed], positions[fixed])


def test_given_numbers_on_a_scattered_mesh_are_the_paper_s_run_bit_for_bit(scattered_surface):
    positions, edges, faces, _ = scattered_surface
    numbers = dict(alpha=0.1, beta=0.6, iterations=8)
    got = core.smooth_mesh(positions, edges, faces=faces, **numbers)
    assert np.array_equal(got, core.hc_smooth(positions, edges, **numbers))


def test_a_welded_scattered_mesh_comes_back_whole(scattered_surface):
    """Welding, then renumbering: a seam's copies move alike, and every vertex lands where the same run on
    the grid's own numbering (neither renumbered) puts it, to the rounding of the neighbour sums."""
    positions, edges, faces, order = scattered_surface
    seam = np.flatnonzero(positions[:, 0] == 20.0)  # a column of the grid, split in two
    copies = np.arange(len(positions), len(positions) + seam.size)
    right = np.isin(faces, seam) & (positions[faces][..., 0] > 20.0).any(axis=1, keepdims=True)
    split = faces.copy()
    split[right] = copies[np.searchsorted(seam, faces[right])]
    points = np.concatenate([positions, positions[seam]])
    numbers = dict(alpha=0.1, beta=0.6, iterations=8, weld=True)

    def run(points, triangles):
        pairs = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
        smoother = core.MeshSmoother(points, pairs, faces=triangles, **numbers)
        to_end(smoother.steps())
        return smoother

    scattered = run(points, split)
    assert scattered.welding is not None and scattered.renumbering is not None
    assert np.array_equal(scattered.result[seam], scattered.result[copies])
    place = np.concatenate([order, copies])  # the grid's number of each vertex
    in_grid = np.empty_like(points)
    in_grid[place] = points
    ordered = run(in_grid, place[split])
    assert ordered.welding is not None and ordered.renumbering is None
    np.testing.assert_allclose(scattered.result, ordered.result[place], rtol=0, atol=1e-12)
