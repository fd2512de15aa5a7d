"""The EMST is exact: its length equals that of the MST of all Delaunay edges, also where a plain
kNN-graph MST is wrong (scan lines, separated clusters, duplicates, ties)."""

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from pointcloud_sets import clusters, delaunay_mst_length, grid_ties, scan_lines, sphere_rings, uniform, with_duplicates
from pointcloud_stages import emst
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from core.pointcloud.spanning_tree import NeighbourIndex, _exact_nearest_foreign, merge_duplicates


def assert_is_emst(points, edges):
    n = len(points)
    assert edges.shape == (n - 1, 2)
    assert edges.min() >= 0 and edges.max() < n
    graph = sp.coo_matrix((np.ones(n - 1), (edges[:, 0], edges[:, 1])), shape=(n, n))
    assert connected_components(graph, directed=False)[0] == 1  # n - 1 edges + connected = tree
    length = np.linalg.norm(points[edges[:, 0]] - points[edges[:, 1]], axis=1).sum()
    assert length == pytest.approx(delaunay_mst_length(points), rel=1e-12, abs=1e-12)


HARD_SETS = {
    "uniform": uniform(1500),
    "scan_lines": scan_lines(),
    "sphere_rings": sphere_rings(),
    "clusters": clusters(),
    "duplicates": with_duplicates(),
    "grid_ties": grid_ties(),
}


# make test-quick keeps k = 3 alone: a small kNN cache, so the exact searches run.
@pytest.mark.parametrize("name", sorted(HARD_SETS))
@pytest.mark.parametrize("k", [pytest.param(1, marks=pytest.mark.slow), 3, pytest.param(12, marks=pytest.mark.slow)])
def test_emst_matches_delaunay_mst(name, k):
    points = HARD_SETS[name]
    assert_is_emst(points, emst(points, neighbours=k))


def test_knn_mst_alone_would_fail_on_these_sets():
    # The sets are hard for real: a k=3 neighbour graph of the scan lines and clusters is disconnected.
    for name in ("scan_lines", "clusters"):
        index = NeighbourIndex(HARD_SETS[name], 3)
        src = np.repeat(np.arange(index.n_points), 3)
        graph = sp.coo_matrix((np.ones(src.size), (src, index.neighbour.ravel())), shape=(index.n_points,) * 2)
        assert connected_components(graph, directed=False)[0] > 1


def test_float32_and_tiny_inputs():
    points = uniform(300).astype(np.float32)
    assert_is_emst(points.astype(np.float64), emst(points))
    assert emst(np.zeros((0, 3))).shape == (0, 2)
    assert emst(np.zeros((1, 3))).shape == (0, 2)
    assert emst(np.zeros((5, 3))).shape == (4, 2)  # all duplicates: zero-length star
    two = np.array([[0.0, 0, 0], [1, 0, 0]])
    assert emst(two).tolist() in ([[0, 1]], [[1, 0]])


def test_duplicates_are_tied_to_their_first_copy():
    points = with_duplicates(50)
    first, representative = merge_duplicates(points)
    assert np.array_equal(points[first[representative]], points)
    assert len(np.unique(points, axis=0)) == len(first)


def brute_force_minimum_per_code(points, code, ask, bound):
    from scipy.spatial.distance import cdist

    distance = cdist(points[ask], points)
    distance[code[ask][:, None] == code[None, :]] = np.inf
    nearest = distance.min(axis=1)
    nearest[nearest >= bound] = np.inf
    result = np.full(code.max() + 1, np.inf)
    np.minimum.at(result, code[ask], nearest)
    return result


@pytest.mark.parametrize("n_ask", [20, 300])  # few askers: growing k; many: sampled bit search
@pytest.mark.parametrize("use_tree", [False, True])
def test_nearest_foreign_search_gives_each_codes_exact_minimum(n_ask, use_tree):
    # The contract the EMST relies on: per code, the minimum reported equals the true nearest
    # point of another code below the bound (single askers may report nothing).
    rng = np.random.default_rng(3)
    index = NeighbourIndex(clusters(4, 100, seed=3), 4)
    code = rng.integers(0, 5, index.n_points)
    code[:50] = 7  # one big code, as a long scan line would be
    ask = np.sort(rng.choice(index.n_points, n_ask, replace=False))
    bound = np.full(ask.size, np.inf)
    bound[::3] = 0.005
    kwargs = dict(tree=index.tree, k=2) if use_tree else {}
    distance, found = _exact_nearest_foreign(index.points, code, ask, bound, **kwargs)
    hit = found >= 0
    assert np.all(code[found[hit]] != code[ask[hit]])
    assert np.allclose(np.linalg.norm(index.points[found[hit]] - index.points[ask[hit]], axis=1), distance[hit])
    reported = np.full(code.max() + 1, np.inf)
    np.minimum.at(reported, code[ask], distance)
    assert np.allclose(reported, brute_force_minimum_per_code(index.points, code, ask, bound), rtol=1e-12, atol=0)


