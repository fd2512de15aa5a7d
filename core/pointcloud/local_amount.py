"""The local amount of smoothing: fewer effective HC steps where the surface bends sharply for its noise.

With a small pull alpha, one HC step (paper section 4, alpha -> 0) is q <- q - (1 - beta) L^2 q, L the
umbrella operator: a bi-Laplacian flow. It leaves planes and spheres of many spacings' radius nearly
alone, but a thin part (an ear, a leg, a sharp rim) of curvature kappa, sampled at spacing h, sinks by
about (kappa h)^3 h per step (on a cylinder L x is -(h kappa)^2 / 4 times the radius vector). Over the
run's T steps that is T (kappa h)^3 h, to be weighed against the noise sigma it removes:

    z = T (kappa h)^3 h / sigma,    influence w = 1 / (1 + (z / Z0)^2),

the fraction of each step's move a point takes (core.smoothing's ``influence``). Flat and gently
curved parts keep the full amount, thin parts get a fraction of it. kappa is the larger absolute
principal curvature of a quadric height field fitted to the point and its nearest neighbours, on
positions that one round of smoothing has already freed of most of the noise (on the noisy input
the fit's curvature is mostly noise). Z0 and the form of w were chosen with
bench/bench_quality_points.py (bench/results/2026-11-25-point-cloud-quality.md).
"""

import numpy as np
from scipy.spatial import cKDTree

from ..geometry import smallest_eigenvectors
from ..parallel import run_blocks

Z0 = 0.3
# The fit's ball grows with the noise: thinning q = THIN_GAIN r^2 within [1, THIN_MAX] (r = sigma / spacing).
THIN_GAIN = 3.0
THIN_MAX = 36.0
_FULL = 0.98  # weights above this count as 1: the smoother then skips those points' scaling
_BLOCK = 1 << 14  # rows per block of the batched fits


def _sum_products(a, b):
    """Row sums of a * b for (s, k) arrays, without the product array."""
    return np.einsum("sk,sk->s", a, b)


def _curvature_block(planar, rows):
    """Largest absolute principal curvature of the quadric w = a u^2 + b uv + c v^2 + d u + e v + f
    fitted by least squares to the points ``rows[i]`` of ``planar`` (3, n) in a frame whose w is the
    normal of their PCA plane (rows include the point itself). The fit's normal equations are built
    from row sums of monomials; any orthonormal u, v in the plane give the same quadric."""
    x, y, z = (coordinate[rows] for coordinate in planar)
    for c in (x, y, z):
        c -= c.mean(axis=1, keepdims=True)
    reach = np.sqrt((x * x + y * y + z * z).max(axis=1))
    reach[reach == 0] = 1.0  # all neighbours on the point: no surface to bend
    for c in (x, y, z):
        c /= reach[:, None]  # unit ball: the columns of the fit are of order 1
    normal = smallest_eigenvectors(*(_sum_products(a, b) for a, b in ((x, x), (y, y), (z, z), (x, y), (x, z), (y, z))))
    # A tangent: the normal crossed with the coordinate axis it is least aligned with.
    axis = np.zeros_like(normal)
    axis[np.arange(len(normal)), np.abs(normal).argmin(axis=1)] = 1.0
    first = np.cross(normal, axis)
    first /= np.linalg.norm(first, axis=1, keepdims=True)
    second = np.cross(normal, first)

    def along(direction):
        return x * direction[:, 0:1] + y * direction[:, 1:2] + z * direction[:, 2:3]

    u, v, w = along(first), along(second), along(normal)
    uu, uv, vv = u * u, u * v, v * v
    m = {
        "uuuu": _sum_products(uu, uu),
        "uuuv": _sum_products(uu, uv),
        "uuvv": _sum_products(uu, vv),
        "uvvv": _sum_products(uv, vv),
        "vvvv": _sum_products(vv, vv),
        "uuu": _sum_products(uu, u),
        "uuv": _sum_products(uu, v),
        "uvv": _sum_products(uv, v),
        "vvv": _sum_products(vv, v),
        "uu": uu.sum(axis=1),
        "uv": uv.sum(axis=1),
        "vv": vv.sum(axis=1),
        "u": u.sum(axis=1),
        "v": v.sum(axis=1),
    }
    count = float(u.shape[1])
    # Monomials [uu, uv, vv, u, v, 1]: entry (i, j) of the normal matrix is the sum of their product.
    names = [
        ["uuuu", "uuuv", "uuvv", "uuu", "uuv", "uu"],
        ["uuuv", "uuvv", "uvvv", "uuv", "uvv", "uv"],
        ["uuvv", "uvvv", "vvvv", "uvv", "vvv", "vv"],
        ["uuu", "uuv", "uvv", "uu", "uv", "u"],
        ["uuv", "uvv", "vvv", "uv", "vv", "v"],
        ["uu", "uv", "vv", "u", "v", None],
    ]
    normal_matrix = np.empty((len(u), 6, 6))
    for i, row in enumerate(names):
        for j, name in enumerate(row):
            normal_matrix[:, i, j] = m[name] if name else count
    right = np.empty((len(u), 6, 1))
    for i, monomial in enumerate((uu, uv, vv, u, v)):
        right[:, i, 0] = _sum_products(w, monomial)
    right[:, 5, 0] = w.sum(axis=1)
    # A tiny ridge keeps collinear neighbourhoods solvable (their curvature comes out ~0).
    diagonal = np.arange(6)
    normal_matrix[:, diagonal, diagonal] += np.trace(normal_matrix, axis1=1, axis2=2)[:, None] * 1e-12
    a, b, c = np.linalg.solve(normal_matrix, right)[:, :3, 0].T
    # Hessian [[2a, b], [b, 2c]] / reach: eigenvalues (a + c +- sqrt((a - c)^2 + b^2)) / reach.
    return (np.abs(a + c) + np.hypot(a - c, b)) / reach


