"""The deviation limit (max_deviation): a ball around every vertex's input position, kept inside every
iteration, equal to the paper's loop with a projection after each iteration."""

import warnings

import numpy as np
import pytest
import small_meshes as sm
from paper_reference import smooth_loop

import core

SPHERE = sm.uv_sphere(6, 9)
POSITIONS, EDGES = sm.noisy(SPHERE[0], seed=5), sm.edges_of(SPHERE[1])


def moves(result):
    return np.linalg.norm(result - POSITIONS, axis=1)


def quiet_smooth(**options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)
        return core.smooth(POSITIONS, EDGES, **options)


@pytest.mark.parametrize("method,alpha", [("hc", 0.1), ("hc", 0.0), ("plain", 0.0), ("original", 0.3)])
@pytest.mark.parametrize("mode", core.MODES)
def test_equals_the_paper_loop_with_a_projection_after_every_iteration(method, alpha, mode):
    free = quiet_smooth(method=method, alpha=alpha, beta=0.6, iterations=6, mode=mode).positions
    limit = 0.5 * float(np.median(moves(free)))  # binds on about half of the vertices
    expected = np.array(
        smooth_loop(
            POSITIONS, EDGES, method=method, alpha=alpha, beta=0.6, iterations=6, mode=mode, max_deviation=limit
        )
    )
    result = quiet_smooth(method=method, alpha=alpha, beta=0.6, iterations=6, mode=mode, max_deviation=limit)
    np.testing.assert_allclose(result.positions, expected, rtol=0, atol=1e-12)
    assert moves(result.positions).max() <= limit * (1 + 1e-12)
    assert (moves(free) > limit).mean() > 0.3  # the limit really binds


def test_inside_every_iteration_not_a_clip_at_the_end():
    free = quiet_smooth(method="hc", alpha=0.1, beta=0.6, iterations=10).positions
    limit = 0.5 * float(np.median(moves(free)))
    limited = quiet_smooth(method="hc", alpha=0.1, beta=0.6, iterations=10, max_deviation=limit).positions
    away = free - POSITIONS
    length = np.linalg.norm(away, axis=1, keepdims=True)
    clipped = np.where(length > limit, POSITIONS + away * limit / np.maximum(length, 1e-300), free)
    assert np.abs(limited - clipped).max() > 1e-3 * limit


def test_every_iteration_keeps_to_it_and_fixed_vertices_stay():
    fixed = np.zeros(len(POSITIONS), bool)
    fixed[::5] = True
    start = POSITIONS.astype(np.float32)
    run = core.Smoothing(start, EDGES, alpha=0.1, beta=0.6, iterations=8, fixed=fixed, max_deviation=0.01)
    for _ in range(8):
        run.advance(1)
        result = run.result().positions
        # single precision: within the rounding of coordinates of size 1 (~6e-8) of the limit
        assert np.linalg.norm(result.astype(float) - start, axis=1).max() <= 0.01 + 1e-7
        assert np.array_equal(result[fixed], start[fixed])


def test_zero_means_no_limit_bit_for_bit():
    for mode in core.MODES:
        plain = quiet_smooth(method="hc", alpha=0.1, beta=0.6, iterations=5, mode=mode).positions
        zero = quiet_smooth(method="hc", alpha=0.1, beta=0.6, iterations=5, mode=mode, max_deviation=0.0).positions
        assert np.array_equal(plain, zero)


@pytest.mark.parametrize("bad", [-1.0, float("nan"), float("inf"), "far", True])
def test_bad_limits_are_refused(bad):
    with pytest.raises(ValueError, match="max_deviation"):
        core.Smoothing(POSITIONS, EDGES, alpha=0.1, beta=0.6, iterations=1, max_deviation=bad)


@pytest.mark.parametrize("bad", [-1.0, "far", True, np.full(len(POSITIONS), 0.1), [0.1]])
def test_the_mesh_pipeline_refuses_bad_limits_with_a_clear_message(bad):
    """One distance or "auto": a limit per vertex (core.Smoothing's) is refused in words, not by NumPy."""
    with pytest.raises(ValueError, match="^max_deviation must be"):
        core.smooth_mesh(POSITIONS, EDGES, iterations=2, max_deviation=bad)


def test_the_automatic_amount_limits_to_a_multiple_of_its_noise_and_explicit_numbers_do_not():
    noisy = sm.noisy(SPHERE[0], sigma=0.15, seed=5)  # noise found: above core.mesh.noise's threshold
    result, report = core.smooth_mesh(noisy, EDGES, return_report=True)
    assert report.amount is not None
    assert report.max_deviation == pytest.approx(core.mesh.smooth.DEVIATION_IN_NOISE * report.amount.sigma)
    assert np.linalg.norm(result - noisy, axis=1).max() <= report.max_deviation * (1 + 1e-12)
    explicit, report = core.smooth_mesh(noisy, EDGES, alpha=0.1, beta=0.6, iterations=5, return_report=True)
    assert report.max_deviation == 0.0
    assert np.array_equal(explicit, core.hc_smooth(noisy, EDGES, alpha=0.1, beta=0.6, iterations=5))
    limited, report = core.smooth_mesh(noisy, EDGES, iterations=5, max_deviation=1e-3, return_report=True)
    assert report.max_deviation == 1e-3 and np.linalg.norm(limited - noisy, axis=1).max() <= 1e-3 * (1 + 1e-12)
