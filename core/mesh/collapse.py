"""Parts whose shape the Automatic Amount would change are left as they were: those it collapses, and
those whose shape it takes away with the noise.

On a coarse part the shape itself can read as noise. Blender's Cone (33 vertices) with noise of 0.1 median
edge lengths: GCV (core.mesh.amount) sees its apex and rim as noise, chooses 198 iterations, and the cone
shrinks to a point (Keep Sharp Edges: by a third); its noise estimate is as large as the part, so the
deviation limit does not hold it. No amount chosen for noise should do that: taking noise of standard
deviation sigma away from a part shrinks its RMS radius r (about its centroid) to sqrt(r^2 - 3 sigma^2) at
the least (isotropic noise; noise along the normals takes less). A part that ends below ``KEEP`` times that
gets its input positions back: left noisy, not harmed. sigma is core.mesh.noise's robust estimate of the
part, which a coarse shape does not inflate as it does GCV's.

A part can also lose its shape without shrinking. On a coarse CAD part (a tube whose walls are single
quads, every vertex on a rim) one HC iteration rounds the rims by more than the noise it takes away. What
the smoothing removed then moves alike from vertex to vertex: the residual along the normals,
r_i = (y_i - x_i) . n_i (y the input, x the result, n its vertex normals), correlates positively between
neighbours (rims moved inwards together), where noise taken away is white or alternating (negative). A
part of at least ``SMOOTH_FROM`` vertices whose residual's neighbour correlation exceeds ``SMOOTH_RESIDUAL``
gets its input back too (``smooth_residual``; HC's default only). Parts of core.mesh.amount.PATCH_FROM
vertices or more, which the Automatic Amount treats as big scans, are not asked: the test takes a pass of
normals over them (about 1.3 s on 5M vertices, a quarter of the default's own time there).

Both smoothers also have a rule read from how far they moved (``moved_beyond_noise``; HC's asks the parts
its correlation rule asks). Taking noise of standard deviation sigma along the normals away moves a
surface by sigma RMS along its normals; a result that ends at an error e
from the shape, e independent of the noise, has moved by sqrt(sigma^2 + e^2). A part moved by more than
``MOVED_IN_NOISE`` = sqrt(2) sigma ended farther from its shape than the input was (e > sigma), by the
noise model alone: nothing here is tuned. Keep Sharp Edges' filter flattens coarse curved parts (a UV
Sphere, a Torus, adjacent faces meeting at near its own angle) that way, and HC rounds the edges and
corners of a coarse noisy box (Blender's Cube subdivided and triangulated) that way; their input comes
back. A linear filter S that keeps t = tr(S) / n of the noise (HC's run at alpha 0: core.mesh.amount
measures t) takes less of it away: its move is sqrt(sigma^2 (1 - 2 t + tr(S'S) / n) + e^2), its error
sqrt(sigma^2 tr(S'S) / n + e^2), and the error exceeds the input's sigma exactly where the move exceeds
sqrt(2 (1 - t)) sigma; HC's rule reads that bound (one iteration keeps about half the noise: a box of 9
cuts that one iteration rounds moves by less than sqrt(2) sigma, yet by more than sigma). That bound has no
slack for a noise estimate read low, as core.mesh.noise reads heavy noise and the noise of a part of a few
dozen vertices (a noisy Ico Sphere of 42 vertices that HC takes half the error off moves 1.1 times that bound): HC's
rule reads it on the light-noise parts (core.mesh.noise's half-step test: light noise, told from
shape, on at least its WHITE_SAMPLES vertices) and on the quiet ones (no noise found: a coarse box with
noise of 0.1 % of its size, which one iteration rounds 1.1-1.3 times farther from the cube), the sqrt(2)
bound elsewhere. The sigma these rules read is core.mesh.noise's floor estimate: a box of a few cuts,
whose creases reach most of its vertices, inflates the median's estimate to a quarter of an edge (20 times
the noise), the floor's to a few times the noise; a box of nine cuts, whose creases reach a fifth of them,
both to 1.3-1.7 times it, the floor's clipped estimate to 1.0-1.3 times. The estimate reads a sample of a
big part's vertices; before a part goes back on it, the caller reads it again on all of them
(core.mesh.noise.read_on_every_vertex): a sample's low reading holds no noisy part.

Keep Sharp Edges, which fits planes, takes the noise away whole: what it moved a vertex along its normal is
that vertex's noise, and the robust scale of those moves (median |r_i| / 0.6745) reads the noise where the
estimate reads a coarse shape's creases; its rule reads the smaller of the two. A part whose input has a
defect the filter keeps (a quad collapsed to a point at a crease drags the crease into a chamfer, and the
filter fits the vertices around to the chamfer's plane) moves a few vertices by many times that scale,
and gets its input back.
"""

import math

import numpy as np

