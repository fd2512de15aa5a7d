"""core.mesh.world: an object's coordinates taken through its stretch, so that lengths are the world's."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import core
from core.mesh import world


def matrix(scale=(1.0, 1.0, 1.0), rotation=(0.0, 0.0, 0.0), location=(0.0, 0.0, 0.0)):
    """A world matrix as Blender builds it (location, rotation, scale), in single precision."""
    result = np.eye(4)
    result[:3, :3] = Rotation.from_euler("xyz", rotation).as_matrix() @ np.diag(scale)
    result[:3, 3] = location
    return result.astype(np.float32)


@pytest.mark.parametrize(
    "transform",
    [
        {},
        dict(rotation=(0.4, -0.3, 1.1)),
        dict(scale=(-1.0, 1.0, 1.0)),
        dict(scale=(1.0, -1.0, -1.0), rotation=(2.0, 0.5, -1.0), location=(5.0, -3.0, 100.0)),
    ],
)
def test_lengths_kept_means_object_space(transform):
    assert world.frame(matrix(**transform)) is None


@pytest.mark.parametrize(
    "transform",
    [
        dict(scale=(10.0, 10.0, 10.0)),
        dict(scale=(1.0, 1.0, 10.0)),
        dict(scale=(1.0, 1.0, 10.0), rotation=(0.4, -0.3, 1.1)),
        dict(scale=(-2.0, 0.5, 3.0), rotation=(1.2, 0.1, -0.7)),
        dict(scale=(1e-3, 2e-3, 1e-3), rotation=(0.1, 0.2, 0.3)),
    ],
)
def test_the_frame_measures_every_move_as_the_world_does(transform):
    full = matrix(**transform)
    stretch = world.frame(full)
    assert np.allclose(stretch, stretch.T, rtol=0, atol=1e-12 * np.abs(stretch).max())
    assert np.linalg.det(stretch) > 0  # the faces keep their winding, mirrored or not
    moves = np.random.default_rng(0).normal(size=(100, 3))
    np.testing.assert_allclose(
        np.linalg.norm(moves @ stretch.T, axis=1),
        np.linalg.norm(moves @ full[:3, :3].astype(np.float64).T, axis=1),
        rtol=1e-12,
    )


def test_a_uniform_scale_is_a_number():
    assert np.array_equal(world.frame(matrix(scale=(-8.0, 8.0, 8.0))), 8.0 * np.eye(3))
    rotated = world.frame(matrix(scale=(8.0, 8.0, 8.0), rotation=(0.3, 0.0, 0.0)))  # its entries rounded
    assert np.array_equal(rotated, rotated[0, 0] * np.eye(3)) and rotated[0, 0] == pytest.approx(8.0, rel=1e-7)


@pytest.mark.parametrize(
    "bad", [matrix(scale=(1.0, 0.0, 1.0)), matrix(scale=(1.0, 1e-8, 1.0)), np.full((4, 4), np.nan)]
)
def test_a_flattened_or_broken_transform_is_refused(bad):
    with pytest.raises(ValueError, match="scale|finite"):
        world.frame(bad)


def test_there_and_back_keeps_the_bits_of_what_did_not_move():
    rng = np.random.default_rng(1)
    local = rng.normal(size=(50, 3)).astype(np.float32)
    local[0, 0] = -0.0
    stretch = world.frame(matrix(scale=(1.0, 1.0, 10.0), rotation=(0.4, -0.3, 1.1)))
    start = world.to_frame(local, stretch)
    assert start.dtype == np.float32
    result = start.copy()
    result[10:] += rng.normal(scale=0.01, size=(40, 3)).astype(np.float32)
    back = world.from_frame(local, start, result, stretch)
    assert np.array_equal(back[:10].view(np.uint32), local[:10].view(np.uint32))
    expected = local[10:] + (result[10:].astype(np.float64) - start[10:]) @ np.linalg.inv(stretch).T
    np.testing.assert_allclose(back[10:], expected, rtol=0, atol=1e-6)


def test_hc_in_the_frame_is_hc_in_object_space_and_its_limit_is_the_worlds():
    """The steps are linear in the positions: only the limit tells the frame from object space."""
    rng = np.random.default_rng(2)
    positions = rng.normal(size=(200, 3)).astype(np.float32)
    edges = np.array([(i, j) for i in range(200) for j in (i + 1, i + 7) if j < 200])
    full = matrix(scale=(1.0, 1.0, 10.0), rotation=(0.4, -0.3, 1.1))
    stretch = world.frame(full)
    start = world.to_frame(positions, stretch)
    options = dict(alpha=0.1, beta=0.6, iterations=10)
    free = world.from_frame(positions, start, core.hc_smooth(start, edges, **options), stretch)
    np.testing.assert_allclose(free, core.hc_smooth(positions, edges, **options), rtol=0, atol=2e-5)
    limited = core.smooth(start, edges, max_deviation=0.05, **options).positions
    back = world.from_frame(positions, start, limited, stretch)
    linear = full[:3, :3].astype(np.float64)
    moves = np.linalg.norm((back.astype(np.float64) - positions) @ linear.T, axis=1)
    assert moves.max() <= 0.05 * (1 + 1e-4) and moves.max() > 0.049
