"""core.smooth_point_cloud: removes noise without shrinking, keeps fixed points, dtype, input; clear errors."""

import numpy as np
import pytest
from pointcloud_sets import noisy_sphere, sphere_rms, with_duplicates

import core
import core.pointcloud.smooth as pointcloud_smooth
from core.pointcloud import PointCloudReport
from core.smoothing import Cancelled


@pytest.fixture(scope="module")
def sphere():
    return noisy_sphere(4000, 0.005, seed=11)


@pytest.fixture(scope="module")
def smoothed(sphere):
    return core.smooth_point_cloud(sphere, rounds=10, return_mesh=True)


def test_reduces_noise_without_shrinking(sphere, smoothed):
    out, report = smoothed
    assert sphere_rms(out) < 0.7 * sphere_rms(sphere)
    before, after = np.linalg.norm(sphere, axis=1).mean(), np.linalg.norm(out, axis=1).mean()
    assert abs(after - before) < 0.005 * before  # size change below 0.5 %
    assert report.isolated < 0.02 * len(sphere)


def test_swapping_helps(sphere, smoothed):
    without = core.smooth_point_cloud(sphere, rounds=10, swap=False)
    assert sphere_rms(smoothed[0]) < sphere_rms(without)


def test_report_mesh_refers_to_input_points(sphere, smoothed):
    _, report = smoothed
    assert isinstance(report, PointCloudReport)
    assert report.mesh.faces.max() < len(sphere) and report.mesh.edges.max() < len(sphere)
    assert len(report.swaps) == 9 and report.swaps[0] > 0  # between consecutive rounds
    assert set(report.seconds) >= {"emst", "sdg", "rfs", "hc", "swap"}


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_shape_dtype_and_input_untouched(dtype):
    points = noisy_sphere(600, 0.005, seed=1, dtype=dtype)
    copy = points.copy()
    out = core.smooth_point_cloud(points, rounds=3)
    assert out.dtype == dtype and out.shape == points.shape
    assert np.array_equal(points, copy)
    assert not np.shares_memory(out, points)
    assert np.abs(out - points).max() > 0


def test_float32_cloud_smooths_in_float32_as_well_as_in_float64(monkeypatch):
    """HC runs in the input's precision; a float32 cloud comes out as close to the sphere as the same
    cloud given in float64, and its steps really ran in float32."""
    points = noisy_sphere(3000, 0.01, seed=4, dtype=np.float32)
    precisions = []
    real_smoothing = pointcloud_smooth.Smoothing
    monkeypatch.setattr(
        pointcloud_smooth, "Smoothing", lambda q, *a, **k: precisions.append(q.dtype) or real_smoothing(q, *a, **k)
    )
    single = core.smooth_point_cloud(points).astype(np.float64)
    assert set(precisions) == {np.dtype(np.float32)}
    double = core.smooth_point_cloud(points.astype(np.float64))
    assert precisions[-1] == np.float64

    def error(out):
        return np.sqrt(np.mean((np.linalg.norm(out, axis=1) - 1.0) ** 2))

    assert error(single) == pytest.approx(error(double), rel=0.01)
    assert error(single) < 0.5 * error(points.astype(np.float64))


@pytest.mark.parametrize("as_indices", [False, True])
def test_fixed_points_do_not_move(as_indices):
    points = noisy_sphere(800, 0.01, seed=2, dtype=np.float32)
    mask = np.zeros(len(points), bool)
    mask[::7] = True
    fixed = np.flatnonzero(mask) if as_indices else mask
    out = core.smooth_point_cloud(points, rounds=4, fixed=fixed)
    assert np.array_equal(out[mask], points[mask])
    assert np.all(np.any(out[~mask] != points[~mask], axis=1).mean() > 0.9)


