"""SDG guarantees, RFS-mesh invariants and edge-swap invariants."""

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import dihedral, dihedral_cos, face_quality, unique_faces
from pointcloud_sets import noisy_sphere
from pointcloud_stages import swap_pass
from scipy.sparse.csgraph import connected_components

from core.pointcloud.geometry import Incidence
from core.pointcloud.rfs import keep_best_pairs, rfs_mesh
from core.pointcloud.sdg import surface_description_graph
from core.pointcloud.spanning_tree import NeighbourIndex, boruvka_emst
from core.pointcloud.swap import EdgeSwapper


def build_sdg(points, k=16, **options):
    # Factor 2 gives the paper's proportions (RFS faces ~2n); 3 (surface_description_graph's default)
    # and smooth_point_cloud's 2.5 give wider neighbourhoods.
    options.setdefault("spacing_factor", 2.0)
    index = NeighbourIndex(points, k)
    tree, _ = boruvka_emst(index)
    return index, tree, surface_description_graph(index, tree, **options)


def n_components(edges, n):
    graph = sp.coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    return connected_components(graph, directed=False)


def plane(n, seed=0, scale=1.0):
    rng = np.random.default_rng(seed)
    p = rng.random((n, 3)) * scale
    p[:, 2] = 0.002 * rng.normal(size=n)
    return p


def edge_lengths(points, edges):
    return np.linalg.norm(points[edges[:, 0]] - points[edges[:, 1]], axis=1)


# --- SDG -------------------------------------------------------------------------------------------


def test_sdg_connected_on_a_noisy_sphere_and_no_edge_spans_a_gap():
    index, tree, graph = build_sdg(noisy_sphere(3000, 0.005))
    assert n_components(graph.edges, index.n_points)[0] == 1
    u, v = graph.edges.T
    assert np.all(
        edge_lengths(index.points, graph.edges) <= 3.0 * np.maximum(graph.spacing[u], graph.spacing[v]) + 1e-12
    )
    degree = np.bincount(graph.edges.ravel(), minlength=index.n_points)
    assert 5 <= np.median(degree) <= 12  # a surface-like neighbourhood, not a 1-D chain or a blob
    wide = build_sdg(index.points, spacing_factor=3.0)[2]
    assert np.median(np.bincount(wide.edges.ravel())) <= 2.5 * np.median(degree)


def test_sdg_separates_clusters_but_keeps_each_connected():
    a = plane(800, seed=1)
    b = plane(800, seed=2) + [5.0, 0.0, 0.0]  # gap 4: ~100x the spacing
    points = np.concatenate([a, b])
    index, tree, graph = build_sdg(points)
    count, label = n_components(graph.edges, index.n_points)
    assert count == 2
    side = index.points[:, 0] > 2.5
    assert len(np.unique(label[side])) == 1 and len(np.unique(label[~side])) == 1
    assert graph.emst_cut == 1


def test_sdg_joins_scan_lines_a_few_spacings_apart():
    # Rows 3 along-row spacings apart: a surface scanned in lines must stay one piece.
    x = np.arange(100) * 0.01
    rows = np.concatenate([np.stack([x, np.full(100, y), np.zeros(100)], 1) for y in np.arange(20) * 0.03])
    rows += np.random.default_rng(0).normal(scale=1e-4, size=rows.shape)
    index, tree, graph = build_sdg(rows)
    assert n_components(graph.edges, index.n_points)[0] == 1
    u, v = graph.edges.T
    crossing = np.abs(index.points[u, 1] - index.points[v, 1]) > 0.015
    assert crossing.sum() > 1000  # not just the EMST's single bridges: rows are really linked


def test_sdg_adapts_to_density():
    # Left half 9x denser than the right: both get surface-like neighbourhoods and stay connected.
    rng = np.random.default_rng(5)
    dense = rng.random((4500, 3)) * [1, 1, 0]
    sparse = rng.random((500, 3)) * [1, 1, 0] + [1, 0, 0]
    points = np.concatenate([dense, sparse]) + rng.normal(scale=1e-4, size=(5000, 3))
    index, tree, graph = build_sdg(points)
    assert n_components(graph.edges, index.n_points)[0] == 1
    degree = np.bincount(graph.edges.ravel(), minlength=index.n_points)
    left = index.points[:, 0] < 0.9
    right = index.points[:, 0] > 1.1
    assert 0.6 < np.median(degree[left]) / np.median(degree[right]) < 1.6
    length = edge_lengths(index.points, graph.edges)
    on_left = left[graph.edges].all(axis=1)
    assert np.median(length[on_left]) < 0.5 * np.median(length[right[graph.edges].all(axis=1)])


