"""The local amount (core.pointcloud.local_amount): curvature of the fitted quadric, the influence it gives,
and what it does to a run: flat parts keep the full amount, thin parts get less and shrink less."""

import numpy as np
import pytest
from pointcloud_sets import noisy_sphere, sphere_rms

import core
import core.pointcloud.smooth as pointcloud_smooth
from core.geometry import smallest_eigenvectors
from core.pointcloud.local_amount import THIN_MAX, Z0, curvature, local_influence, sampled_curvature, thinning
from core.pointcloud.spanning_tree import NeighbourIndex


def flat_and_thin(seed=0, sigma=0.004):
    """A flat 1 x 1 square (4000 points) and, far from it, a thin open cylinder of radius 0.03 along z
    (1000 points: about 1.4 spacings around), both with Gaussian noise along the normal."""
    rng = np.random.default_rng(seed)
    flat = np.column_stack([rng.random((4000, 2)), rng.normal(0.0, sigma, 4000)])
    angle, height = rng.random(1000) * 2 * np.pi, rng.random(1000) * 1.5
    radius = 0.03 + rng.normal(0.0, sigma, 1000)
    thin = np.column_stack([3.0 + radius * np.cos(angle), radius * np.sin(angle), height])
    return np.concatenate([flat, thin]), slice(0, 4000), slice(4000, 5000)


def test_curvature_of_a_sphere_and_a_plane():
    sphere = noisy_sphere(5000, 0.0, seed=3) * 2.0  # radius 2: curvature 0.5
    index = NeighbourIndex(sphere, 16)
    assert np.allclose(curvature(index.points, index.neighbour), 0.5, rtol=0.02)
    plane = np.column_stack([np.random.default_rng(1).random((2000, 2)), np.zeros(2000)])
    index = NeighbourIndex(plane, 16)
    assert np.abs(curvature(index.points, index.neighbour)).max() < 1e-9


def test_influence_follows_predicted_shrinkage_against_noise():
    kappa = np.array([0.0, 0.1, 1.0, 5.0, 20.0])
    weight = local_influence(kappa, steps=100, sigma=0.01, spacing=0.02)
    assert weight[0] == 1.0 and weight[1] == 1.0  # flat and gently curved: the full amount
    assert np.all(np.diff(weight) <= 0) and weight[-1] < 0.01
    z = 100 * (5.0 * 0.02) ** 3 * 0.02 / 0.01
    assert weight[3] == pytest.approx(1 / (1 + (z / Z0) ** 2))
    # More noise for the same bend: more of the amount stays.
    assert local_influence(kappa, steps=100, sigma=0.05, spacing=0.02)[3] > weight[3]
    assert np.all(local_influence(kappa, steps=100, sigma=0.0, spacing=0.02) == 1.0)


def test_flat_part_gets_the_full_amount_thin_part_less():
    points, flat, thin = flat_and_thin()
    _, report = core.smooth_point_cloud(points, return_mesh=True)
    assert report.influence.shape == (len(points),)
    # Flat: the full amount but where the noise left after one round still bends the fit a little.
    assert np.median(report.influence[flat]) == 1.0 and report.influence[flat].mean() > 0.94
    assert np.median(report.influence[thin]) < 0.01


@pytest.mark.slow
def test_thin_part_shrinks_less_and_flat_part_is_smoothed_as_before():
    points, flat, thin = flat_and_thin()
    local = core.smooth_point_cloud(points)
    uniform = core.smooth_point_cloud(points, local_amount=False)

    def radius_error(out):
        return abs(np.hypot(out[thin, 0] - 3.0, out[thin, 1]).mean() - 0.03)

    assert radius_error(local) < 0.5 * radius_error(uniform)
    flat_rms = [np.sqrt(np.mean(out[flat, 2] ** 2)) for out in (points, uniform, local)]
    assert flat_rms[2] < 0.5 * flat_rms[0] and flat_rms[2] == pytest.approx(flat_rms[1], rel=0.1)


def test_weight_one_everywhere_is_the_uniform_run_bit_for_bit(monkeypatch):
    points = noisy_sphere(3000, 0.01, seed=5)
    uniform = core.smooth_point_cloud(points, local_amount=False)
    monkeypatch.setattr(pointcloud_smooth, "local_influence", lambda kappa, *args: np.ones_like(kappa))
    ones = core.smooth_point_cloud(points)
    assert np.array_equal(ones, uniform)
    monkeypatch.undo()
    assert not np.array_equal(core.smooth_point_cloud(points), uniform)  # the real weights do change it