def test_duplicates_move_together():
    points = with_duplicates(400) * [1, 1, 0.01]  # a thin slab: surface-like
    out = core.smooth_point_cloud(points, rounds=3)
    _, inverse = np.unique(points, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    for group in np.unique(inverse):
        same = out[inverse == group]
        assert np.all(same == same[0])


def test_zero_rounds_returns_a_copy():
    points = noisy_sphere(200, 0.01)
    out = core.smooth_point_cloud(points, rounds=0)
    assert np.array_equal(out, points) and out is not points


@pytest.mark.parametrize("n", [0, 1, 2, 3, 4])
def test_tiny_inputs(n):
    points = np.random.default_rng(0).random((n, 3))
    out = core.smooth_point_cloud(points, rounds=2)
    assert out.shape == (n, 3)


def test_progress_and_cancel():
    points = noisy_sphere(300, 0.01)
    calls = []
    core.smooth_point_cloud(points, rounds=3, progress=lambda done, total: calls.append((done, total)))
    assert calls == [(1, 3), (2, 3), (3, 3)]
    with pytest.raises(Cancelled):
        core.smooth_point_cloud(points, rounds=3, progress=lambda done, total: done < 2)


@pytest.mark.parametrize(
    "options, message",
    [
        (dict(points=np.zeros((5, 2))), "shape"),
        (dict(points=np.array([[0.0, 0, 0], [np.inf, 0, 0]])), "infinite"),
        (dict(points=np.zeros((5, 3), dtype=np.int64)), "float32 or float64"),
        (dict(alpha=1.5), "alpha"),
        (dict(beta=-0.1), "beta"),
        (dict(rounds=-1), "rounds"),
        (dict(rounds=2.5), "rounds"),
        (dict(iterations_per_round=0), "iterations_per_round"),
        (dict(neighbours=1), "neighbours"),
        (dict(spacing_factor=0), "spacing_factor"),
        (dict(spacing_factor=4.0, gap_factor=3.0), "gap_factor"),
        (dict(min_quality=2), "min_quality"),
        (dict(fixed=np.zeros(3, bool)), "length"),
        (dict(fixed=[10**6]), "fixed"),
        (dict(progress=5), "progress"),
    ],
)
def test_bad_input(options, message):
    options = dict(options)
    points = options.pop("points", noisy_sphere(50, 0.01))
    with pytest.raises(ValueError, match=message):
        core.smooth_point_cloud(points, **options)


def test_stepwise_run_equals_one_call_and_reports_stages():
    from core.pointcloud import PointCloudSmoother

    points = noisy_sphere(500, 0.01, seed=4)
    run = PointCloudSmoother(points, rounds=3)
    stages, fractions = [], []
    for fraction in run.steps():
        stages.append((run.stage, run.rounds_done))
        fractions.append(fraction)
    assert stages == [("neighbours", 0), ("emst", 0), ("sdg", 0), ("rfs", 0), ("round", 1), ("round", 2), ("round", 3)]
    assert fractions == [k / 7 for k in range(1, 8)]
    assert np.array_equal(run.result, core.smooth_point_cloud(points, rounds=3))
    with pytest.raises(ValueError, match="alpha"):
        PointCloudSmoother(points, alpha=2)  # checked before any work


def test_long_stages_yield_in_slices_with_the_same_result(monkeypatch):
    """A large cloud's long stages (kNN query, Borůvka rounds, RFS pruning, HC steps) yield between
    slices, so a caller's progress moves every second or so; slices small enough to show it on a small
    cloud leave every stage's result, and the run's, bit for bit the same."""
    from core.pointcloud import PointCloudSmoother, spanning_tree, stepwise

    points = noisy_sphere(3000, 0.01, seed=5)
    whole = core.smooth_point_cloud(points, rounds=3)
    monkeypatch.setattr(stepwise, "SLICE", 2000)
    monkeypatch.setattr(spanning_tree, "_QUERY_ENTRIES", 10_000)
    monkeypatch.setattr(pointcloud_smooth, "_HC_SLICE", 20_000)
    run = PointCloudSmoother(points, rounds=3)
    seen = [(fraction, run.stage, run.rounds_done) for fraction in run.steps()]
    fractions = [fraction for fraction, _, _ in seen]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0 and fractions[0] > 0
    finished = [(stage, done) for fraction, stage, done in seen if fraction * 7 == round(fraction * 7)]
    stages = [("neighbours", 0), ("emst", 0), ("sdg", 0), ("rfs", 0), ("round", 1), ("round", 2), ("round", 3)]
    assert finished == stages
    # Between the finished stages (``stage`` names the last one): slices of the kNN query (nothing finished
    # yet), the EMST, the RFS stage and every round (the SDG is one slice).
    in_between = {(stage, done) for fraction, stage, done in seen if fraction * 7 != round(fraction * 7)}
    assert in_between == {(None, 0), ("neighbours", 0), ("sdg", 0), ("rfs", 0), ("round", 1), ("round", 2)}
    assert len(seen) > 30
    assert np.array_equal(run.result, whole)