@pytest.mark.parametrize(
    "points",
    [noisy_sphere(1000, 0.01, seed=3), np.concatenate([plane(400, seed=1), plane(400, seed=2) + [5.0, 0.0, 0.0]])],
)
def test_sdg_keeps_exactly_the_consistent_emst_edges(points):
    # An EMST edge is in the SDG iff it is consistent (no adaptive edge brings back a cut one: that
    # would need |pq| <= spacing_factor x min(h) <= gap_factor x max(h)), and the counts the graph
    # reports are those of its edges.
    index, tree, graph = build_sdg(points)
    n = index.n_points
    have = set(map(tuple, np.sort(graph.edges, axis=1)))
    u, v = tree.T
    consistent = edge_lengths(index.points, tree) <= 3.0 * np.maximum(graph.spacing[u], graph.spacing[v])
    present = np.array([tuple(e) in have for e in np.sort(tree, axis=1)])
    np.testing.assert_array_equal(present, consistent)
    assert graph.emst_kept == present.sum() and graph.emst_cut == (~present).sum()
    assert len(tree) == n - 1


def test_sdg_rejects_inconsistent_factors():
    index = NeighbourIndex(plane(50), 8)
    with pytest.raises(ValueError, match="spacing_factor"):
        surface_description_graph(index, boruvka_emst(index)[0], spacing_factor=4.0, gap_factor=3.0)


# --- RFS mesh --------------------------------------------------------------------------------------


def assert_mesh_invariants(points, faces, edges=None, min_quality=None):
    n = len(points)
    assert faces.ndim == 2 and faces.shape[1] == 3
    assert np.all((faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2]))
    assert len(np.unique(np.sort(faces, axis=1), axis=0)) == len(faces)  # no duplicate faces
    inc = Incidence(faces, n)
    assert inc.edge_count.max(initial=0) <= 2  # at most two faces per edge
    if edges is not None:  # exactly the edges of the faces: none without a face
        assert np.array_equal(np.unique(np.sort(edges, axis=1), axis=0), inc.edges)
    if min_quality is not None:
        assert face_quality(points, faces).min(initial=1.0) >= min_quality


@pytest.mark.parametrize("sigma", [0.002, 0.01])
def test_rfs_invariants_on_a_noisy_sphere(sigma):
    index, tree, graph = build_sdg(noisy_sphere(3000, sigma, seed=1))
    mesh = rfs_mesh(index.points, graph.edges, min_quality=0.3)
    assert_mesh_invariants(index.points, mesh.faces, mesh.edges, min_quality=0.3)
    n = index.n_points
    # Paper: about as many faces as a valid mesh (2n on a sphere), edges ~50 % more than 3n. We
    # get ~1.6n faces and ~3n edges at low noise (deleting faces leaves holes), ~2n and ~4n at more.
    assert 1.4 * n < len(mesh.faces) < 2.6 * n
    assert 2.7 * n < len(mesh.edges) < 5.0 * n
    used = np.zeros(n, bool)
    used[mesh.faces.ravel()] = True
    assert used.mean() > 0.98


def test_rfs_quality_threshold_is_applied():
    index, tree, graph = build_sdg(noisy_sphere(1500, 0.01, seed=2))
    loose = rfs_mesh(index.points, graph.edges, min_quality=0.0)
    strict = rfs_mesh(index.points, graph.edges, min_quality=0.7)
    assert_mesh_invariants(index.points, strict.faces, strict.edges, min_quality=0.7)
    assert face_quality(index.points, loose.faces).min() < 0.7
    assert len(strict.faces) < len(loose.faces)


def test_keep_best_pairs_keeps_the_flattest_pair():
    # Edge (0, 1) on the x axis with four faces: two nearly flat on opposite sides, two folded up.
    points = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0.05], [0.5, -1, 0.05], [0.5, 0.3, 1], [0.5, -0.3, 1.0]])
    faces = np.array([[0, 1, 4], [0, 1, 2], [0, 1, 5], [0, 1, 3]])
    keep = keep_best_pairs(points, faces)
    assert keep.tolist() == [False, True, False, True]


def test_quality_of_equilateral_is_one_and_degenerate_zero():
    points = np.array([[0, 0, 0], [1, 0, 0], [0.5, np.sqrt(3) / 2, 0], [2, 0, 0]])
    q = face_quality(points, np.array([[0, 1, 2], [0, 1, 3]]))
    assert q[0] == pytest.approx(1.0) and q[1] == 0.0


