"""Properties on random graphs: fixed vertices bit-identical, no NaN, input untouched whatever its memory
layout, dtype kept, results scale-equivariant."""

import warnings

import numpy as np
import pytest
import small_meshes as sm
from hypothesis import given, settings
from hypothesis import strategies as st
from pointcloud_sets import noisy_sphere
from pointcloud_stages import emst, swap_pass

import core
from core.pointcloud import rfs_mesh, surface_description_graph
from core.pointcloud.spanning_tree import NeighbourIndex, boruvka_emst


@st.composite
def random_meshes(draw):
    n = draw(st.integers(min_value=0, max_value=30))
    m = draw(st.integers(min_value=0, max_value=60)) if n else 0
    seed = draw(st.integers(min_value=0, max_value=2**32 - 1))
    rng = np.random.default_rng(seed)
    dtype = draw(st.sampled_from([np.float32, np.float64]))
    scale = draw(st.sampled_from([1e-3, 1.0, 1e4]))
    positions = (rng.normal(size=(n, 3)) * scale).astype(dtype)
    edges = rng.integers(0, max(n, 1), size=(m, 2))
    fixed = rng.random(n) < draw(st.sampled_from([0.0, 0.2, 1.0]))
    return positions, edges, fixed


settings.register_profile("ci", max_examples=150, deadline=None)
settings.load_profile("ci")


def bits(array):
    return np.ascontiguousarray(array).view(np.uint8)


LAYOUTS = ("fortran", "every_other_row", "column_slice", "reversed", "read_only", "read_only_fortran")


def in_layout(array, layout):
    """A new array holding ``array``'s values in another memory layout (a view into a larger buffer
    where the layout needs one)."""
    array = np.asarray(array)
    if layout in ("fortran", "read_only_fortran"):
        out = np.array(array, order="F")
    elif layout == "every_other_row":
        buffer = np.zeros((2 * len(array),) + array.shape[1:], dtype=array.dtype)
        buffer[::2] = array
        out = buffer[::2]
    elif layout == "column_slice":  # e.g. the position columns of an (n, 6) position + normal array
        width = array.shape[1] if array.ndim == 2 else 1
        buffer = np.zeros((len(array), 2 * width), dtype=array.dtype)
        out = buffer[:, width:] if array.ndim == 2 else buffer[:, 1]
        out[...] = array
    elif layout == "reversed":
        out = array[::-1].copy()[::-1]
    elif layout == "read_only":
        out = array.copy()
    if layout.startswith("read_only"):
        out.flags.writeable = False
    return out


def test_layouts_are_what_they_say():
    array = np.arange(24.0).reshape(8, 3)
    for layout in LAYOUTS:
        out = in_layout(array, layout)
        assert np.array_equal(out, array) and not np.shares_memory(out, array)
        assert out.flags.writeable == (not layout.startswith("read_only"))
        assert out.flags.c_contiguous == (layout == "read_only")
    assert in_layout(array, "reversed").strides[0] < 0
    assert in_layout(np.arange(8), "column_slice").strides == (16,)


def as_indices(mask):
    """The fixed vertices as an index array; for the one ambiguous case (both of 2 vertices: [0, 1]
    also reads as a 0/1 mask, which core refuses) the mask itself."""
    indices = np.flatnonzero(mask)
    return mask if len(mask) == 2 and indices.size == 2 else indices


def quietly(function, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)
        return function(*args, **kwargs)


