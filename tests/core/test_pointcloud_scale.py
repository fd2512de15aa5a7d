"""Units do not matter: the same cloud in metres or in micrometres is smoothed the same, and a scale
float64 cannot hold is refused up front."""

import numpy as np
import pytest
from pointcloud_sets import noisy_sphere
from pointcloud_stages import emst, swap_pass

import core
from core.pointcloud import estimate_noise, rfs_mesh, surface_description_graph
from core.pointcloud.spanning_tree import NeighbourIndex, boruvka_emst

SCALES = [1e-6, 1e-3, 1e3, 1e6]
# smooth(s P) / s against smooth(P), relative to the diagonal. Each HC step rounds a few times at a few
# ulps and HC contracts (alpha > 0, beta > 0.5), so even 198 steps stay near 200 x 2.2e-16 = 4.4e-14;
# measured: below 1e-15.
RTOL = 1e-13
EXPLICIT = dict(alpha=0.05, iterations_per_round=4)


@pytest.fixture(scope="module")
def sphere():
    points = noisy_sphere(2000, 0.01, seed=3)
    fixed = np.zeros(len(points), dtype=bool)
    fixed[::10] = True
    return points, fixed


@pytest.fixture(scope="module")
def reference(sphere):
    points, fixed = sphere
    return {
        name: core.smooth_point_cloud(points, fixed=fixed, return_mesh=True, **options)
        for name, options in (("auto", {}), ("explicit", EXPLICIT))
    }


def diagonal(points):
    return float(np.linalg.norm(np.ptp(points, axis=0)))


@pytest.mark.slow
@pytest.mark.parametrize("amount", ["auto", "explicit"])
@pytest.mark.parametrize("scale", SCALES)
def test_result_is_scale_equivariant(sphere, reference, amount, scale):
    points, fixed = sphere
    expected, expected_report = reference[amount]
    out, report = core.smooth_point_cloud(
        points * scale, fixed=fixed, return_mesh=True, **(EXPLICIT if amount == "explicit" else {})
    )
    assert np.abs(out / scale - expected).max() <= RTOL * diagonal(points)
    assert np.array_equal(out[fixed], (points * scale)[fixed])  # fixed points keep their bits
    # The same amount of smoothing and the same mesh: no decision depended on the unit.
    assert (report.rounds, report.iterations_per_round, report.alpha) == (
        expected_report.rounds,
        expected_report.iterations_per_round,
        expected_report.alpha,
    )
    assert np.array_equal(report.mesh.faces, expected_report.mesh.faces)
    assert report.noise.ratio == pytest.approx(expected_report.noise.ratio, rel=1e-12)
    assert report.noise.sigma == pytest.approx(expected_report.noise.sigma * scale, rel=1e-12)
    assert np.abs(expected - points).max() > 1e-3 * diagonal(points)  # the run smoothed: not vacuous


@pytest.mark.parametrize("scale", [1e-300, 1e300])
def test_far_scales_are_smoothed_the_same(sphere, reference, scale):
    points, fixed = sphere
    expected, _ = reference["auto"]
    out = core.smooth_point_cloud(points * scale, fixed=fixed)
    assert np.abs(out / scale - expected).max() <= RTOL * diagonal(points)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("scale", [2.0**-40, 2.0**30])
def test_power_of_two_scales_are_bit_exact(dtype, scale):
    points = noisy_sphere(500, 0.01, seed=4, dtype=dtype)
    expected = core.smooth_point_cloud(points)
    out = core.smooth_point_cloud(points * dtype(scale))
    assert np.array_equal(out, expected * dtype(scale))
    assert out.dtype == dtype and not np.array_equal(out, points * dtype(scale))


def test_points_left_in_place_keep_their_bits():
    # A point far off a huge sphere gets no face. Its small coordinates are far below the sphere's
    # precision (divided by the cloud's scale they underflow), and still come back bit for bit.
    points = np.concatenate([noisy_sphere(500, 0.01, seed=6) * 1e300, [[1e302, 1e-20, -3e-30]]])
    out, report = core.smooth_point_cloud(points, return_mesh=True)
    assert report.isolated == 1 and len(points) - 1 not in report.mesh.faces
    assert np.array_equal(out[-1].view(np.uint8), points[-1].view(np.uint8))
    assert np.abs(out[:-1] - points[:-1]).max() > 0
    unmoved = core.smooth_point_cloud(points, rounds=0)
    assert np.array_equal(unmoved.view(np.uint8), points.view(np.uint8))


@pytest.mark.parametrize(
    "dtype, scale",
    [
        (np.float64, 1e-310),
        (np.float64, 1e-320),
        (np.float64, 1e308),
        (np.float64, 2e307),
        (np.float32, 1e-39),
        (np.float32, 1e38),
    ],
)
def test_scales_float_cannot_hold_are_refused_up_front(dtype, scale):
    points = (noisy_sphere(300, 0.01, seed=7) * scale).astype(dtype)
    assert np.isfinite(points).all() and np.abs(points).max() > 0
    message = r"scale of the points' coordinates is out of range.*rescale"
    with pytest.raises(ValueError, match=message):
        core.pointcloud.PointCloudSmoother(points)  # on construction, before any work
    with pytest.raises(ValueError, match=message):
        core.smooth_point_cloud(points)


def test_all_zero_and_single_points_are_fine():
    assert np.array_equal(core.smooth_point_cloud(np.zeros((5, 3))), np.zeros((5, 3)))
    assert np.array_equal(core.smooth_point_cloud(np.array([[1e-300, 0, 0]])), [[1e-300, 0, 0]])


@pytest.mark.parametrize("scale", [1e-6, 1e6])
def test_every_stage_is_scale_free_on_its_own(scale):
    """The stages' thresholds are relative (angles, ratios of lengths, the noise fit in units of its
    ball), so each gives the same answer on s P without the smoother's normalisation."""
    points = noisy_sphere(1500, 0.01, seed=8)
    scaled = points * scale

    def stages(p):
        index = NeighbourIndex(p, 16)
        tree, _ = boruvka_emst(index)
        graph = surface_description_graph(index, tree, spacing_factor=2.5)
        mesh = rfs_mesh(index.points, graph.edges)
        moved = index.points + np.random.default_rng(0).normal(
            scale=0.3 * np.median(graph.spacing), size=index.points.shape
        )
        return index, tree, graph, mesh, swap_pass(moved, mesh.faces), estimate_noise(index)

    index, tree, graph, mesh, swapped, noise = stages(points)
    index_s, tree_s, graph_s, mesh_s, swapped_s, noise_s = stages(scaled)
    assert np.array_equal(index.original, index_s.original) and np.array_equal(tree, tree_s)
    assert np.array_equal(graph.edges, graph_s.edges)
    assert np.array_equal(mesh.faces, mesh_s.faces) and len(mesh.faces) > len(points)
    assert swapped[2] > 0 and swapped[2] == swapped_s[2] and np.array_equal(swapped[0], swapped_s[0])
    assert noise_s.ratio == pytest.approx(noise.ratio, rel=1e-12) and noise.ratio > 0
    assert noise_s.sigma == pytest.approx(noise.sigma * scale, rel=1e-12)
    assert np.array_equal(np.sort(emst(points), axis=1), np.sort(emst(scaled), axis=1))
