"""The umbrella operator T equals its definition in paper section 5."""

import numpy as np
import scipy.sparse as sp
from hypothesis import given
from hypothesis import strategies as st
from oracles import umbrella_matrix

import core


@given(st.integers(1, 25), st.integers(0, 80), st.integers(0, 2**32 - 1))
def test_matches_dense_definition(n, m, seed):
    edges = np.random.default_rng(seed).integers(0, n, size=(m, 2))
    dense = np.zeros((n, n))
    for a, b in edges:
        if a != b:
            dense[a, b] = dense[b, a] = 1.0
    degree = dense.sum(axis=1)
    expected = np.divide(dense, degree[:, None], out=np.zeros_like(dense), where=degree[:, None] > 0)
    operator = core.umbrella_operator(edges, n)
    t = umbrella_matrix(operator)
    assert t.has_canonical_format  # every row's neighbours increasing, each once
    np.testing.assert_allclose(t.toarray(), expected, rtol=1e-15)
    np.testing.assert_array_equal(operator.degree, degree)
    upper = sp.csr_matrix(
        (np.ones(operator.upper_indices.size), operator.upper_indices, operator.upper_indptr), shape=(n, n)
    )
    assert upper.has_canonical_format
    np.testing.assert_array_equal(upper.toarray(), np.triu(dense, 1))  # each edge once, in row min(i, j)
    assert np.array_equal(operator.isolated, degree == 0)
    assert operator.n_edges == int(np.triu(dense).sum())


def test_many_duplicates_of_one_edge_count_once():
    # Duplicates are merged by summing a small counter; 256 copies must neither wrap it to zero nor
    # drop the edge, and the upper triangle must hold each edge once.
    edges = np.array([[0, 1]] * 256 + [[1, 2]] * 3 + [[2, 2]] * 5 + [[2, 0]])
    operator = core.umbrella_operator(edges, 4)
    np.testing.assert_array_equal(operator.degree, [2, 2, 2, 0])
    np.testing.assert_array_equal(operator.upper_indptr, [0, 2, 3, 3, 3])
    np.testing.assert_array_equal(operator.upper_indices, [1, 2, 2])
    assert operator.n_edges == 3


def test_public_construction_path_gives_the_same_pattern(monkeypatch):
    # The counting placement uses SciPy's private kernels; without them the public coo -> csr is used.
    from core import adjacency

    edges = np.random.default_rng(4).integers(0, 300, size=(2000, 2))  # duplicates and self-loops
    fast = core.umbrella_operator(edges, 310)
    monkeypatch.setattr(adjacency, "_coo_tocsr", None)
    public = core.umbrella_operator(edges, 310)
    for name in ("indptr", "indices", "degree", "upper_indptr", "upper_indices"):
        np.testing.assert_array_equal(getattr(fast, name), getattr(public, name))
    assert umbrella_matrix(fast).has_canonical_format


def test_a_changed_private_kernel_falls_back_to_the_public_path(monkeypatch):
    # If SciPy's private kernels refuse our call (a changed signature), the public path gives the
    # same pattern, here and for the point-cloud incidences that share pairs_in_order.
    from core import adjacency

    edges = np.random.default_rng(5).integers(0, 300, size=(2000, 2))
    fast = core.umbrella_operator(edges, 310)
    calls = []

    def changed(*args):
        calls.append(len(args))
        raise TypeError("coo_tocsr() takes different arguments now")

    monkeypatch.setattr(adjacency, "_coo_tocsr", changed)
    public = core.umbrella_operator(edges, 310)
    assert calls  # the private kernel was tried
    for name in ("indptr", "indices", "degree", "upper_indptr", "upper_indices"):
        a, b = getattr(fast, name), getattr(public, name)
        assert a.dtype == b.dtype, name
        np.testing.assert_array_equal(a, b, err_msg=name)
