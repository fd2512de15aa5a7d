"""The edge swapper's chunked, threaded pass and its edge lookup against plain whole-array forms."""

import numpy as np
import pytest
from pointcloud_sets import noisy_sphere

from core import parallel
from core.pointcloud import swap
from core.pointcloud.rfs import rfs_mesh
from core.pointcloud.sdg import surface_description_graph
from core.pointcloud.spanning_tree import NeighbourIndex, boruvka_emst


def sphere_mesh(n, seed):
    index = NeighbourIndex(noisy_sphere(n, 0.01, seed=seed), 16)
    tree, _ = boruvka_emst(index)
    graph = surface_description_graph(index, tree, spacing_factor=2.0)
    return index, rfs_mesh(index.points, graph.edges)


def passes(index, mesh, count=3):
    swapper = swap.EdgeSwapper(mesh.faces, index.n_points, mesh.other, mesh.edges)
    rng = np.random.default_rng(1)
    states = []
    for _ in range(count):
        swaps = swapper.swap_pass(index.points + rng.normal(scale=0.003, size=index.points.shape))
        states.append((swaps, swapper.faces.copy(), swapper.other.copy(), swapper.keys.copy()))
    return states


@pytest.mark.slow
def test_chunks_and_threads_give_the_one_block_result(monkeypatch):
    index, mesh = sphere_mesh(3000, seed=2)
    whole = passes(index, mesh)
    assert whole[0][0] > 0
    monkeypatch.setattr(swap, "_CHUNK", 7)  # chunk edges everywhere, and odd
    monkeypatch.setattr(parallel, "MIN_BLOCK", 100)
    monkeypatch.setattr(parallel, "thread_count", lambda: 3)
    for (count, *state), (count_whole, *state_whole) in zip(passes(index, mesh), whole):
        assert count == count_whole
        assert all(np.array_equal(x, y) for x, y in zip(state, state_whole))


def test_has_edge_and_the_key_merge_agree_with_whole_array_searches():
    index, mesh = sphere_mesh(2000, seed=3)
    swapper = swap.EdgeSwapper(mesh.faces, index.n_points, mesh.other, mesh.edges)
    rng = np.random.default_rng(0)
    for _ in range(3):
        swapper.swap_pass(index.points + rng.normal(scale=0.003, size=index.points.shape))
        keys = swapper.keys
        assert np.all(np.diff(keys) > 0)
        fresh = swap.EdgeSwapper(swapper.faces, index.n_points)  # keys (and their runs) from scratch
        assert np.array_equal(keys, fresh.keys)
        # Queries: every edge both ways round, and random pairs (mostly absent), the last vertex too.
        u = np.concatenate([keys // index.n_points, keys % index.n_points, rng.integers(0, index.n_points, 5000)])
        v = np.concatenate([keys % index.n_points, keys // index.n_points, rng.integers(0, index.n_points, 5000)])
        u[-1] = v[-1] = index.n_points - 1
        wanted = np.isin(np.minimum(u, v) * index.n_points + np.maximum(u, v), keys)
        assert np.array_equal(swapper.has_edge(u, v), wanted)
        assert np.array_equal(fresh.has_edge(u, v), wanted)


def test_replaced_keys_merge_like_delete_and_insert():
    rng = np.random.default_rng(4)
    for size in (1, 2, 50, 1000):
        pool = np.sort(rng.choice(10 * size + 10, size=2 * size, replace=False))
        present = rng.permutation(pool)[:size]
        keys, absent = np.sort(present), np.setdiff1d(pool, present)
        m = int(rng.integers(1, size + 1))
        gone, new = np.sort(rng.choice(keys, m, replace=False)), np.sort(rng.choice(absent, m, replace=False))
        wanted = np.sort(np.concatenate([np.setdiff1d(keys, gone), new]))
        assert np.array_equal(swap._replaced(keys, gone, new), wanted)