@given(
    random_meshes(),
    st.sampled_from(core.METHODS),
    st.sampled_from(core.MODES),
    st.floats(0, 1),
    st.floats(0, 1),
    st.integers(0, 6),
)
def test_invariants(mesh, method, mode, alpha, beta, iterations):
    positions, edges, fixed = mesh
    before = positions.copy()
    edges_before = edges.copy()
    try:
        result = quietly(
            core.smooth,
            positions,
            edges,
            method=method,
            alpha=alpha,
            beta=beta,
            iterations=iterations,
            mode=mode,
            fixed=fixed,
        )
    except core.DivergenceError:
        # Only HC outside the convergence region may blow up; the input is untouched even then.
        assert method == "hc" and not core.in_convergence_region(alpha, beta)
        assert np.array_equal(positions, before)
        return
    out = result.positions
    assert out.dtype == positions.dtype and out.shape == positions.shape
    assert out is not positions
    assert np.array_equal(positions, before) and np.array_equal(edges, edges_before)  # inputs untouched
    assert np.isfinite(out).all()
    isolated = np.ones(len(positions), dtype=bool)
    isolated[edges[edges[:, 0] != edges[:, 1]].ravel()] = False
    frozen = fixed | isolated
    assert np.array_equal(out[frozen].view(np.uint8), before[frozen].view(np.uint8))  # bit-identical
    assert result.iterations <= iterations


@given(
    random_meshes(),
    st.sampled_from(core.METHODS),
    st.sampled_from(core.MODES),
    st.sampled_from(LAYOUTS),
    st.booleans(),
    st.booleans(),
    st.integers(0, 4),
)
def test_every_input_layout_is_untouched_and_gives_the_contiguous_result(
    mesh, method, mode, layout, with_original, fixed_as_indices, iterations
):
    positions, edges, mask = mesh
    rng = np.random.default_rng(len(positions))
    original = (positions + rng.normal(size=positions.shape).astype(positions.dtype)) if with_original else None
    fixed = as_indices(mask) if fixed_as_indices else mask
    options = dict(method=method, alpha=0.3, beta=0.7, iterations=iterations, mode=mode)
    expected = quietly(
        core.smooth,
        positions.copy(),
        edges,
        fixed=fixed.copy(),
        original=None if original is None else original.copy(),
        **options,
    )
    inputs = dict(positions=positions, edges=edges, fixed=fixed, original=original)
    laid_out = {name: None if value is None else in_layout(value, layout) for name, value in inputs.items()}
    result = quietly(
        core.smooth,
        laid_out["positions"],
        laid_out["edges"],
        fixed=laid_out["fixed"],
        original=laid_out["original"],
        **options,
    )
    assert np.array_equal(bits(result.positions), bits(expected.positions))  # bit for bit
    assert result.positions.flags.writeable and result.iterations == expected.iterations
    for name, value in inputs.items():
        if value is not None:
            assert np.array_equal(bits(laid_out[name]), bits(value)), f"{name} was modified"


@pytest.mark.slow
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("layout", LAYOUTS)
def test_point_cloud_input_of_every_layout_is_untouched_and_gives_the_contiguous_result(layout, dtype):
    points = noisy_sphere(150, 0.01, seed=5, dtype=dtype)
    mask = np.zeros(len(points), dtype=bool)
    mask[::9] = True
    for fixed in (mask, np.flatnonzero(mask)):
        expected = core.smooth_point_cloud(points.copy(), rounds=2, fixed=fixed.copy())
        laid_out, laid_out_fixed = in_layout(points, layout), in_layout(fixed, layout)
        out = core.smooth_point_cloud(laid_out, rounds=2, fixed=laid_out_fixed)
        assert np.array_equal(bits(out), bits(expected)) and out.flags.writeable
        assert np.array_equal(bits(laid_out), bits(points)) and np.array_equal(laid_out_fixed, fixed)
    assert np.abs(expected - points).max() > 0  # the run moved points: the comparison is not vacuous


@given(random_meshes(), st.sampled_from(core.MODES))
def test_fixed_as_indices_equals_fixed_as_mask(mesh, mode):
    positions, edges, fixed = mesh
    a = core.hc_smooth(positions, edges, alpha=0.1, beta=0.6, iterations=3, mode=mode, fixed=fixed)
    indices = np.flatnonzero(fixed)
    if len(positions) == 2 and indices.size == 2:  # [0, 1] also reads as a 0/1 mask: refused
        with pytest.raises(ValueError, match="boolean mask"):
            core.hc_smooth(positions, edges, alpha=0.1, beta=0.6, iterations=3, mode=mode, fixed=indices)
        return
    b = core.hc_smooth(positions, edges, alpha=0.1, beta=0.6, iterations=3, mode=mode, fixed=indices)
    assert np.array_equal(a, b)


