"""Directed adjacency (j in adj(i) without i in adj(j)): the pattern, and every smoother in both modes
against the per-vertex loop of the paper given that adjacency, to rounding."""

import numpy as np
import pytest
import scipy.sparse as sp
import small_meshes as sm
from hypothesis import given, settings
from hypothesis import strategies as st
from paper_reference import smooth_loop

import core
from core import locality
from core.geometry import fan_triangles
from core.mesh.borders import apply_border


def dense_pattern(operator):
    n = operator.n_vertices
    return sp.csr_matrix((np.ones(operator.indices.size), operator.indices, operator.indptr), shape=(n, n)).toarray()


def adjacency_sets(operator):
    return [
        set(operator.indices[operator.indptr[i] : operator.indptr[i + 1]].tolist()) for i in range(operator.n_vertices)
    ]


@given(st.integers(1, 20), st.integers(0, 60), st.integers(0, 30), st.integers(0, 2**32 - 1))
def test_with_rows_replaces_exactly_the_listed_rows(n, m, k, seed):
    rng = np.random.default_rng(seed)
    edges = rng.integers(0, n, size=(m, 2))
    new_edges = rng.integers(0, n, size=(k, 2))
    listed = rng.random(n) < 0.4
    base = core.umbrella_operator(edges, n)
    operator = base.with_rows(listed, new_edges)
    expected = dense_pattern(base)
    expected[listed] = 0.0
    for a, b in new_edges:
        if a != b:
            if listed[a]:
                expected[a, b] = 1.0
            if listed[b]:
                expected[b, a] = 1.0
    got = dense_pattern(operator)
    np.testing.assert_array_equal(got, expected)
    assert sp.csr_matrix(
        (np.ones(operator.indices.size), operator.indices, operator.indptr), (n, n)
    ).has_canonical_format
    np.testing.assert_array_equal(operator.degree, expected.sum(axis=1))
    assert operator.symmetric == bool(np.array_equal(expected, expected.T))
    assert operator.n_edges == int(np.triu(np.maximum(expected, expected.T)).sum())
    # The triangles the sequential smoothers read: rows above the diagonal, columns below it.
    upper = sp.csr_matrix((np.ones(operator.upper_indices.size), operator.upper_indices, operator.upper_indptr), (n, n))
    np.testing.assert_array_equal(upper.toarray(), np.triu(expected, 1))
    indptr, indices = operator.lower_columns
    lower = sp.csc_matrix((np.ones(indices.size), indices, indptr), shape=(n, n))
    assert lower.has_canonical_format
    np.testing.assert_array_equal(lower.toarray(), np.tril(expected, -1))


def test_pairs_in_both_directions_give_the_umbrella_operator():
    edges = np.random.default_rng(2).integers(0, 200, size=(900, 2))
    operator = core.umbrella_operator(edges, 210)
    pairs = core.umbrella_from_pairs(np.r_[edges[:, 0], edges[:, 1]], np.r_[edges[:, 1], edges[:, 0]], 210)
    assert pairs.symmetric
    for name in ("indptr", "indices", "degree", "upper_indptr", "upper_indices"):
        a, b = getattr(operator, name), getattr(pairs, name)
        assert a.dtype == b.dtype
        np.testing.assert_array_equal(a, b, err_msg=name)
    one_way = core.umbrella_from_pairs(edges[:, 0], edges[:, 1], 210)
    assert not one_way.symmetric
    assert one_way.n_edges == operator.n_edges


def test_renumbered_keeps_a_directed_pattern():
    operator = curve_operator(*sm.grid(6, 5))[0]
    order = np.random.default_rng(0).permutation(operator.n_vertices)
    renumbered = operator.renumbered(order)
    assert not renumbered.symmetric
    np.testing.assert_array_equal(dense_pattern(renumbered), dense_pattern(operator)[np.ix_(order, order)])


def curve_operator(positions, faces):
    """The umbrella of core.mesh.borders' "curve" rule (directed) and the corners it fixes."""
    n = len(positions)
    operator = core.umbrella_operator(sm.edges_of(faces), n)
    return apply_border("curve", operator, fan_triangles(faces), np.zeros(n, dtype=bool))


def _random_directed(positions, faces, seed):
    """Every edge of the mesh, but some vertices drop a random half of their neighbours."""
    n = len(positions)
    edges = sm.edges_of(faces)
    rng = np.random.default_rng(seed)
    keep = rng.random(len(edges)) < 0.5
    return core.umbrella_operator(edges, n).with_rows(rng.random(n) < 0.3, edges[keep]), np.zeros(n, dtype=bool)