from .. import parallel
from ..geometry import centroid, vertex_normals
from .amount import PATCH_FROM
from .noise import _MAD, _group_medians

# Of the radius noise removal can leave: a collapsing cone ends near 0 (HC) or at 0.4-0.66 (Keep Sharp Edges),
# a smoothing that keeps the shape near 1. An 8-vertex cube with noise of half its edge can end below it (its
# noise estimate is loose on so few vertices) and is then left noisy.
KEEP = 0.75


def collapsed(before, after, part_of_vertex, sigma):
    """(parts,) bool: the parts whose RMS radius in ``after`` is below KEEP x sqrt(r^2 - 3 sigma^2), r their
    radius in ``before`` and ``sigma`` (parts,) their noise.

    Examples
    --------
    >>> import numpy as np
    >>> from core.mesh.collapse import collapsed
    >>> square = np.array([[1, 1, 0], [1, -1, 0], [-1, -1, 0], [-1, 1, 0]], dtype=float)
    >>> before = np.r_[square, square + 5.0]  # two parts of radius sqrt(2)
    >>> after = np.r_[0.95 * square, 0.1 * square + 5.0]  # the first noise taken away, the second shrunk
    >>> collapsed(before, after, np.array([0, 0, 0, 0, 1, 1, 1, 1]), np.array([0.1, 0.1])).tolist()
    [False, True]
    """
    parts = sigma.size
    counts = np.maximum(np.bincount(part_of_vertex, minlength=parts), 1)
    return _radii(after, part_of_vertex, counts) < KEEP * np.sqrt(
        np.maximum(_radii(before, part_of_vertex, counts) ** 2 - 3.0 * sigma**2, 0.0)
    )


def _radii(points, part_of_vertex, counts):
    """(parts,) the RMS distance of each part's vertices to their centroid, in the points' own precision
    (a ratio of radii is all it is for); one part, the usual scan, without the per-part gathers."""
    points = np.asarray(points)
    if counts.size == 1:
        away = points - centroid(points).astype(points.dtype)
        return np.sqrt(np.array([np.einsum("ij,ij->", away, away, dtype=np.float64)]) / counts)
    centroids = np.stack([np.bincount(part_of_vertex, points[:, k], counts.size) for k in range(3)], axis=1)
    away = points - (centroids / counts[:, None])[part_of_vertex].astype(points.dtype)
    return np.sqrt(np.bincount(part_of_vertex, np.einsum("ij,ij->i", away, away), counts.size) / counts)


# The residual's neighbour correlation above which a part's shape, not its noise, was taken away: HC's
# default leaves it below 0 on the benchmark's scans (bench_default_heldout.py holds no part there but
# face000's floaters), at or above 0.10 on the coarse primitives it makes worse (the tube at 0.1-0.3 edge
# lengths, the NGon cylinder) and at most 0.03 on those it takes a fifth of the error off or more without
# collapsing them (bench_primitives.py --no-guard). The NGon cylinder, 0.85-0.99 of the input's error where
# it is not worse, reads 0.21-0.37 and is held.
SMOOTH_RESIDUAL = 0.07
SMOOTH_FROM = 20  # vertices: on fewer the correlation is mostly chance


def smooth_residual(before, after, triangles, operator, part_of_vertex, parts):
    """(parts,) bool: the parts of SMOOTH_FROM to PATCH_FROM vertices whose residual along the normals
    correlates between neighbours (the pairs of ``operator``, a core.umbrella_operator) above
    SMOOTH_RESIDUAL.

    Examples
    --------
    >>> import numpy as np, core
    >>> from core.mesh.collapse import smooth_residual
    >>> u, v = np.meshgrid(np.linspace(0, 1, 8), np.linspace(0, 1, 8))
    >>> grid = np.arange(64).reshape(8, 8)
    >>> triangles = np.r_[np.stack([grid[:-1, :-1], grid[:-1, 1:], grid[1:, 1:]], -1).reshape(-1, 3),
    ...                   np.stack([grid[:-1, :-1], grid[1:, 1:], grid[1:, :-1]], -1).reshape(-1, 3)]
    >>> operator = core.umbrella_operator(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), 64)
    >>> flat = np.c_[u.ravel(), v.ravel(), np.zeros(64)]
    >>> noisy = flat + [0, 0, 0.01] * np.random.default_rng(0).normal(size=(64, 1))
    >>> bump = flat + [0, 0, 0.1] * np.exp(-10 * ((u - 0.5) ** 2 + (v - 0.5) ** 2)).reshape(-1, 1)
    >>> one_part = np.zeros(64, dtype=int)
    >>> bool(smooth_residual(noisy, flat, triangles, operator, one_part, 1)[0])  # noise taken away
    False
    >>> bool(smooth_residual(bump, flat, triangles, operator, one_part, 1)[0])  # the bump taken away
    True
    """
    counts = np.bincount(part_of_vertex, minlength=parts)
    asked = (counts >= SMOOTH_FROM) & (counts < PATCH_FROM)
    if not asked.any():
        return asked
    correlation = residual_correlation(
        before, after, _of_parts(triangles, asked, part_of_vertex), operator, part_of_vertex, parts
    )
    return asked & (correlation > SMOOTH_RESIDUAL)