# --- edge swapping ---------------------------------------------------------------------------------


def interior_dihedral_sum(points, faces):
    inc = Incidence(faces, len(points))
    two = np.flatnonzero(inc.edge_count == 2)
    i1, i2 = inc.order[inc.edge_start[two]], inc.order[inc.edge_start[two] + 1]
    third = faces.ravel()  # the vertex opposite each incidence
    return np.nansum(dihedral(points, inc.edges[two, 0], inc.edges[two, 1], third[i1], third[i2]))


def test_swap_takes_the_flatter_diagonal():
    a, b, c, d = [-2, 0, 0], [2, 0, 0], [0, 1, 1], [0, -1, 1]
    points = np.array([a, b, c, d], dtype=float)
    faces = np.array([[0, 1, 2], [1, 0, 3]])  # diagonal ab: dihedral 90 deg; cd would give ~127 deg
    new, _, count = swap_pass(points, faces)
    assert count == 1
    assert sorted(map(sorted, new.tolist())) == [[0, 2, 3], [1, 2, 3]]
    again, _, count = swap_pass(points, new)
    assert count == 0  # and not back


def test_swap_never_creates_an_existing_edge():
    # Same quad, but cd already exists (in a third face): swapping would give cd three faces.
    points = np.array([[-2, 0, 0], [2, 0, 0], [0, 1, 1], [0, -1, 1], [0, 0, 3]], dtype=float)
    faces = np.array([[0, 1, 2], [1, 0, 3], [2, 3, 4]])
    new, _, count = swap_pass(points, faces)
    assert count == 0 and np.array_equal(new, faces)


@pytest.mark.parametrize("seed", [0, 1])
def test_swap_invariants_and_monotone_dihedral_sum(seed):
    index, tree, graph = build_sdg(noisy_sphere(2000, 0.01, seed=seed))
    faces = rfs_mesh(index.points, graph.edges).faces
    total = interior_dihedral_sum(index.points, faces)
    counts = []
    for _ in range(4):
        before, snapshot = faces, faces.copy()
        faces, edges, count = swap_pass(index.points, before)
        assert np.array_equal(before, snapshot)  # input untouched
        counts.append(count)
        assert len(faces) == len(before)
        assert_mesh_invariants(index.points, faces, edges)
        now = interior_dihedral_sum(index.points, faces)
        assert now >= total - 1e-9  # swaps are independent, so each one's gain adds up
        total = now
    assert counts[0] > 0


@settings(max_examples=15, deadline=None)
@given(st.integers(30, 200), st.integers(0, 2**31 - 1), st.floats(0.0, 0.2))
def test_rfs_and_swap_invariants_on_random_clouds(n, seed, noise):
    rng = np.random.default_rng(seed)
    points = rng.random((n, 3))
    points[:, 2] *= noise
    index, tree, graph = build_sdg(points, k=8)
    mesh = rfs_mesh(index.points, graph.edges, min_quality=0.2)
    assert_mesh_invariants(index.points, mesh.faces, mesh.edges, min_quality=0.2)
    # rfs_mesh pairs the kept faces' incidences from its own grouping: what regrouping the faces gives.
    fresh = EdgeSwapper(mesh.faces, index.n_points)
    given_state = EdgeSwapper(mesh.faces, index.n_points, mesh.other, mesh.edges)
    assert np.array_equal(given_state.other, fresh.other) and np.array_equal(given_state.keys, fresh.keys)
    faces = mesh.faces
    for _ in range(3):
        faces, edges, _ = swap_pass(index.points, faces)
        assert_mesh_invariants(index.points, faces, edges)


def test_pair_priorities_order_flattest_first_in_both_encodings():
    from core.pointcloud.rfs import _priority

    rng = np.random.default_rng(0)
    cos = np.round(rng.uniform(-1, 1, 500), 2)  # many ties
    edge = rng.permutation(10_000)[:500]
    packed, ranked = _priority(cos, edge, 10_000), _priority(cos, edge, 1 << 30)
    assert len(set(packed)) == 500 and len(set(ranked)) == 500
    assert np.array_equal(np.argsort(packed), np.argsort(ranked))
    assert cos[np.argmax(packed)] == cos.min()  # the largest dihedral angle comes first


# --- geometry from face normals, the swapper's kept state, threads ---------------------------------


