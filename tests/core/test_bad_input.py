"""Bad input raises ValueError with a message a user can act on, and changes nothing."""

import warnings
from decimal import Decimal
from fractions import Fraction

import numpy as np
import pytest
import small_meshes as sm

import core

POSITIONS, FACES = sm.octahedron()
EDGES = sm.edges_of(FACES)


def run(**overrides):
    arguments = dict(positions=POSITIONS, edges=EDGES, alpha=0.1, beta=0.6, iterations=3)
    arguments.update(overrides)
    positions, edges = arguments.pop("positions"), arguments.pop("edges")
    return core.hc_smooth(positions, edges, **arguments)


@pytest.mark.parametrize(
    "overrides,message",
    [
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
        (dict(alpha=Decimal("0.1")), "alpha must be a number"),  # not a numbers.Real
        (dict(iterations=-1), "iterations must be 0 or more"),
        (dict(iterations=2.5), "whole number"),
        (dict(mode="parallel"), "mode must be one of"),
        (dict(fixed=np.zeros(5, dtype=bool)), "length 6"),
        (dict(fixed=np.array([7])), "0..5"),
        (dict(tolerance=-1.0), "tolerance"),
        (dict(original=np.zeros((5, 3))), "original must have the shape"),
        (dict(operator=core.umbrella_operator(EDGES, 7)), "built for 6 vertices"),
    ],
)
def test_bad_input_raises_value_error(overrides, message):
    positions = overrides.get("positions", POSITIONS)
    before = np.array(positions, copy=True)
    with pytest.raises(ValueError, match=message):
        run(**overrides)
    np.testing.assert_array_equal(np.asarray(positions), before)


def test_any_real_number_is_a_number():
    """A Fraction or a NumPy scalar is a number like a float: the same run, and reports hold floats."""
    as_floats = run(alpha=0.1, beta=0.6, tolerance=0.001)
    exact = dict(alpha=Fraction(1, 10), beta=Fraction(3, 5), tolerance=Fraction(1, 1000))
    np.testing.assert_array_equal(run(**exact), as_floats)
    np.testing.assert_array_equal(run(alpha=np.float64(0.1), beta=np.float64(0.6), tolerance=0.001), as_floats)
    _, report = core.smooth_mesh(POSITIONS, EDGES, iterations=3, return_report=True, **exact)
    assert type(report.alpha) is float and report.alpha == 0.1 and type(report.beta) is float
    cloud = np.random.default_rng(0).random((200, 3))
    np.testing.assert_array_equal(
        core.smooth_point_cloud(cloud, alpha=Fraction(1, 10), rounds=1, iterations_per_round=2),
        core.smooth_point_cloud(cloud, alpha=0.1, rounds=1, iterations_per_round=2),
    )


def test_unknown_variant_and_method():
    with pytest.raises(ValueError, match="variant must be one of"):
        core.laplacian_smooth(POSITIONS, EDGES, variant="cotangent", iterations=1)
    with pytest.raises(ValueError, match="method must be one of"):
        core.smooth(POSITIONS, EDGES, method="taubin", iterations=1)


@pytest.mark.parametrize("mode", core.MODES)
def test_degenerate_but_valid_meshes(mode):
    empty = core.hc_smooth(np.zeros((0, 3)), np.zeros((0, 2), dtype=int), alpha=0.1, beta=0.6, iterations=5, mode=mode)
    assert empty.shape == (0, 3)
    no_edges = core.hc_smooth(POSITIONS, np.zeros((0, 2), dtype=int), alpha=0.1, beta=0.6, iterations=5, mode=mode)
    assert np.array_equal(no_edges, POSITIONS)  # every vertex isolated, hence fixed
    all_fixed = core.smooth(
        POSITIONS, EDGES, alpha=0.1, beta=0.6, iterations=5, mode=mode, fixed=np.ones(6, dtype=bool)
    )
    assert np.array_equal(all_fixed.positions, POSITIONS)
    zero = core.smooth(POSITIONS, EDGES, alpha=0.1, beta=0.6, iterations=0, mode=mode)
    assert np.array_equal(zero.positions, POSITIONS) and zero.iterations == 0


@pytest.mark.parametrize("options", [{}, {"iterations": 3}, {"border": "curve"}, {"weld": True}], ids=repr)
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_smooth_mesh_returns_an_empty_mesh_quietly(dtype, options):
    """No vertices, no faces: an empty result of the same dtype, as hc_smooth gives, and no NumPy warning."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = core.smooth_mesh(
            np.zeros((0, 3), dtype), np.zeros((0, 2), int), faces=np.zeros((0, 3), int), **options
        )
    assert result.shape == (0, 3) and result.dtype == dtype
    assert [str(warning.message) for warning in caught] == []


def test_coincident_points_give_no_nan():
    positions = np.zeros((6, 3))
    result = core.hc_smooth(positions, EDGES, alpha=0.1, beta=0.6, iterations=10, tolerance=1e-3)
    assert np.array_equal(result, positions)


INT_MASK = np.array([0, 1, 1, 0, 0, 1])  # a mask of the octahedron's 6 vertices, in int form


@pytest.mark.parametrize("fixed", [INT_MASK, INT_MASK.tolist(), np.zeros(6, np.int32), np.ones(6, np.uint8)])
def test_fixed_that_reads_as_mask_or_indices_is_refused(fixed):
    with pytest.raises(ValueError, match=r"0s and 1s.*fixed\.astype\(bool\).*np\.flatnonzero"):
        run(fixed=fixed)
    with pytest.raises(ValueError, match=r"fixed\.astype\(bool\)"):
        core.smooth_point_cloud(POSITIONS, fixed=fixed)


def test_fixed_as_mask_or_unambiguous_indices_is_accepted():
    mask = INT_MASK.astype(bool)
    expected = run(fixed=mask)
    assert np.array_equal(expected[mask], POSITIONS[mask]) and not np.array_equal(expected, POSITIONS)
    for indices in (np.flatnonzero(mask), [5, 2, 1, 2], np.array([1, 2, 5, 1, 2, 5, 1])):
        assert np.array_equal(run(fixed=indices), expected)
    # As long as the vertex count but with indices above 1: unambiguous.
    assert np.array_equal(run(fixed=np.arange(6)), POSITIONS)


def test_fixed_on_tiny_meshes():
    two, edge = np.array([[0.0, 0, 0], [1.0, 0, 0]]), np.array([[0, 1]])
    one_fixed = core.hc_smooth(two, edge, alpha=0.1, beta=0.6, iterations=1, fixed=[1])
    assert np.array_equal(one_fixed[1], two[1]) and not np.array_equal(one_fixed[0], two[0])
    # With 2 vertices [0, 1] is both indices (fix both) and a mask (fix vertex 1): refused, and the
    # message says how to fix both.
    with pytest.raises(ValueError, match="2 vertices, fix both with a boolean mask"):
        core.hc_smooth(two, edge, alpha=0.1, beta=0.6, iterations=1, fixed=[0, 1])
    both = core.hc_smooth(two, edge, alpha=0.1, beta=0.6, iterations=1, fixed=np.ones(2, bool))
    assert np.array_equal(both, two)
    # One vertex has no neighbours and never moves: [0] is read as its index, either reading is the same.
    lone = np.array([[1.0, 2.0, 3.0]])
    assert np.array_equal(
        core.hc_smooth(lone, np.zeros((0, 2), int), alpha=0.1, beta=0.6, iterations=1, fixed=[0]), lone
    )
