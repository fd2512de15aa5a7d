"""Scattered vertex numberings are smoothed in a cache-friendly order, with the same result."""

import numpy as np
import pytest

import core
from core import locality


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
