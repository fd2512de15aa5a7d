"""core.pointcloud.noise: the noise / spacing estimate and the amount of smoothing chosen from it."""

import numpy as np
import pytest
from pointcloud_sets import noisy_sphere, sphere_rms

import core
from core.pointcloud import noise
from core.pointcloud.noise import estimate_noise, matched_alpha, steps_per_round, total_steps
from core.pointcloud.spanning_tree import NeighbourIndex


def noisy_plane(n, ratio, seed=0):
    """n points uniform on the unit square, Gaussian noise of ``ratio`` x the spacing sqrt(1 / n)."""
    rng = np.random.default_rng(seed)
    points = np.zeros((n, 3))
    points[:, :2] = rng.random((n, 2))
    return points + rng.normal(scale=ratio / np.sqrt(n), size=points.shape)


def unit_sphere(n, ratio, seed=0):
    """n points on the unit sphere, Gaussian noise of ``ratio`` x the spacing sqrt(4 pi / n)."""
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return v + rng.normal(scale=ratio * np.sqrt(4 * np.pi / n), size=v.shape)


@pytest.mark.parametrize("ratio", [0.05, 0.3, 1.0, 3.0])
def test_recovers_noise_over_spacing_on_a_plane(ratio):
    n = 20000
    estimate = estimate_noise(NeighbourIndex(noisy_plane(n, ratio), 16))
    assert estimate.ratio == pytest.approx(ratio, rel=0.2)
    assert estimate.spacing == pytest.approx(1 / np.sqrt(n), rel=0.15)  # the surface's, not the noisy points'
    assert estimate.sigma == pytest.approx(ratio / np.sqrt(n), rel=0.2)


@pytest.mark.parametrize("n, ratio", [(1500, 0.1), (5000, 0.5), (20000, 2.0)])
def test_recovers_noise_over_spacing_on_a_sphere(n, ratio):
    # The quadric takes the curvature out: a sparse, nearly clean sphere is not mistaken for noise.
    estimate = estimate_noise(NeighbourIndex(unit_sphere(n, ratio), 16))
    assert estimate.ratio == pytest.approx(ratio, rel=0.2)


def scan_rows(ratio, along=0.002, across=0.04, seed=0):
    """A scanner's rows on the unit square: points every ``along`` on rows ``across`` apart (20x),
    Gaussian noise of ``ratio`` x the spacing sqrt(along x across)."""
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(np.arange(0, 1, along), np.arange(0, 1, across))
    points = np.stack([x.ravel() + rng.random(x.size) * along, y.ravel(), np.zeros(x.size)], axis=1)
    return points + rng.normal(scale=ratio * np.sqrt(along * across), size=points.shape)


@pytest.mark.parametrize("ratio", [0.05, 0.5])
def test_scan_rows_are_measured_across_the_rows(ratio):
    # The nearest 24 points all lie on the point's own row, which any noise across it fits exactly:
    # the neighbourhood has to grow until it spans several rows.
    estimate = estimate_noise(NeighbourIndex(scan_rows(ratio), 16))
    assert estimate.ratio == pytest.approx(ratio, rel=0.2) and estimate.neighbours > 24


def test_clean_surface_has_next_to_no_noise():
    assert estimate_noise(NeighbourIndex(unit_sphere(3000, 0.0), 16)).ratio < 0.01


def test_wider_balls_only_for_heavier_noise():
    light = estimate_noise(NeighbourIndex(noisy_plane(20000, 0.2), 16))
    heavy = estimate_noise(NeighbourIndex(noisy_plane(20000, 3.0), 16))
    assert light.neighbours == 24 and heavy.neighbours > light.neighbours
    assert heavy.samples * (heavy.neighbours + 1) <= max(noise._SAMPLE_ENTRIES, 64 * (heavy.neighbours + 1))


@pytest.mark.parametrize("n", [0, 1, 5, 11])
def test_too_few_points_give_no_estimate(n):
    estimate = estimate_noise(NeighbourIndex(np.random.default_rng(0).random((n, 3)), 16))
    assert estimate.ratio == 0.0 and estimate.samples == 0


