"""Runs that blow up are refused, never returned; chunked runs equal one-shot runs bit for bit."""

import warnings

import numpy as np
import pytest
import small_meshes as sm

import core

POSITIONS, FACES = sm.uv_sphere(8, 12)
NOISY = sm.noisy(POSITIONS, 0.05)
EDGES = sm.edges_of(FACES)
CUBE, CUBE_FACES = sm.cube_quads()  # bipartite: plain HC with alpha = beta = 0 grows 3x per step
CUBE_EDGES = sm.edges_of(CUBE_FACES)


def run(positions, edges, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)
        return core.smooth(positions, edges, **options)


@pytest.mark.parametrize("mode", core.MODES)
@pytest.mark.parametrize("iterations", [20, 2000])  # a bounding box thousands of times larger; inf/NaN
def test_blown_up_result_raises_and_names_the_region(mode, iterations):
    noisy = sm.noisy(CUBE, 0.05)
    before = noisy.copy()
    with pytest.raises(core.DivergenceError, match=r"alpha 0 and beta 0 .*alpha > 0 and beta > 0\.5") as caught:
        run(noisy, CUBE_EDGES, method="hc", alpha=0.0, beta=0.0, iterations=iterations, mode=mode)
    assert isinstance(caught.value, ValueError)
    assert np.array_equal(noisy, before)


def test_divergence_kinds_are_told_apart():
    noisy = sm.noisy(CUBE, 0.05)
    with pytest.raises(core.DivergenceError, match="bounding box grew"):
        run(noisy, CUBE_EDGES, method="hc", alpha=0.0, beta=0.0, iterations=20)
    with pytest.raises(core.DivergenceError, match="infinite or NaN"):
        run(noisy, CUBE_EDGES, method="hc", alpha=0.0, beta=0.0, iterations=2000)


def test_point_clouds_refuse_a_blown_up_run():
    rng = np.random.default_rng(3)
    points = rng.normal(size=(600, 3))
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    with warnings.catch_warnings(), pytest.raises(core.DivergenceError, match="alpha > 0 and beta > 0.5"):
        warnings.simplefilter("ignore", core.ConvergenceWarning)
        core.smooth_point_cloud(points, alpha=0.0, beta=0.0, iterations_per_round=100, rounds=2)


@pytest.mark.parametrize("method", core.METHODS)
@pytest.mark.parametrize("mode", core.MODES)
def test_inside_the_region_long_runs_return(method, mode):
    out = run(NOISY, EDGES, method=method, alpha=0.01, beta=0.51, iterations=500, mode=mode).positions
    assert np.isfinite(out).all()


@pytest.mark.parametrize("mode", core.MODES)
@pytest.mark.parametrize("tolerance", [0.0, 1e-4])
def test_chunked_run_equals_one_shot_bit_for_bit(mode, tolerance):
    """The tolerance is measured against the input's bounding box, whatever the chunk."""
    options = dict(
        method="hc",
        alpha=0.1,
        beta=0.6,
        iterations=60,
        mode=mode,
        tolerance=tolerance,
        fixed=np.arange(0, len(NOISY), 7),
    )
    whole = core.smooth(NOISY, EDGES, **options)
    stepped = core.Smoothing(NOISY, EDGES, **options)
    chunks = []
    while not stepped.finished:
        chunks.append(stepped.advance(3))
    chunked = stepped.result()
    assert np.array_equal(chunked.positions, whole.positions)
    assert chunked.iterations == whole.iterations == sum(chunks)
    assert chunked.stopped_early == whole.stopped_early == (tolerance > 0)


def test_advance_checks_each_chunk():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)
        stepped = core.Smoothing(sm.noisy(CUBE, 0.05), CUBE_EDGES, method="hc", alpha=0.0, beta=0.0, iterations=100)
    stepped.advance(3)  # 27x at most: within the bounding box allowed
    with pytest.raises(core.DivergenceError, match="after 6 iterations"):
        stepped.advance(3)


@pytest.mark.parametrize("mode", core.MODES)
@pytest.mark.parametrize("scale", [2.0**-520, 2.0**520])  # squares of moves would underflow / overflow
def test_tolerance_stops_at_the_same_iteration_at_any_scale(mode, scale):
    options = dict(method="hc", alpha=0.1, beta=0.6, iterations=500, mode=mode, tolerance=1e-5)
    unit = core.smooth(NOISY, EDGES, **options)
    far = core.smooth(NOISY * scale, EDGES, **options)
    assert unit.stopped_early and far.stopped_early and far.iterations == unit.iterations
    assert np.array_equal(far.positions, unit.positions * scale)  # a power of two: exact


def test_steps_yield_the_fraction_done_like_the_point_cloud_run():
    run = core.Smoothing(NOISY, EDGES, method="hc", alpha=0.1, beta=0.6, iterations=10)
    assert list(run.steps(4)) == [0.4, 0.8, 1.0]
    assert np.array_equal(run.result().positions, core.hc_smooth(NOISY, EDGES, alpha=0.1, beta=0.6, iterations=10))
    assert list(core.Smoothing(NOISY, EDGES, iterations=0).steps()) == [1.0]