def test_incidence_cos_equals_the_dihedral_cos_whatever_the_face_orientation():
    from core.pointcloud.geometry import face_normals, incidence_cos

    rng = np.random.default_rng(3)
    points = rng.normal(size=(4 * 300, 3))
    quads = np.arange(4 * 300).reshape(-1, 4)  # per quad: edge (u, v), third vertices s and t
    u, v, s, t = quads.T
    # Faces in random vertex orders: the sign rule must not depend on it.
    first = np.array([rng.permutation(x) for x in np.stack([u, v, s], 1)])
    second = np.array([rng.permutation(x) for x in np.stack([u, v, t], 1)])
    faces = np.concatenate([first, second])
    x = 3 * np.arange(300) + np.argmax(first == s[:, None], axis=1)  # incidence opposite s
    y = 3 * (300 + np.arange(300)) + np.argmax(second == t[:, None], axis=1)
    cos = incidence_cos(face_normals(points, faces), faces, x, y)
    assert np.allclose(cos, dihedral_cos(points, u, v, s, t), atol=1e-12)


def test_swapper_state_stays_that_of_its_faces():
    # The swapper updates "which incidence lies across each edge" and the edge keys in place; after
    # passes at moving points they must equal what a fresh build from its faces gives.
    from core.pointcloud.swap import EdgeSwapper

    index, tree, graph = build_sdg(noisy_sphere(3000, 0.01, seed=4))
    swapper = EdgeSwapper(rfs_mesh(index.points, graph.edges).faces, index.n_points)
    rng = np.random.default_rng(0)
    total = 0
    for _ in range(4):
        total += swapper.swap_pass(index.points + rng.normal(scale=0.003, size=index.points.shape))
        fresh = EdgeSwapper(swapper.faces, index.n_points)
        assert np.array_equal(swapper.other, fresh.other)
        assert np.array_equal(swapper.keys, fresh.keys)
        assert_mesh_invariants(index.points, swapper.faces, swapper.edges)
    assert total > 0


def test_rfs_mesh_swapper_state_on_a_noisy_sphere():
    index, tree, graph = build_sdg(noisy_sphere(3000, 0.01, seed=4))
    mesh = rfs_mesh(index.points, graph.edges)
    fresh = EdgeSwapper(mesh.faces, index.n_points)
    assert (fresh.other >= 0).mean() > 0.5  # mostly interior edges: the comparison means something
    assert np.array_equal(EdgeSwapper(mesh.faces, index.n_points, mesh.other, mesh.edges).other, fresh.other)


@pytest.mark.slow
def test_results_do_not_depend_on_the_thread_count(monkeypatch):
    import core
    from core import parallel

    points = noisy_sphere(30_000, 0.01, seed=5)  # large enough to be split into blocks
    monkeypatch.setattr(parallel, "MIN_BLOCK", 1000)
    widest = []
    original_run_all = parallel.run_all

    def recording_run_all(tasks):
        widest.append(len(tasks))
        return original_run_all(tasks)

    monkeypatch.setattr(parallel, "run_all", recording_run_all)
    monkeypatch.setattr(parallel, "thread_count", lambda: 1)
    one = core.smooth_point_cloud(points, rounds=2)
    assert max(widest) == 1
    widest.clear()
    monkeypatch.setattr(parallel, "thread_count", lambda: 3)  # on any machine: the pool has the threads
    three = core.smooth_point_cloud(points, rounds=2)
    assert max(widest) == 3  # the stages really were split
    assert np.array_equal(one, three)