def test_more_noise_more_steps_and_a_weaker_pull():
    ratios = [0.0, 0.05, 0.1, 0.2, 0.3, 0.5, 0.63, 1.0, 5.0]
    steps = [total_steps(r) for r in ratios]
    alphas = [matched_alpha(s) for s in steps]
    assert steps == sorted(steps) and alphas == sorted(alphas, reverse=True)
    assert steps[0] == noise.MIN_STEPS and steps[-1] == noise.MAX_STEPS
    assert total_steps(0.5) == 75  # 300 r^2
    assert steps_per_round(1.0, 3) == 66 and steps_per_round(1.0, 1) == 198 and steps_per_round(0.0, 5) == 1
    assert matched_alpha(66) == pytest.approx(0.01)  # the old fixed defaults lie on the rule
    with pytest.raises(ValueError, match="ratio"):
        total_steps(float("nan"))


def test_noisier_cloud_gets_more_smoothing_end_to_end():
    quiet = core.smooth_point_cloud(unit_sphere(1500, 0.1, seed=1), return_mesh=True)[1]
    loud = core.smooth_point_cloud(unit_sphere(1500, 1.0, seed=1), return_mesh=True)[1]
    assert quiet.noise.ratio < 0.2 < 0.6 < loud.noise.ratio
    assert quiet.iterations_per_round < loud.iterations_per_round and quiet.alpha > loud.alpha


def test_sparse_nearly_clean_sphere_loses_clearly_more_noise():
    # 1500 points, noise 0.1 x the spacing: 66 steps at alpha 0.01 (the old fixed amount) flatten the
    # sphere between samples and remove ~15 %; the chosen 3 steps remove ~50 %.
    points = unit_sphere(1500, 0.1)
    before = sphere_rms(points)
    automatic = sphere_rms(core.smooth_point_cloud(points))
    fixed = sphere_rms(core.smooth_point_cloud(points, alpha=0.01, iterations_per_round=22))
    assert automatic < 0.6 * before and automatic < 0.8 * fixed


def test_report_carries_the_estimate_and_the_amount():
    points = noisy_sphere(3000, 0.01, seed=3)
    _, report = core.smooth_point_cloud(points, return_mesh=True)
    assert report.automatic == ("alpha", "iterations_per_round")
    assert report.noise.ratio > 0 and report.noise.samples > 0 and "noise" in report.seconds
    assert report.rounds == 3
    assert report.iterations_per_round == steps_per_round(report.noise.ratio, 3)
    assert report.alpha == pytest.approx(matched_alpha(3 * report.iterations_per_round))


def test_explicit_numbers_bypass_the_estimate(monkeypatch):
    points = noisy_sphere(800, 0.01, seed=5)
    explicit = dict(alpha=0.01, iterations_per_round=22, rounds=2)
    before, report = core.smooth_point_cloud(points, return_mesh=True, **explicit)
    assert (report.alpha, report.iterations_per_round, report.automatic) == (0.01, 22, ())
    # Whatever the estimate says, explicit numbers give the same result.
    fake = noise.NoiseEstimate(ratio=50.0, sigma=1.0, spacing=0.02, neighbours=24, samples=64)
    monkeypatch.setattr("core.pointcloud.smooth.estimate_noise", lambda index: fake)
    assert np.array_equal(core.smooth_point_cloud(points, **explicit), before)
    # Only the steps given: alpha follows them; only alpha given: the steps follow the (fake) noise.
    _, report = core.smooth_point_cloud(points, return_mesh=True, iterations_per_round=10)
    assert report.alpha == pytest.approx(0.66 / 30) and report.automatic == ("alpha",)
    _, report = core.smooth_point_cloud(points, return_mesh=True, alpha=0.2)
    assert report.alpha == 0.2 and report.iterations_per_round == noise.MAX_STEPS // 3


@pytest.mark.parametrize(
    "options, message",
    [
        (dict(alpha="max"), "alpha must be 'auto' or a number"),
        (dict(alpha=None), "alpha"),
        (dict(iterations_per_round="automatic"), "iterations_per_round must be 'auto' or a whole number"),
        (dict(iterations_per_round=0), "iterations_per_round must be 'auto' or a whole number >= 1"),
        (dict(rounds="auto"), "rounds must be a whole number"),
    ],
)
def test_bad_amounts_raise(options, message):
    with pytest.raises(ValueError, match=message):
        core.smooth_point_cloud(noisy_sphere(50, 0.01), **options)