def _directed_cases():
    grid, sphere, quads = sm.grid(7, 5), sm.uv_sphere(5, 7), sm.cube_quads()
    two_parts = sm.combined(sm.grid(4, 4), sm.pentagonal_prism())
    yield "open grid, border curves", grid, curve_operator(*grid)
    yield "open grid + closed prism, border curves", two_parts, curve_operator(*two_parts)
    yield "sphere, random rows", sphere, _random_directed(*sphere, seed=1)
    yield "quads, random rows", quads, _random_directed(*quads, seed=2)


CASES = list(_directed_cases())
METHODS = [("hc", 0.1, 0.6), ("hc", 0.3, 0.8), ("plain", 0.0, 0.5), ("central", 0.3, 0.5), ("original", 0.2, 0.5)]


@pytest.mark.parametrize("name,mesh,prepared", CASES, ids=[c[0] for c in CASES])
@pytest.mark.parametrize("method,alpha,beta", METHODS, ids=[f"{m}-a{a}-b{b}" for m, a, b in METHODS])
@pytest.mark.parametrize("mode", core.MODES)
@pytest.mark.parametrize("fixed_kind", ["rule", "more"])
def test_directed_adjacency_matches_the_paper_loop(name, mesh, prepared, method, alpha, beta, mode, fixed_kind):
    positions = sm.noisy(mesh[0], seed=len(name))
    operator, fixed = prepared
    assert not operator.symmetric  # the case really is directed
    fixed = fixed.copy()
    if fixed_kind == "more":
        fixed[[1, len(positions) // 2]] = True
    expected = np.array(
        smooth_loop(
            positions,
            None,
            method=method,
            alpha=alpha,
            beta=beta,
            iterations=4,
            mode=mode,
            fixed=np.flatnonzero(fixed),
            adj=adjacency_sets(operator),
        )
    )
    with np.errstate(all="raise"):
        result = core.smooth(
            positions,
            None,
            operator=operator,
            method=method,
            alpha=alpha,
            beta=beta,
            iterations=4,
            mode=mode,
            fixed=fixed,
        )
    diagonal = np.linalg.norm(np.ptp(positions, axis=0))
    np.testing.assert_allclose(result.positions, expected, rtol=0, atol=1e-12 * diagonal)
    assert np.abs(expected - positions).max() > 1e-3  # the reference moved: the comparison is not vacuous
    # The directed rows matter: the symmetric adjacency of the same mesh gives another result.
    symmetric = core.smooth(
        positions, sm.edges_of(mesh[1]), method=method, alpha=alpha, beta=beta, iterations=4, mode=mode, fixed=fixed
    ).positions
    assert np.abs(symmetric - expected).max() > 1e-6


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(core.MODES))
def test_random_directed_graphs_match_the_paper_loop(seed, mode):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 14))
    pairs = rng.integers(0, n, size=(int(rng.integers(0, 3 * n)), 2))
    operator = core.umbrella_from_pairs(pairs[:, 0], pairs[:, 1], n)
    positions = rng.normal(size=(n, 3))
    expected = np.array(
        smooth_loop(
            positions, None, method="hc", alpha=0.2, beta=0.7, iterations=3, mode=mode, adj=adjacency_sets(operator)
        )
    )
    result = core.hc_smooth(positions, None, operator=operator, alpha=0.2, beta=0.7, iterations=3, mode=mode)
    np.testing.assert_allclose(result, expected, rtol=0, atol=1e-12 * max(1.0, np.abs(positions).max()))


@pytest.mark.parametrize("method", ["hc", "plain"])
def test_renumbered_directed_run_equals_the_plain_one(monkeypatch, method):
    # Scattered numbering: the simultaneous smoothers renumber (reverse Cuthill-McKee of the pattern
    # and its transpose) and hand back the caller's order.
    positions, faces = sm.grid(25, 25)
    order = np.random.default_rng(5).permutation(len(positions))
    inverse = np.empty_like(order)
    inverse[order] = np.arange(len(order))
    positions = sm.noisy(positions[order], sigma=0.1, seed=6)
    faces = inverse[np.array(faces)]
    operator, fixed = curve_operator(positions, faces)
    kwargs = dict(method=method, alpha=0.1, beta=0.6, iterations=5, fixed=fixed)
    expected = core.smooth(positions, None, operator=operator, **kwargs).positions
    assert not operator._renumbering  # below MIN_VERTICES: the caller's order
    monkeypatch.setattr(locality, "MIN_VERTICES", 0)
    monkeypatch.setattr(locality, "SCATTERED_GAP", 10)
    operator, fixed = curve_operator(positions, faces)
    got = core.smooth(positions, None, operator=operator, **kwargs).positions
    renumbered = operator._renumbering
    assert renumbered and not renumbered.operator.symmetric
    assert np.array_equal(np.sort(renumbered.order), np.arange(len(positions)))
    assert locality.median_gap(renumbered.operator) < locality.median_gap(operator) / 4
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)