@pytest.mark.slow
def test_pruning_rounds_equal_the_edge_by_edge_rule_in_any_order_within_a_round():
    # Reference: the paper's rule one edge at a time, in the order of the rounds (shuffled within
    # each round), with the best pair found by brute force from dihedral_cos.
    from core.pointcloud.rfs import _prune, corona_faces

    index, tree, graph = build_sdg(noisy_sphere(1500, 0.01, seed=6), spacing_factor=3.0)
    points = index.points
    faces = unique_faces(corona_faces(points, graph.edges))
    faces = faces[face_quality(points, faces) >= 0.3]
    inc = Incidence(faces, len(points))
    settled = np.full(inc.edges.shape[0], -1)
    alive, _ = _prune(points, faces, settled=settled)
    assert settled.max() >= 2  # several rounds happened
    members = [inc.order[s : s + c] // 3 for s, c in zip(inc.edge_start, inc.edge_count)]
    rng = np.random.default_rng(0)
    reference = np.ones(len(faces), dtype=bool)
    for r in range(settled.max() + 1):
        for e in rng.permutation(np.flatnonzero(settled == r)):
            live = [f for f in members[e] if reference[f]]
            if len(live) <= 2:
                continue
            u, v = inc.edges[e]
            third = [int(np.setdiff1d(faces[f], [u, v])[0]) for f in live]
            pairs = [(i, j) for i in range(len(live)) for j in range(i + 1, len(live))]
            cos = [
                dihedral_cos(points, np.array([u]), np.array([v]), np.array([third[i]]), np.array([third[j]]))[0]
                for i, j in pairs
            ]
            i, j = pairs[int(np.argmin(np.nan_to_num(cos, nan=np.inf)))]
            for k, f in enumerate(live):
                if k not in (i, j):
                    reference[f] = False
    assert np.array_equal(alive, reference)
    assert Incidence(faces[alive], len(points)).edge_count.max() <= 2


def test_incidence_order_by_counting_equals_a_stable_sort(monkeypatch):
    # The incidences are grouped by edge with SciPy's counting kernels; the result must be exactly
    # the stable argsort of the edge keys (ties: incidence order), also on the public fallback.
    from core import adjacency
    from core.pointcloud import geometry

    faces = np.random.default_rng(2).integers(0, 40, size=(500, 3))
    faces = faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])]
    counted = geometry.Incidence(faces, 40)
    first = faces[:, [1, 2, 0]].ravel()
    second = faces[:, [2, 0, 1]].ravel()
    keys = np.minimum(first, second) * 40 + np.maximum(first, second)
    np.testing.assert_array_equal(counted.order, np.argsort(keys, kind="stable"))
    monkeypatch.setattr(adjacency, "_coo_tocsr", None)
    np.testing.assert_array_equal(geometry.Incidence(faces, 40).order, counted.order)


