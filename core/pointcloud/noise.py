"""How noisy is a point cloud, relative to its sample spacing? (picks the amount of smoothing)

The estimate, from a fixed-size subsample of the points (so it costs the same at 10k and 1M points):

* **Noise sigma**: around each sample point, its K nearest neighbours are put in their local PCA
  frame and a quadric height field w = a u^2 + b uv + c v^2 + d u + e v + f is fitted by least
  squares; the RMS residual (with the 6 fitted degrees of freedom taken out) is the normal-direction
  noise there. A quadric, not a plane, so that a curved but clean surface does not count as noise.
* **Spacing h**: the square root of the surface area per point. When the ball of K neighbours is
  much wider than the noise, it cuts a disc of radius d_K out of the (noisy) surface, so
  K = pi d_K^2 / h^2, i.e. h = d_K sqrt(pi / K). This is the spacing of the underlying surface
  sampling, not of the noisy points (which crowd together in 3D when the noise exceeds the spacing).
* **The ball cuts the noise off**: a ball of radius d only holds the points with |w| < d, fewer the
  nearer its rim, so it sees a smaller sigma and fewer points than the slab has (at d = 3 sigma:
  13 % less sigma, 11 % fewer points). For Gaussian noise both follow from t = sigma / d alone, so
  the observed residual / d is mapped back to t through that model (``_TRUNCATION``) and the count
  is corrected with it. The mapping flattens out as t grows (a ball much smaller than the noise is
  a 3D blob whose spread is only its own radius), so it is trusted up to t = 1/3:
* **K grows with the noise**: K starts at 24 (a small ball keeps the quadric accurate on curved,
  sparse samples) and is multiplied by 3 while the median t is above 1/3, up to 648 neighbours. It
  also grows while the balls are not two-dimensional (scan lines: dense along a line, far apart
  across, so the nearest neighbours all lie on one line, which hides the noise across it).
* The ratio sigma / h is taken per sample point and summarized by its **median**, which ignores the
  minority of points whose ball straddles a sharp edge or a boundary.
"""

from dataclasses import dataclass

import numpy as np

_SAMPLE_ENTRIES = 1 << 15  # sample points x neighbours per pass: bounds the cost of a pass
_MIN_SAMPLES = 64
_K_START, _K_GROWTH, _K_MAX = 24, 3, 648
_REACH = 3.0  # the ball of neighbours must be this many sigma wide for the truncation model


def _truncation_model():
    """For t = sigma / d in [0, 0.7]: (observed residual / d, fraction of the slab's points kept) of
    a plane sampled with density rho and Gaussian normal noise sigma, cut by a ball of radius d: a
    point at height w is kept within the disc of radius sqrt(d^2 - w^2)."""
    t = np.linspace(0.0, 0.7, 141)
    z = np.linspace(-8.0, 8.0, 1601)
    weight = np.exp(-0.5 * z * z)
    weight /= weight.sum()
    w = t[:, None] * z[None, :]
    kept = np.clip(1.0 - w * w, 0.0, None) * weight  # disc area / (pi d^2), times the density of w
    fraction = kept.sum(axis=1)
    observed = np.sqrt((w * w * kept).sum(axis=1) / fraction)
    return t, observed, fraction


_TRUNCATION = _truncation_model()  # observed is increasing on this range of t
_MIN_POINTS = 12  # below this there is no neighbourhood to fit a quadric to
# Middle / largest PCA eigenvalue a neighbourhood needs to count as a piece of surface (a uniform disc:
# 1; a ball on one scan line, whose neighbours all lie along the line: ~0, and a line fits any noise
# across it exactly, so the ball has to grow until it spans several lines).
_TWO_D = 0.2


@dataclass(frozen=True)
class NoiseEstimate:
    """How noisy a point cloud is against its sample spacing (``estimate_noise``; the module docstring
    says how it is measured).

    Examples
    --------
    >>> import numpy as np, core
    >>> from core.pointcloud.spanning_tree import NeighbourIndex
    >>> rng = np.random.default_rng(0)
    >>> sphere = rng.normal(size=(500, 3))
    >>> sphere /= np.linalg.norm(sphere, axis=1, keepdims=True)
    >>> noisy = sphere * rng.normal(1.0, 0.03, size=(500, 1))
    >>> index = NeighbourIndex(noisy, 16)  # distinct points, KD-tree, 16 nearest neighbours
    >>> estimate = core.pointcloud.estimate_noise(index)
    >>> round(estimate.sigma, 2), round(estimate.ratio, 1), estimate.samples  # the noise added: 0.03
    (0.03, 0.2, 500)
    """

    ratio: float  # median over sample points of sigma / spacing (0 when there are too few points)
    sigma: float  # median normal-direction noise (same units as the points)
    spacing: float  # median sqrt(area per point) of the underlying sampling
    neighbours: int  # K of the pass the estimate comes from
    samples: int  # sample points it is the median over


