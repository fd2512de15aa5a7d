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
bench/bench_quality_points.py (bench/README.md, "Quality on real scans (point clouds)").
"""

import numpy as np

from .threads import run_blocks

Z0 = 0.3
_FULL = 0.98  # weights above this count as 1: the smoother then skips those points' scaling
_BLOCK = 1 << 14  # rows per block of the batched fits


def _curvature_block(points, rows):
    """Largest absolute principal curvature of the quadric w = a u^2 + b uv + c v^2 + d u + e v + f
    fitted by least squares to points[rows[i]] in their PCA frame (rows include the point itself)."""
    patch = points[rows]
    patch -= patch.mean(axis=1, keepdims=True)
    reach = np.sqrt(np.einsum("ski,ski->sk", patch, patch).max(axis=1))
    reach[reach == 0] = 1.0  # all neighbours on the point: no surface to bend
    patch /= reach[:, None, None]  # unit ball: the columns of the fit are of order 1
    frame = np.linalg.eigh(np.einsum("ski,skj->sij", patch, patch))[1]  # ascending: column 0 the normal
    local = np.einsum("ski,sij->skj", patch, frame)
    u, v, w = local[..., 2], local[..., 1], local[..., 0]
    design = np.stack([u * u, u * v, v * v, u, v, np.ones_like(u)], axis=2)
    normal_matrix = np.matmul(design.transpose(0, 2, 1), design)
    right = np.matmul(design.transpose(0, 2, 1), w[..., None])
    # A tiny ridge keeps collinear neighbourhoods solvable (their curvature comes out ~0).
    ridge = np.trace(normal_matrix, axis1=1, axis2=2)[:, None, None] * 1e-12 * np.eye(6)
    a, b, c = np.linalg.solve(normal_matrix + ridge, right)[:, :3, 0].T
    # Hessian [[2a, b], [b, 2c]] / reach: eigenvalues (a + c +- sqrt((a - c)^2 + b^2)) / reach.
    return (np.abs(a + c) + np.hypot(a - c, b)) / reach


def curvature(points, neighbours):
    """Per point: the largest absolute principal curvature of the quadric fitted to the point and its
    ``neighbours`` (m, k) rows of ``points`` (k >= 5; 1 / radius on a sphere)."""
    rows = np.concatenate([np.arange(points.shape[0])[:, None], neighbours], axis=1)
    out = np.empty(points.shape[0])

    def block(start, stop):
        for first in range(start, stop, _BLOCK):
            last = min(first + _BLOCK, stop)
            out[first:last] = _curvature_block(points, rows[first:last])

    run_blocks(block, points.shape[0], share=0.2)
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