def curvature(points, neighbours):
    """Per point: the largest absolute principal curvature of the quadric fitted to the point and its
    ``neighbours`` (m, k) rows of ``points`` (k >= 5; 1 / radius on a sphere)."""
    rows = np.concatenate([np.arange(points.shape[0])[:, None], neighbours], axis=1)
    return _fitted(points, rows)


def _fitted(points, rows):
    """``curvature`` with the rows of each fit given, the fitted point first."""
    planar = np.ascontiguousarray(points.T)  # 1-D gathers per coordinate
    out = np.empty(rows.shape[0])

    def block(start, stop):
        for first in range(start, stop, _BLOCK):
            last = min(first + _BLOCK, stop)
            out[first:last] = _curvature_block(planar, rows[first:last])

    run_blocks(block, rows.shape[0], share=0.2)
    return out


def thinning(ratio):
    """The thinning q of the points the curvature is fitted at, for a noise / spacing ratio: 1 (every
    point, a 16-neighbour ball) for small noise; for large noise the first round leaves enough of it that
    a small ball reads it as curvature, so the ball widens (by sqrt(q)) with the noise."""
    return float(np.clip(THIN_GAIN * ratio * ratio, 1.0, THIN_MAX))


def sampled_curvature(points, neighbours, q):
    """``curvature`` seen through a ball sqrt(q) times wider at about the same cost: the quadric is fitted
    at every q-th point (the points are in KD-tree order, so a stride samples space evenly) to its
    nearest sample points, and each point takes the mean curvature of the sample points among itself and
    its ``neighbours``. q <= 1 is ``curvature`` itself."""
    m, k = neighbours.shape
    if q <= 1.0 or m < q * 4 * (k + 1):  # too few sample points for a fit each
        return curvature(points, neighbours)
    chosen = np.unique(np.arange(0.0, m, q).astype(np.int64))
    sample = points[chosen]
    tree = cKDTree(sample)
    at_sample = _fitted(sample, tree.query(sample, k + 1, workers=-1)[1])
    kappa = np.zeros(m)
    kappa[chosen] = at_sample
    taken = np.zeros(m, dtype=bool)
    taken[chosen] = True
    out = np.empty(m)

    def block(start, stop):
        near = np.concatenate([np.arange(start, stop)[:, None], neighbours[start:stop]], axis=1)
        count = taken[near].sum(axis=1)
        out[start:stop] = kappa[near].sum(axis=1) / np.maximum(count, 1)
        return start + np.flatnonzero(count == 0)

    lonely = np.concatenate(run_blocks(block, m))
    if lonely.size:  # no sample point among the neighbours: the nearest one's
        out[lonely] = at_sample[tree.query(points[lonely], 1, workers=-1)[1]]
    return out


def local_influence(kappa, steps, sigma, spacing):
    """The influence each point's HC moves get (see the module docstring): 1 where the predicted
    shrinkage of ``steps`` steps is small against the noise ``sigma``, less where it is not."""
    if sigma <= 0 or spacing <= 0:
        return np.ones_like(kappa)
    z = steps * (kappa * spacing) ** 3 * spacing / sigma
    weight = 1.0 / (1.0 + (z / Z0) ** 2)
    weight[weight > _FULL] = 1.0
    return weight
