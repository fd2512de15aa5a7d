"""Properties on random graphs: fixed vertices bit-identical, no NaN, input untouched, dtype kept."""

import warnings

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import core


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


@given(random_meshes(), st.sampled_from(core.METHODS), st.sampled_from(core.MODES),
       st.floats(0, 1), st.floats(0, 1), st.integers(0, 6))
def test_invariants(mesh, method, mode, alpha, beta, iterations):
    positions, edges, fixed = mesh
    before = positions.copy()
    edges_before = edges.copy()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", core.ConvergenceWarning)
        result = core.smooth(positions, edges, method=method, alpha=alpha, beta=beta, iterations=iterations,
                             mode=mode, fixed=fixed)
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


@given(random_meshes(), st.sampled_from(core.MODES))
def test_fixed_as_indices_equals_fixed_as_mask(mesh, mode):
    positions, edges, fixed = mesh
    a = core.hc_smooth(positions, edges, alpha=0.1, beta=0.6, iterations=3, mode=mode, fixed=fixed)
    b = core.hc_smooth(positions, edges, alpha=0.1, beta=0.6, iterations=3, mode=mode, fixed=np.flatnonzero(fixed))
    assert np.array_equal(a, b)


@given(random_meshes())
def test_edge_order_direction_and_duplicates_do_not_matter(mesh):
    positions, edges, _ = mesh
    rng = np.random.default_rng(len(edges))
    shuffled = np.concatenate([edges, edges[:, ::-1]])[rng.permutation(2 * len(edges))] if len(edges) else edges
    a = core.hc_smooth(positions, edges, alpha=0.1, beta=0.6, iterations=2)
    b = core.hc_smooth(positions, shuffled, alpha=0.1, beta=0.6, iterations=2)
    np.testing.assert_allclose(a, b, rtol=1e-6 if positions.dtype == np.float32 else 1e-12,
                               atol=1e-30)