def _of_parts(triangles, asked, part_of_vertex):
    """The triangles of the parts ``asked`` ((parts,) bool): the residual's normals are taken over these only."""
    triangles = np.asarray(triangles)
    return triangles[asked[part_of_vertex[triangles[:, 0]]]]


def _residual(before, after, triangles):
    """r_i = (y_i - x_i) . n_i: ``before`` y less ``after`` x along the result's area-weighted vertex normals
    (0 where no triangle touches a vertex)."""
    return np.einsum("ij,ij->i", np.asarray(before) - np.asarray(after), vertex_normals(after, triangles))


def residual_correlation(before, after, triangles, operator, part_of_vertex, parts):
    """(parts,) the correlation of r_i = (y_i - x_i) . n_i (``before`` y, ``after`` x, n the result's
    area-weighted vertex normals) between neighbours, sum r_i r_j / sum deg_i r_i^2 over each part's pairs,
    r taken about its part's mean (the volume restore's uniform offset is no shape)."""
    residual = _residual(before, after, triangles)
    counts = np.bincount(part_of_vertex, minlength=parts)
    residual -= (np.bincount(part_of_vertex, residual, parts) / np.maximum(counts, 1))[part_of_vertex]
    around = np.empty_like(residual)  # sum of r_j over each vertex's neighbours, in cache-sized chunks

    def keep(rows, sums):
        around[rows] = sums[0]

    parallel.RowBlocks(operator.indptr, operator.indices, operator.n_vertices).run(
        lambda block: block.neighbour_sums(residual[None, :], keep)
    )
    pairs = np.bincount(part_of_vertex, residual * around, parts)
    squares = np.bincount(part_of_vertex, operator.degree * residual**2, parts)
    return pairs / np.maximum(squares, 1e-300)


MOVED_IN_NOISE = math.sqrt(2.0)


def moved_beyond_noise(before, after, triangles, part_of_vertex, sigma, asked, kept=0.0, own_scale=False):
    """(parts,) bool: the parts of at least SMOOTH_FROM vertices ``asked`` ((parts,) bool: those with noise
    found, or as the caller chooses)
    whose RMS move along the result's normals, r_i = (y_i - x_i) . n_i (``before`` y, ``after`` x), exceeds
    MOVED_IN_NOISE times their noise ``sigma``, times sqrt(1 - ``kept``) where the run is a linear filter S
    whose trace ``kept`` = tr(S) / n is known (core.mesh.amount's t(k); 0: not known, the bound for any filter;
    a number, or one per part).
    ``own_scale`` (a filter that takes the noise away whole: Keep Sharp Edges): sigma is at most the robust
    scale of the move itself, median |r_i| / 0.6745 over the part.

    Examples
    --------
    >>> import numpy as np
    >>> from core.mesh.collapse import moved_beyond_noise
    >>> around = np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False)
    >>> disc = np.c_[np.r_[0.0, np.cos(around)], np.r_[0.0, np.sin(around)], np.zeros(25)]
    >>> fan = np.c_[np.zeros(24, dtype=int), np.arange(1, 25), np.r_[np.arange(2, 25), 1]]
    >>> noisy = disc + [0.0, 0.0, 0.01] * (-1.0) ** np.arange(25)[:, None]  # noise of 0.01 along the normals
    >>> one_part, found, sigma = np.zeros(25, dtype=int), np.array([True]), np.array([0.01])
    >>> moved_beyond_noise(noisy, disc, fan, one_part, sigma, found).tolist()  # the noise taken away
    [False]
    >>> moved_beyond_noise(noisy, disc + [0.0, 0.0, 0.02], fan, one_part, sigma, found).tolist()  # moved by more
    [True]
    """
    parts = sigma.size
    counts = np.bincount(part_of_vertex, minlength=parts)
    asked = asked & (counts >= SMOOTH_FROM)
    if not asked.any():
        return asked
    residual = _residual(before, after, _of_parts(triangles, asked, part_of_vertex))
    moved = np.sqrt(np.bincount(part_of_vertex, residual * residual, parts) / np.maximum(counts, 1))
    if own_scale:
        sigma = np.fmin(sigma, _group_medians(part_of_vertex, np.abs(residual), parts) / _MAD)
    return asked & (moved > MOVED_IN_NOISE * np.sqrt(np.maximum(1.0 - np.asarray(kept, dtype=np.float64), 0.0)) * sigma)
