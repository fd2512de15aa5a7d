"""Bad input raises ValueError with a message a user can act on, and changes nothing."""

import numpy as np
import pytest

import core
import small_meshes as sm

POSITIONS, FACES = sm.octahedron()
EDGES = sm.edges_of(FACES)


def run(**overrides):
    arguments = dict(positions=POSITIONS, edges=EDGES, alpha=0.1, beta=0.6, iterations=3)
    arguments.update(overrides)
    positions, edges = arguments.pop("positions"), arguments.pop("edges")
    return core.hc_smooth(positions, edges, **arguments)


@pytest.mark.parametrize("overrides,message", [
    (dict(positions=np.zeros((6, 2))), r"shape \(n, 3\)"),
    (dict(positions=np.zeros(6)), r"shape \(n, 3\)"),
    (dict(positions=np.zeros((6, 3), dtype=np.int64)), "float32 or float64"),
    (dict(positions=np.where(np.arange(18).reshape(6, 3) == 4, np.nan, 0.0)), "NaN or infinite.*vertex 1"),
    (dict(positions=np.full((6, 3), np.inf)), "NaN or infinite"),
    (dict(edges=np.array([[0, 1, 2]])), r"shape \(m, 2\)"),
    (dict(edges=np.array([[0.0, 1.0]])), "integer"),
    (dict(edges=np.array([[0, 6]])), "vertex 6.*only 6 vertices"),
    (dict(edges=np.array([[-1, 2]])), "vertex -1"),
    (dict(alpha=-0.1), "alpha must lie between 0 and 1"),
    (dict(beta=1.5), "beta must lie between 0 and 1"),
    (dict(alpha=float("nan")), "alpha"),
    (dict(alpha="0.5"), "alpha"),
    (dict(iterations=-1), "iterations must be 0 or more"),
    (dict(iterations=2.5), "whole number"),
    (dict(mode="parallel"), "mode must be one of"),
    (dict(fixed=np.zeros(5, dtype=bool)), "length 6"),
    (dict(fixed=np.array([7])), "0..5"),
    (dict(tolerance=-1.0), "tolerance"),
    (dict(original=np.zeros((5, 3))), "original must have the shape"),
    (dict(operator=core.umbrella_operator(EDGES, 7)), "built for 6 vertices"),
])
def test_bad_input_raises_value_error(overrides, message):
    positions = overrides.get("positions", POSITIONS)
    before = np.array(positions, copy=True)
    with pytest.raises(ValueError, match=message):
        run(**overrides)
    np.testing.assert_array_equal(np.asarray(positions), before)


def test_unknown_variant_and_method():
    with pytest.raises(ValueError, match="variant must be one of"):
        core.laplacian_smooth(POSITIONS, EDGES, variant="cotangent", iterations=1)
    with pytest.raises(ValueError, match="method must be one of"):
        core.smooth(POSITIONS, EDGES, method="taubin", iterations=1)


@pytest.mark.parametrize("mode", core.MODES)
def test_degenerate_but_valid_meshes(mode):
    empty = core.hc_smooth(np.zeros((0, 3)), np.zeros((0, 2), dtype=int), alpha=0.1, beta=0.6, iterations=5,
                           mode=mode)
    assert empty.shape == (0, 3)
    no_edges = core.hc_smooth(POSITIONS, np.zeros((0, 2), dtype=int), alpha=0.1, beta=0.6, iterations=5, mode=mode)
    assert np.array_equal(no_edges, POSITIONS)  # every vertex isolated, hence fixed
    all_fixed = core.smooth(POSITIONS, EDGES, alpha=0.1, beta=0.6, iterations=5, mode=mode,
                            fixed=np.ones(6, dtype=bool))
    assert np.array_equal(all_fixed.positions, POSITIONS)
    zero = core.smooth(POSITIONS, EDGES, alpha=0.1, beta=0.6, iterations=0, mode=mode)
    assert np.array_equal(zero.positions, POSITIONS) and zero.iterations == 0


def test_coincident_points_give_no_nan():
    positions = np.zeros((6, 3))
    result = core.hc_smooth(positions, EDGES, alpha=0.1, beta=0.6, iterations=10, tolerance=1e-3)
    assert np.array_equal(result, positions)
