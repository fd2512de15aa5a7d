"""Early stop by tolerance, progress reports, cancelling, reusing a prebuilt operator."""

import numpy as np
import pytest
import small_meshes as sm

import core

POSITIONS, FACES = sm.uv_sphere(8, 12)
NOISY = sm.noisy(POSITIONS, 0.05)
EDGES = sm.edges_of(FACES)


@pytest.mark.parametrize("mode", core.MODES)
def test_tolerance_stops_early_once_moves_are_small(mode):
    result = core.smooth(NOISY, EDGES, alpha=0.2, beta=0.7, iterations=10_000, mode=mode, tolerance=1e-6)
    assert result.stopped_early and 1 < result.iterations < 10_000
    # the last iteration run moved every vertex by less than the tolerance; the one before did not
    before_last = core.smooth(NOISY, EDGES, alpha=0.2, beta=0.7, iterations=result.iterations - 1, mode=mode)
    diagonal = np.linalg.norm(np.ptp(NOISY, axis=0))
    moves = np.linalg.norm(result.positions - before_last.positions, axis=1)
    assert moves.max() < 1e-6 * diagonal
    full = core.smooth(NOISY, EDGES, alpha=0.2, beta=0.7, iterations=result.iterations, mode=mode)
    assert np.array_equal(full.positions, result.positions) and not full.stopped_early


def test_progress_is_reported_and_false_cancels():
    seen = []
    core.hc_smooth(NOISY, EDGES, alpha=0.1, beta=0.6, iterations=4, progress=lambda d, t: seen.append((d, t)))
    assert seen == [(1, 4), (2, 4), (3, 4), (4, 4)]
    before = NOISY.copy()
    with pytest.raises(core.Cancelled, match="after 2 of 4"):
        core.hc_smooth(NOISY, EDGES, alpha=0.1, beta=0.6, iterations=4, progress=lambda d, t: d < 2)
    assert np.array_equal(NOISY, before)


def test_original_points_can_differ_from_the_start():
    """Restarting from an intermediate result with the true originals continues the same run."""
    first = core.hc_smooth(NOISY, EDGES, alpha=0.1, beta=0.6, iterations=3)
    resumed = core.hc_smooth(first, EDGES, alpha=0.1, beta=0.6, iterations=2, original=NOISY)
    straight = core.hc_smooth(NOISY, EDGES, alpha=0.1, beta=0.6, iterations=5)
    np.testing.assert_allclose(resumed, straight, atol=1e-13)


def test_prebuilt_operator_is_reused_and_equal():
    operator = core.umbrella_operator(EDGES, len(NOISY))
    for mode in core.MODES:
        a = core.hc_smooth(NOISY, EDGES, alpha=0.1, beta=0.6, iterations=3, mode=mode)
        b = core.hc_smooth(NOISY, None, alpha=0.1, beta=0.6, iterations=3, mode=mode, operator=operator)
        assert np.array_equal(a, b)