@settings(max_examples=25, deadline=None)
@given(st.integers(2, 60), st.integers(1, 6), st.integers(0, 2**31 - 1), st.booleans())
def test_emst_exact_on_random_sets(n, k, seed, quantize):
    rng = np.random.default_rng(seed)
    points = rng.random((n, 3))
    if quantize:  # ties and duplicates
        points = np.round(points * 3) / 3
    distinct = np.unique(points, axis=0)
    if len(distinct) < 5 or np.linalg.matrix_rank(distinct[1:] - distinct[0]) < 3:
        points = np.concatenate([points, rng.random((5, 3))])  # Delaunay needs a full-dimensional set
    assert_is_emst(points, emst(points, neighbours=k))


@pytest.mark.parametrize("finite", [False, True])
def test_bit_search_finds_the_nearest_point_of_another_code(finite):
    # Every bit's search is bounded by the best point the earlier bits found; the answers must still
    # be the exact nearest point of another code below each asker's bound (brute force here).
    from core.pointcloud.spanning_tree import _query_by_bits

    rng = np.random.default_rng(4)
    points = rng.random((600, 3))
    code = rng.integers(1, 23, size=600)
    ask = rng.choice(600, size=200, replace=False)
    bound = rng.random(200) * 0.3 if finite else np.full(200, np.inf)
    distance, index = _query_by_bits(points, code, ask, bound)
    gaps = np.linalg.norm(points[ask][:, None, :] - points[None, :, :], axis=2)
    gaps[code[ask][:, None] == code[None, :]] = np.inf
    nearest = gaps.min(axis=1)
    expected = np.where(nearest < bound, nearest, np.inf)
    np.testing.assert_allclose(distance, expected, rtol=1e-12)
    hit = np.isfinite(expected)
    np.testing.assert_allclose(gaps[np.flatnonzero(hit), index[hit]], expected[hit], rtol=1e-12)
    assert np.all(index[~hit] == -1)


def test_many_askers_per_code_minimum_is_exact(monkeypatch):
    # Many askers: a sample searches first, and the triangle inequality from the sample rules most
    # of the others out. Each code's best answer must still be its exact nearest other-code point,
    # and an asker reported empty must have no other-code point below the bound it returns.
    from core.pointcloud import spanning_tree
    from core.pointcloud.spanning_tree import _exact_nearest_foreign

    asked = []
    original = spanning_tree._query_by_bits
    monkeypatch.setattr(
        spanning_tree,
        "_query_by_bits",
        lambda points, code, ask, bound: asked.append(ask.size) or original(points, code, ask, bound),
    )
    rng = np.random.default_rng(7)
    n, clusters = 12_000, 24
    centres = rng.normal(size=(clusters, 3)) * 10  # clusters far apart relative to their size
    member = rng.integers(0, clusters, n)
    points = centres[member] + rng.normal(size=(n, 3)) * 0.1
    order = cKDTree(points).indices  # the pipeline's rows are in KD-tree order
    points, code = points[order], member[order] + 1
    ask = np.arange(n)
    distance, index, searched = _exact_nearest_foreign(points, code, ask, np.full(n, np.inf), return_bound=True)
    nearest = np.empty(n)  # reference: one tree over every other cluster
    for c in range(1, clusters + 1):
        mine = code == c
        nearest[mine] = cKDTree(points[~mine]).query(points[mine])[0]
        np.testing.assert_allclose(distance[mine].min(), nearest[mine].min(), rtol=1e-12)
    hit = index >= 0
    np.testing.assert_allclose(np.linalg.norm(points[hit] - points[index[hit]], axis=1), distance[hit], rtol=1e-12)
    assert np.all(code[index[hit]] != code[hit])
    assert np.all(nearest[~hit] >= searched[~hit] * (1 - 1e-12))
    assert asked[0] == -(-n // 16)  # the sample
    assert sum(asked[1:]) < n // 4  # most of the others were ruled out without a search