def test_explicit_steps_are_taken_in_full():
    points, _, _ = flat_and_thin()
    explicit = dict(iterations_per_round=7, alpha=0.03)
    out, report = core.smooth_point_cloud(points, return_mesh=True, **explicit)
    assert report.influence is None
    assert np.array_equal(out, core.smooth_point_cloud(points, local_amount=False, **explicit))


def test_closed_form_normals_agree_with_eigh():
    rng = np.random.default_rng(4)
    spread = rng.normal(size=(2000, 17, 3)) * [1.0, 0.7, 0.02]  # flat patches ...
    spread[:200] *= [1.0, 1e-9, 1e-9]  # ... and collinear ones: no clear smallest direction
    rotation = np.linalg.qr(rng.normal(size=(2000, 3, 3)))[0]
    patch = np.einsum("ski,sji->skj", spread, rotation)
    matrices = np.einsum("ski,skj->sij", patch, patch)
    entries = [matrices[:, i, j] for i, j in ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))]
    ours = smallest_eigenvectors(*entries)
    reference = np.linalg.eigh(matrices)[1][:, :, 0]
    assert np.allclose(np.linalg.norm(ours, axis=1), 1.0)
    assert np.abs(np.abs(np.einsum("si,si->s", ours[200:], reference[200:])) - 1.0).max() < 1e-9
    # Collinear: any direction across the line is a smallest eigenvector.
    line = rotation[:200, :, 0]
    assert np.abs(np.einsum("si,si->s", ours[:200], line)).max() < 1e-6


def test_curvature_of_a_thin_cylinder():
    rng = np.random.default_rng(2)
    angle, height = rng.random(6000) * 2 * np.pi, rng.random(6000) * 2.0
    cylinder = np.column_stack([0.25 * np.cos(angle), 0.25 * np.sin(angle), height])
    index = NeighbourIndex(cylinder, 16)
    assert np.median(curvature(index.points, index.neighbour)) == pytest.approx(4.0, rel=0.03)


def noisy_unit_sphere(n, noise_in_spacings, seed=0):
    """Unit sphere, Gaussian radial noise of ``noise_in_spacings`` nearest-neighbour spacings."""
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    spacing = np.median(NeighbourIndex(v, 1).distance[:, 0])
    return v * (1.0 + rng.normal(scale=noise_in_spacings * spacing, size=(n, 1)))


def test_thinning_grows_with_the_noise_within_bounds():
    assert thinning(0.0) == 1.0 and thinning(0.5) == 1.0  # little noise: every point, as before
    assert 1.0 < thinning(1.0) < thinning(2.0) < THIN_MAX
    assert thinning(10.0) == THIN_MAX


def test_no_thinning_is_the_plain_fit_bit_for_bit():
    index = NeighbourIndex(noisy_unit_sphere(3000, 0.5, seed=1), 16)
    plain = curvature(index.points, index.neighbour)
    assert np.array_equal(sampled_curvature(index.points, index.neighbour, 1.0), plain)
    # Too few points for a sample of fits: the plain fit too.
    assert np.array_equal(sampled_curvature(index.points, index.neighbour, 50.0), plain)


def test_sampled_fit_reads_the_curvature_through_noise():
    """Noise of half a spacing: over 16 neighbours (a ball of ~2.3 spacings) the quadric reads it as
    curvature several times the sphere's; fitted on every 16th point (a ball 4 times wider) it reads
    the sphere's."""
    index = NeighbourIndex(noisy_unit_sphere(20000, 0.5, seed=2), 16)
    plain = curvature(index.points, index.neighbour)
    sampled = sampled_curvature(index.points, index.neighbour, 16.0)
    assert np.median(plain) > 4.0
    assert np.median(sampled) == pytest.approx(1.0, rel=0.3)
    assert np.percentile(sampled, 90) < 2.0
    assert np.isfinite(sampled).all() and sampled.shape == plain.shape


@pytest.mark.slow
def test_large_noise_keeps_the_full_amount_on_a_gentle_surface(monkeypatch):
    """Noise of ~1.3 spacings on a sphere of ~90 spacings' radius: the first round leaves enough noise
    that the 16-neighbour fit gives many points a small share; the wider sampled fit does not, and the
    run removes more of the noise."""
    points = noisy_sphere(20000, 0.01, seed=1)
    out, report = core.smooth_point_cloud(points, return_mesh=True)
    assert report.noise.ratio > 1.0 and thinning(report.noise.ratio) > 4.0
    monkeypatch.setattr(pointcloud_smooth, "thinning", lambda ratio: 1.0)
    narrow, narrow_report = core.smooth_point_cloud(points, return_mesh=True)
    assert np.mean(report.influence < 1) < 0.2 < 0.35 < np.mean(narrow_report.influence < 1)
    assert sphere_rms(out) < 0.95 * sphere_rms(narrow)
