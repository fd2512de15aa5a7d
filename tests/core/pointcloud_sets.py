"""Point sets for the point-cloud tests: hard cases for the EMST and noisy samples of known surfaces."""

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import minimum_spanning_tree
from scipy.spatial import Delaunay


def uniform(n, seed=0):
    return np.random.default_rng(seed).random((n, 3))


def scan_lines(rows=8, per_row=300, seed=0):
    """Dense rows far apart (row gap ~50x the spacing along a row): a kNN graph is disconnected."""
    rng = np.random.default_rng(seed)
    x = np.linspace(0.0, 1.0, per_row)
    return np.concatenate(
        [np.stack([x, np.full(per_row, y), 0.01 * rng.random(per_row)], axis=1) for y in np.linspace(0.0, 1.0, rows)]
    )


def sphere_rings(rings=40, per_ring=150, seed=0):
    """Scan rings on a unit sphere (latitude circles, dense along each ring, rings far apart
    relative to that): every Borůvka round needs exact searches, and merged rings invalidate the
    remembered nearest foreign points of many others."""
    rng = np.random.default_rng(seed)
    theta = np.linspace(0.1, np.pi - 0.1, rings)[:, None]
    phi = np.linspace(0.0, 2 * np.pi, per_ring, endpoint=False)[None, :] + rng.random((rings, 1))
    p = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta) + 0 * phi], axis=-1)
    return p.reshape(-1, 3) + rng.normal(scale=1e-4, size=(rings * per_ring, 3))


def clusters(k=6, size=200, seed=0):
    """Tight clusters far apart."""
    rng = np.random.default_rng(seed)
    centres = rng.random((k, 3)) * 10.0
    return np.concatenate([rng.normal(c, 0.01, (size, 3)) for c in centres])


def with_duplicates(n=400, seed=0):
    rng = np.random.default_rng(seed)
    p = rng.random((n, 3))
    return np.concatenate([p, p[: n // 4], p[: n // 8]])[rng.permutation(n + n // 4 + n // 8)]


def grid_ties(n=600, seed=0):
    """Points on a coarse grid: many equal distances and duplicates."""
    return np.round(np.random.default_rng(seed).random((n, 3)) * 5.0) / 5.0


def delaunay_mst_length(points):
    """Total length of the EMST via the MST of all Delaunay edges (duplicates add nothing)."""
    distinct = np.unique(points, axis=0)
    simplices = Delaunay(distinct).simplices
    pairs = np.concatenate([simplices[:, [i, j]] for i in range(4) for j in range(i + 1, 4)])
    pairs = np.unique(np.sort(pairs, axis=1), axis=0)
    length = np.linalg.norm(distinct[pairs[:, 0]] - distinct[pairs[:, 1]], axis=1)
    graph = sp.coo_matrix((length, (pairs[:, 0], pairs[:, 1])), shape=(len(distinct),) * 2)
    return minimum_spanning_tree(graph).sum()


def noisy_sphere(n, sigma_fraction, seed=0, dtype=np.float64):
    """Unit sphere, Gaussian noise of sigma_fraction x bounding-box diagonal (2 sqrt 3)."""
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return (v + rng.normal(scale=sigma_fraction * 2 * np.sqrt(3), size=v.shape)).astype(dtype)


def sphere_rms(points):
    return float(np.sqrt(np.mean((np.linalg.norm(points, axis=1) - 1.0) ** 2)))