@given(random_meshes())
def test_edge_order_direction_and_duplicates_do_not_matter(mesh):
    positions, edges, _ = mesh
    rng = np.random.default_rng(len(edges))
    shuffled = np.concatenate([edges, edges[:, ::-1]])[rng.permutation(2 * len(edges))] if len(edges) else edges
    a = core.hc_smooth(positions, edges, alpha=0.1, beta=0.6, iterations=2)
    b = core.hc_smooth(positions, shuffled, alpha=0.1, beta=0.6, iterations=2)
    np.testing.assert_allclose(a, b, rtol=1e-6 if positions.dtype == np.float32 else 1e-12, atol=1e-30)


@given(
    random_meshes(),
    st.sampled_from(core.METHODS),
    st.sampled_from(core.MODES),
    st.sampled_from([1e-6, 1e-3, 7.0, 1e3, 1e6]),
    st.integers(0, 8),
)
def test_mesh_smoothing_is_scale_equivariant(mesh, method, mode, scale, iterations):
    positions, edges, fixed = mesh
    positions = positions.astype(np.float64)
    options = dict(method=method, alpha=0.2, beta=0.6, iterations=iterations, mode=mode, fixed=fixed)
    expected = core.smooth(positions, edges, **options).positions
    result = core.smooth(positions * scale, edges, **options).positions / scale
    # Linear in the points: the same arithmetic on scaled numbers, so equal to a few roundings per
    # iteration, each a few ulps of the coordinates (of the diagonal's size: the points are centred).
    size = max(np.linalg.norm(np.ptp(positions, axis=0)) if len(positions) else 0.0, np.abs(positions).max(initial=0.0))
    np.testing.assert_allclose(result, expected, rtol=0, atol=1e-14 * (iterations + 1) * size)


@given(
    random_meshes(),
    st.sampled_from(core.METHODS),
    st.sampled_from(core.MODES),
    st.sampled_from([2.0**-20, 2.0**30]),
    st.sampled_from([0.0, 1e-3]),
)
def test_mesh_smoothing_by_a_power_of_two_scale_is_bit_exact(mesh, method, mode, scale, tolerance):
    positions, edges, fixed = mesh
    options = dict(method=method, alpha=0.2, beta=0.6, iterations=5, mode=mode, fixed=fixed, tolerance=tolerance)
    expected = core.smooth(positions, edges, **options)
    result = core.smooth(positions * positions.dtype.type(scale), edges, **options)
    # Every product and sum scales exactly by a power of two (no overflow or underflow at these sizes).
    assert np.array_equal(result.positions, expected.positions * positions.dtype.type(scale))
    assert result.iterations == expected.iterations


def test_other_entry_points_leave_their_input_alone():
    # Read-only Fortran-ordered inputs: any write into them raises.
    def frozen(array):
        return in_layout(array, "read_only_fortran")

    points = frozen(noisy_sphere(300, 0.01, seed=9))
    assert len(emst(points)) == len(points) - 1
    index = NeighbourIndex(points, 12)
    tree, _ = boruvka_emst(index)
    graph = surface_description_graph(index, frozen(tree))
    mesh = rfs_mesh(frozen(index.points), frozen(graph.edges))
    faces, _, swaps = swap_pass(frozen(index.points), frozen(mesh.faces))
    assert swaps > 0 and not np.array_equal(faces, mesh.faces)
    positions, face_list = sm.uv_sphere()
    edges = frozen(sm.edges_of(face_list))
    assert core.umbrella_operator(edges, len(positions)).n_edges == len(edges)
    change = core.measure_change(frozen(positions), frozen(positions * 1.1), frozen(np.array(face_list)))
    assert change.moved == len(positions) and change.volume_change > 0.3