@pytest.mark.parametrize(
    "size, n, seed", [(0, 5, 0), (1, 1, 1), (1, 7, 2), (2, 1, 3), (50, 3, 4), (2000, 40, 5), (3000, 2000, 6)]
)
def test_group_by_edge_equals_a_stable_sort_of_the_keys(size, n, seed):
    # Many ties (n small), empty input, a single pair, vertices without pairs (n large).
    from core.pointcloud.geometry import group_by_edge

    rng = np.random.default_rng(seed)
    a, b = rng.integers(0, n, size=(2, size))
    low, high = np.minimum(a, b), np.maximum(a, b)
    keys = low.astype(np.int64) * n + high
    order, edge_start, edges, edge_of = group_by_edge(low, high, n)
    reference = np.argsort(keys, kind="stable")
    np.testing.assert_array_equal(order, reference)
    assert order.dtype == edge_of.dtype == np.int32  # the documented narrow types
    assert edges.dtype == np.int64 and edges.shape == (edge_start.size, 2)
    distinct, first_at, number = np.unique(keys[reference], return_index=True, return_inverse=True)
    np.testing.assert_array_equal(edge_start, first_at)
    np.testing.assert_array_equal(edges, np.stack([distinct // n, distinct % n], axis=1).reshape(-1, 2))
    expected_of = np.empty(size, dtype=np.int64)
    expected_of[reference] = number
    np.testing.assert_array_equal(edge_of, expected_of)


def test_incidence_fields_equal_the_key_sort_fallback(monkeypatch):
    from core import adjacency
    from core.pointcloud import geometry

    rng = np.random.default_rng(7)
    for n, count in ((30, 400), (500, 3000), (3, 1), (4, 0)):
        faces = np.array([rng.permutation(n)[:3] for _ in range(count)], dtype=np.int64).reshape(-1, 3)
        counted = geometry.Incidence(faces, n)
        with monkeypatch.context() as m:
            m.setattr(adjacency, "_coo_tocsr", None)
            fallback = geometry.Incidence(faces, n)
        for name in ("order", "edge_start", "edge_count", "edge_of", "keys", "edges"):
            a, b = getattr(counted, name), getattr(fallback, name)
            assert a.dtype == b.dtype, name
            np.testing.assert_array_equal(a, b, err_msg=name)


def _best_pairs_reference(normals, forward, edges, order, start, count):
    # The all-pairs arrays of each edge and np.argmin, NaN as inf.
    first, second, best = [], [], []
    for e in edges:
        incidence = order[start[e] : start[e] + count[e]]
        sign = np.where(forward[incidence], 1.0, -1.0)
        v = [normals[j][incidence // 3] * sign for j in range(3)]
        i, j = np.triu_indices(incidence.size, 1)
        cos = v[0][i] * v[0][j] + v[1][i] * v[1][j] + v[2][i] * v[2][j]
        cos[np.isnan(cos)] = np.inf
        pick = np.argmin(cos)
        first.append(incidence[i[pick]]), second.append(incidence[j[pick]]), best.append(cos[pick])
    return np.array(first, dtype=np.int64), np.array(second, dtype=np.int64), np.array(best)


@pytest.mark.parametrize("block", [1 << 16, 5, 1])  # edges handled in blocks of about block / width
def test_best_pairs_equal_argmin_over_all_pairs_with_ties_and_nan(monkeypatch, block):
    from core.pointcloud import rfs
    from core.pointcloud.rfs import _best_pairs

    monkeypatch.setattr(rfs, "_PAIR_BLOCK", block)
    rng = np.random.default_rng(8)
    n_faces = 60
    # Few distinct normals: many equal cos (ties); some NaN faces; one edge with only NaN faces.
    choices = rng.normal(size=(3, 4))
    choices /= np.linalg.norm(choices, axis=0)
    normals = choices[:, rng.integers(0, 4, n_faces)]
    normals[:, rng.integers(0, n_faces, 8)] = np.nan
    normals[:, [0, 1, 2]] = np.nan
    forward = rng.random(3 * n_faces) < 0.5
    widths = np.array([3, 3, 4, 6, 3, 5, 9, 4])
    order = np.concatenate([[0, 3, 6]] + [rng.choice(np.arange(9, 3 * n_faces), w, replace=False) for w in widths[1:]])
    start = np.concatenate(([0], np.cumsum(widths)[:-1]))
    edges = np.array([6, 0, 2, 5, 1, 7, 4, 0])
    got = _best_pairs(normals.T, forward, edges, order, start, widths)
    want = _best_pairs_reference(normals, forward, edges, order, start, widths)
    for a, b in zip(got, want):
        np.testing.assert_array_equal(a, b)
    assert np.isinf(got[2][1])  # the all-NaN edge: first pair, cos inf
    empty = _best_pairs(normals.T, forward, np.zeros(0, dtype=np.int64), order, start, widths)
    assert all(x.size == 0 for x in empty)


@pytest.mark.parametrize("n, count, seed", [(6, 300, 0), (1000, 5000, 1), (4, 0, 2), (3, 1, 3), (2**21, 400, 4)])
def test_face_keys_give_the_unique_sorted_rows(n, count, seed):
    # Every vertex order and repeated vertices; n = 2^21 takes the np.unique fallback (n^3 > 2^62).
    from core.pointcloud.geometry import faces_of_keys, triple_keys

    rng = np.random.default_rng(seed)
    faces = rng.integers(0, n, size=(count, 3))
    faces = np.concatenate([faces, faces[:, ::-1], faces[:, [1, 2, 0]]])
    expected = unique_faces(faces)
    for columns in (faces.T, faces.astype(np.int32).T):
        got = faces_of_keys(triple_keys(*columns, n), n)
        assert got.dtype == np.int64
        np.testing.assert_array_equal(got, expected)


def test_pruning_is_the_same_with_int64_incidence_numbers(monkeypatch):
    # The rounds handle incidence and edge numbers as int32 when they fit; int64 gives the same.
    from core.pointcloud import rfs

    index, tree, graph = build_sdg(noisy_sphere(3000, 0.01, seed=9), spacing_factor=3.0)
    narrow = rfs.rfs_mesh(index.points, graph.edges)
    monkeypatch.setattr(rfs, "_INT32_LIMIT", 0)
    wide = rfs.rfs_mesh(index.points, graph.edges)
    np.testing.assert_array_equal(narrow.faces, wide.faces)
    np.testing.assert_array_equal(narrow.edges, wide.edges)


def test_corona_keys_give_the_unique_faces_of_the_candidates(monkeypatch):
    from core import parallel
    from core.pointcloud.geometry import faces_of_keys
    from core.pointcloud.rfs import corona_faces

    index, tree, graph = build_sdg(noisy_sphere(4000, 0.01, seed=10))
    monkeypatch.setattr(parallel, "MIN_BLOCK", 100)  # several blocks when threads are on
    for gap in (np.pi, 2.0):
        expected = unique_faces(corona_faces(index.points, graph.edges, gap))
        parts = corona_faces(index.points, graph.edges, gap, keys=True)
        np.testing.assert_array_equal(faces_of_keys(parts, index.n_points), expected)