def _quadric_residuals(points, neighbour_rows, reach):
    """Per row: (RMS residual of the quadric height field fitted to points[neighbour_rows[row]] in
    their PCA frame, in units of that row's ``reach``; middle / largest PCA eigenvalue).
    ``neighbour_rows`` (s, K) includes the centre point itself."""
    patch = points[neighbour_rows]  # (s, K, 3)
    patch = patch - patch.mean(axis=1, keepdims=True)
    # In units of the ball's radius: every column of the fit below is then of order 1 at any scale.
    patch /= reach[:, None, None]
    covariance = np.einsum("ski,skj->sij", patch, patch)
    spread, frame = np.linalg.eigh(covariance)  # ascending: column 0 is the normal
    local = np.einsum("ski,sij->skj", patch, frame)
    u, v, w = local[..., 2], local[..., 1], local[..., 0]
    design = np.stack([u * u, u * v, v * v, u, v, np.ones_like(u)], axis=2)  # (s, K, 6)
    normal_matrix = np.einsum("ska,skb->sab", design, design)
    right = np.einsum("ska,sk->sa", design, w)
    # A tiny ridge keeps degenerate patches (collinear neighbours) solvable; their residual is ~0.
    # Relative to the trace (at least K, from the constant column), and the columns are alike in size.
    scale = np.trace(normal_matrix, axis1=1, axis2=2)[:, None, None] * 1e-12
    coefficients = np.linalg.solve(normal_matrix + scale * np.eye(6), right[..., None])[..., 0]
    residual = w - np.einsum("ska,sa->sk", design, coefficients)
    dof = max(neighbour_rows.shape[1] - 6, 1)
    flatness = spread[:, 1] / spread[:, 2]  # the largest is > 0: the farthest neighbour is at distance 1
    return np.sqrt(np.einsum("sk,sk->s", residual, residual) / dof), flatness


def estimate_noise(index):
    """NoiseEstimate of the distinct points of a ``NeighbourIndex`` (see the module docstring).

    Parameters
    ----------
    index : core.pointcloud.spanning_tree.NeighbourIndex
        The distinct points and their KD-tree.

    Returns
    -------
    NoiseEstimate
        All zero for fewer than 12 points.

    Examples
    --------
    >>> import numpy as np, core
    >>> from core.pointcloud.spanning_tree import NeighbourIndex
    >>> rng = np.random.default_rng(0)
    >>> sphere = rng.normal(size=(500, 3))
    >>> sphere /= np.linalg.norm(sphere, axis=1, keepdims=True)
    >>> noisy = sphere * rng.normal(1.0, 0.03, size=(500, 1))
    >>> index = NeighbourIndex(noisy, 16)  # distinct points, KD-tree, 16 nearest neighbours
    >>> round(core.pointcloud.estimate_noise(index).sigma, 2)
    0.03
    """
    m = index.n_points
    if m < _MIN_POINTS:
        return NoiseEstimate(0.0, 0.0, 0.0, 0, 0)
    k = min(_K_START, m - 1)
    while True:
        # Evenly spaced rows of the KD-tree order: spread over the whole cloud, and deterministic.
        samples = int(min(m, max(_MIN_SAMPLES, _SAMPLE_ENTRIES // (k + 1))))
        rows = np.linspace(0, m - 1, samples).round().astype(np.int64)
        distance, found = index.tree.query(index.points[rows], k + 1, workers=-1)  # column 0: the point itself
        reach = distance[:, -1]  # > 0: the points are distinct
        observed, flatness = _quadric_residuals(index.points, found, reach)
        t_table, observed_table, fraction_table = _TRUNCATION
        t = np.interp(observed, observed_table, t_table)  # clipped to 0.7 where the model saturates
        sigma = t * reach
        spacing = reach * np.sqrt(np.pi * np.interp(t, t_table, fraction_table) / k)
        wide_enough = np.median(t) <= 1.0 / _REACH and np.median(flatness) >= _TWO_D
        if wide_enough or k >= min(_K_MAX, m - 1):
            break
        k = min(k * _K_GROWTH, _K_MAX, m - 1)
    positive = spacing > 0
    ratio = float(np.median(sigma[positive] / spacing[positive])) if positive.any() else 0.0
    return NoiseEstimate(ratio, float(np.median(sigma)), float(np.median(spacing)), int(k), int(samples))


# --- the amount of smoothing -------------------------------------------------------------------------
#
# After T umbrella steps a point has averaged over about sqrt(T) mesh spacings, and HC's pull alpha to
# the originals stops the spreading at about 1/sqrt(alpha) spacings. To average the noise away the
# reach has to grow with the noise over the spacing, r, so T grows as r^2, and alpha = PULL / T
# keeps the pull from cancelling the extra steps. Too much reach on a nearly clean, sparse sample
# flattens the surface between the samples and rounds sharp edges; too little leaves noise. Sweeps
# of T with bench/bench_points.py (bench/results/2026-11-23-point-clouds.md at commit 555017f, "How the amount of
# smoothing is chosen") put the best T between 300 r^2 and 1200 r^2 on smooth shapes and lower on
# sharp edges; the rule takes the low end: too few steps leave some noise, too many distort the shape.
# The rule: T = STEPS_PER_RATIO_SQUARED r^2 within [MIN_STEPS, MAX_STEPS], alpha = PULL / T.
STEPS_PER_RATIO_SQUARED = 300.0
MIN_STEPS = 3  # one step per round at the default 3 rounds
MAX_STEPS = 198  # bounds the cost: 3 rounds of 66 steps (reached at r = 0.81)
PULL = 0.66  # alpha x total steps


def total_steps(ratio):
    """Total HC steps for a noise / spacing ratio: STEPS_PER_RATIO_SQUARED r^2 within [MIN_STEPS, MAX_STEPS]."""
    if not np.isfinite(ratio) or ratio < 0:
        raise ValueError(f"the noise / spacing ratio must be a number >= 0, got {ratio!r}")
    return int(np.clip(round(STEPS_PER_RATIO_SQUARED * ratio * ratio), MIN_STEPS, MAX_STEPS))


def steps_per_round(ratio, rounds):
    """HC steps per round for ``rounds`` rounds (at least 1) that together come closest to total_steps."""
    return max(1, int(round(total_steps(ratio) / max(rounds, 1))))


def matched_alpha(steps):
    """The pull that stops HC's reach about where ``steps`` steps get: PULL / steps, at most 1.

    Examples
    --------
    >>> import core
    >>> core.matched_alpha(10)
    0.066
    """
    return float(min(1.0, PULL / max(steps, 1)))
