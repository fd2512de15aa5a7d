"""Keep Sharp Edges: smoothing that keeps the creases of hard-surface parts (machined, cast, CAD-like).

HC's umbrella averages every vertex with all its neighbours, across a crease too, so it rounds every
edge. This mode smooths the face normals first, never across a crease, then moves the vertices to fit
the smoothed normals: Sun, Rosin, Martin and Langbein 2007, "Fast and effective feature-preserving mesh
denoising" (the two-step scheme MeshLab offers as "Two Step Smoothing").

One step of it, with the triangles' unit normals n_f and centroids c_f:

1. **Normal filtering**, ``NORMAL_ITERATIONS`` times: n_i <- normalize(sum_j w_ij n_j) over the faces j
   sharing a vertex with face i (i itself included), w_ij = (g_i . g_j - T)^2 where g_i . g_j > T and 0
   elsewhere, T = cos(sharpness angle). Faces whose guidance normals g meet at more than the sharpness
   angle do not see each other: the normals of the two sides of a crease stay apart, while the noise
   within each side is averaged away. The guidance (Zhang, Deng, Zhang, Bouaziz and Liu 2015, "Guided
   Mesh Normal Filtering"; ``guidance_normals``), computed once per step, is the mean normal of the most
   consistent patch each face lies in: steady where a single face is not, it tells a crease from noise
   that tilts faces by nearly as much as the crease turns. It runs where core.mesh.noise finds noise
   (``guided``; core.MeshSmoother asks, steps set or not): it needs patches on one side of each crease,
   which scans have and a coarse model (every face at a corner) does not. Elsewhere Sun et al.'s filter
   compares the faces' own normals, g = n, recomputed every pass. On bench_sharp_edges.py's tuning parts
   the guidance (with the nearest planes below) leaves 14-25 % less RMS error at 1 % isotropic noise,
   and the bevelled box's creases 13-15° off at 0.5 % noise instead of 36° (against ``guided=False``).
   With the guidance, each face then takes the filtered normal of its ring whose plane lies nearest its
   corners (``nearest_plane_normals``): the faces along a crease that filtering left between the two
   sides take the side they lie on, and a face at a corner, where every patch is mixed and the guidance
   blends the sides, takes its own side's plane back from a neighbour that kept it (a clean box of 8 x 8
   squares a side stays put).
2. **Vertex fitting**, ``FIT_ITERATIONS`` times: x_i <- x_i + 1/|F_i| sum_{f in F_i} n_f n_f^T (c_f - x_i),
   F_i the faces around vertex i: each vertex moves towards the planes through its faces' centroids
   with the filtered normals (a crease vertex to the line where its two planes meet, a corner to the
   point of three). With the guidance, the faces then take their nearest planes again, placed by the
   fitted corners (much less noisy than the step's start), and ``REFIT_ITERATIONS`` more passes follow.
3. **Tangential relaxation**: a vertex whose faces all agree (no crease through it, no open border)
   moves ``TANGENTIAL`` of the way to its neighbours' mean along its tangent plane: noise along the
   surface (isotropic noise)
   leaves uneven, folded triangles whose normals the filter cannot trust; this evens them out without
   moving the surface (on the tuning parts at 0.5 % isotropic noise: 2-16 % less RMS error).
4. **HC's push-back** (paper section 4, Algorithm 1), with the step's move as the Laplacian move:
   b_i = p_i - (alpha o_i + (1 - alpha) q_i), then p_i <- p_i - (beta b_i + (1 - beta) mean_adj(b)).
   What the fitting moved alike over a neighbourhood (a face or a rim drifting inwards: shrinkage) is
   taken back, what it moved vertex by vertex (the noise) is kept.
5. The corners of triangles the step turned over (against their filtered normal or their ring's mean)
   get half their move, up to ``FOLD_ROUNDS`` times; then the deviation limit, if any. A triangle that
   noise had turned over before the step is left to it: halving its corners' moves would keep the fold
   (bench_sharp_edges.py --sets tuning --sigmas 0.01 --kinds iso: 25-55 % less RMS error than halving them
   too).

Everything runs on all faces or vertices at once: the face rings are one sparse pattern (the faces
sharing a vertex with each face: incidence times its transpose), built once per run; the filtering
computes the weight of each pair of faces in it once (about 6 per triangle; once per step with the
guidance, every pass without) and sums it both ways, a fitting pass is three sparse products on the
flattened coordinates.
Fixed vertices never move (their positions still place their faces' planes); ``influence`` scales each
step's move, as core.smoothing scales an iteration's.
"""

import itertools
import math
from collections.abc import Iterator

import numpy as np
import scipy.sparse as sp

try:  # the kernels behind ``csr_matrix @ x`` (y += A x) and the CSC's; private: a public fallback
    from scipy.sparse._sparsetools import csc_matvecs as _csc_matvecs
    from scipy.sparse._sparsetools import csr_matvec as _csr_matvec
    from scipy.sparse._sparsetools import csr_matvecs as _csr_matvecs

    _probe = (np.array([0, 1], dtype=np.int32), np.zeros(1, dtype=np.int32), np.ones(1), np.ones(1), np.zeros(1))
    _csr_matvec(1, 1, *_probe)
    _csr_matvecs(1, 1, 1, *_probe)
    _csc_matvecs(1, 1, 1, *_probe)
    if _probe[-1][0] != 3.0:
        raise ValueError("y += A x expected")
except (ImportError, TypeError, ValueError):  # SciPy without these kernels, or with other signatures
    _csr_matvec = _csr_matvecs = _csc_matvecs = None
from numpy.typing import ArrayLike

from ..adjacency import Umbrella, umbrella_operator
from ..geometry import face_normals, fan_triangles, project_rows_within
from ..parallel import BLOCK
from ..slices import to_end
from ..validation import (
    bbox_diagonal,
    check_fixed,
    check_influence,
    check_iterations,
    check_max_deviation,
    check_positions,
    check_tolerance,
    check_unit_interval,
)

# Faces meeting at more than this angle are not averaged, as Blender's Auto Smooth angle: 30° keeps the 35°
# and 45° creases of a bevelled box, 50° rounds them (bench_sharp_edges.py's bevelled box at 0.25 % noise,
# core.smooth_mesh with sharpness_angle 30°, 40°, 50°: 4.6°, 5.5°, 23.5° of dihedral error along the normals).
DEFAULT_SHARPNESS_ANGLE = math.radians(30.0)
NORMAL_ITERATIONS = 20  # filtering passes per step (MeshLab's default too)
FIT_ITERATIONS = 20  # fitting passes per step (MeshLab's default too)
# Fitting passes after the faces take their nearest planes again, from the fitted corners (guided steps):
# on the tuning parts at 0.5 % noise 5 leave as little dihedral error as 20.
REFIT_ITERATIONS = 5
DEFAULT_ALPHA = 0.0  # the push-back's weights (paper section 4): beta 0 takes back each step's
DEFAULT_BETA = 0.0  # neighbourhood mean (the drift), keeps all of the vertex-by-vertex part (the noise)
DEFAULT_ITERATIONS = 5  # steps when the caller gives no amount and no Automatic Amount runs
TANGENTIAL = 0.5  # share of the tangential umbrella move per step on vertices off the creases (step 3)
FOLD_ROUNDS = 4  # rounds of halving the move of the corners of triangles a step turned over
PASS_SLICES_FROM = 200_000  # triangles from which steps() also yields between the passes of a step
FIT_SLICE = 5  # fitting passes between two of those yields
FIT_SLICES = -(-FIT_ITERATIONS // FIT_SLICE)
REFIT_SLICES = -(-REFIT_ITERATIONS // FIT_SLICE)
GUIDED_SLICES = 3  # after the guidance and after each choice of the nearest planes
STEP_SLICES = GUIDED_SLICES + NORMAL_ITERATIONS + FIT_SLICES + REFIT_SLICES + FOLD_ROUNDS  # a step's, at most
# The guidance's vertex rings (about 6 faces) count their consistency this many times against the face
# rings' (about 13): on the tuning parts at 0.5 % noise 1.5-3 leave the same dihedral error, 1 more.
VERTEX_RING_WEIGHT = 2.0
_BLOCK = BLOCK  # face pairs per block of the filtering's dot products: its temporaries stay in cache


def check_sharpness_angle(value):
    """The sharpness angle in radians, in (0, pi), or ValueError."""
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float, np.integer, np.floating))
        or not np.isfinite(value)
    ):
        raise ValueError(f"sharpness_angle must be an angle in radians, got {value!r}")
    if not 0.0 < value < math.pi:
        raise ValueError(
            f"sharpness_angle must lie between 0 and pi radians (0 and 180 degrees), got {value!r} "
            f"({math.degrees(value):g} degrees)"
        )
    return float(value)


def check_triangles(faces, n_vertices):
    """The (t, 3) triangles of ``faces`` (any polygons, fanned), indices checked; ValueError if none."""
    if faces is None:
        raise ValueError("Keep Sharp Edges needs the faces: it smooths the face normals (pass faces=)")
    triangles = fan_triangles(faces)
    if triangles.shape[0] == 0:
        raise ValueError("Keep Sharp Edges needs faces, and the mesh has none (a point cloud or a wire mesh)")
    if triangles.min() < 0 or triangles.max() >= n_vertices:
        raise ValueError(f"faces must use vertex indices between 0 and {n_vertices - 1}")
    return triangles


class FaceRings:
    """The sparse patterns of a triangle mesh the two steps run on.

    Attributes
    ----------
    incidence : (n, t) CSR, 1 where vertex i is a corner of triangle f.
    indptr, indices, counts : the faces sharing a vertex with each face, itself included (CSR, (t, t)).
    ring : that pattern as a (t, t) CSR of ones.
    upper_rows, upper_indptr, upper_indices : the pairs i < j of that pattern (CSR, (t, t), and each
        entry's row): the filtering's weights are symmetric, so a pass computes each pair once.
    corner_columns : (9 t,) the columns k n + v of each triangle's corners v and coordinates k.
    faces_at : (n,) the number of triangles around each vertex, |F_i|.
    border : (n,) bool, the vertices on an edge of one triangle.
    across : (t, 3) the triangle across each triangle's edge from corner k to corner k + 1 (itself on an
        open border; one of them where more than two triangles share the edge).
    """

    def __init__(self, triangles, n_vertices):
        to_end(self._build(triangles, n_vertices))

    @classmethod
    def in_slices(cls, triangles, n_vertices):
        """The rings built in slices: a generator yielding after each stage (each a second or so at a
        million triangles), returning the rings."""
        rings = cls.__new__(cls)
        yield from rings._build(triangles, n_vertices)
        return rings

    def _build(self, triangles, n_vertices):
        t = triangles.shape[0]
        index = np.int32 if max(t, n_vertices) < np.iinfo(np.int32).max // 9 else np.int64
        rows = triangles.ravel().astype(index)
        columns = np.repeat(np.arange(t, dtype=index), 3)
        self.incidence = sp.csr_matrix((np.ones(rows.size), (rows, columns)), shape=(n_vertices, t))
        self.incidence.sum_duplicates()
        self.incidence.data[:] = 1.0  # a triangle with a repeated corner counts once at that vertex
        pattern = (self.incidence.T @ self.incidence).tocsr()
        pattern.sort_indices()
        yield
        self.indptr, self.indices = pattern.indptr, pattern.indices
        self.counts = np.diff(self.indptr)
        self.ring = sp.csr_matrix((np.ones(self.indices.size), self.indices, self.indptr), shape=(t, t))
        self.upper_rows = np.repeat(np.arange(t, dtype=self.indices.dtype), self.counts)
        above = self.indices > self.upper_rows
        self.upper_rows, self.upper_indices = self.upper_rows[above], self.indices[above]
        self.upper_indptr = np.zeros(t + 1, dtype=self.indices.dtype)  # one index type, as SciPy's kernels need
        np.cumsum(np.bincount(self.upper_rows, minlength=t), out=self.upper_indptr[1:])
        self.corner_columns = (triangles.astype(index)[:, :, None] + n_vertices * np.arange(3, dtype=index)).ravel()
        yield
        # Each triangle's edges (its corners k, k + 1) as sorted vertex pairs, sorted by pair: a pair met twice
        # is an edge between two triangles, a pair met once an open border (its umbrella leans inwards).
        pairs = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1).astype(np.int64)
        keys = pairs[:, 0] * n_vertices + pairs[:, 1]
        order = np.argsort(keys, kind="stable")
        ordered = keys[order]
        same = ordered[1:] == ordered[:-1]
        first, second = order[:-1][same], order[1:][same]
        self.across = np.repeat(np.arange(t, dtype=index), 3)  # a border edge's other triangle: itself
        self.across[first], self.across[second] = second // 3, first // 3
        self.across = self.across.reshape(t, 3)
        alone = ~(np.r_[same, False] | np.r_[False, same])
        self.border = np.zeros(n_vertices, dtype=bool)
        self.border[pairs[order[alone]].ravel()] = True
        self.faces_at = np.diff(self.incidence.indptr)
        self.triangles = triangles
        yield


def _unit(vectors, good=None):
    """(k, 3) unit vectors, (0, 0, 0) for a zero one; fills the bool mask ``good`` of the non-zero ones."""
    lengths = np.sqrt(np.einsum("ij,ij->i", vectors, vectors))
    good = np.greater(lengths, 0.0, out=good)
    np.divide(1.0, lengths, out=lengths, where=good)
    if not good.all():  # zero, or not a number
        lengths[~good] = 0.0
    return vectors * lengths[:, None]


def guidance_normals(normals, rings):
    """Zhang, Deng, Zhang, Bouaziz and Liu 2015's guidance ("Guided Mesh Normal Filtering"): each face takes
    the mean normal of the most consistent patch it lies in. The patches are the face rings (the faces
    sharing a vertex with face j, P_j) and, smaller, the vertex rings (the faces around vertex v, P_v):
    in a strip at most two or three faces wide between two creases (a thin plate's rim) every face ring
    reaches across a crease, the ring of a vertex inside the strip does not. A patch's consistency is
    H = D R, small for a patch on one side of every crease: D = max_{a in P} (1 - n_a . m), the spread
    of its normals around their unit mean m, and R = max_{a in P} s_a / (1e-9 + sum_{a in P} S_a), its
    steepest edge against the sum of all, with s_a and S_a the largest and the sum of |n_a - n_b| over
    the triangles b across a's edges. Face i takes m of the patch of smallest H among those containing
    it: the face rings of its ring's faces (the pattern is symmetric) and the vertex rings of its corners,
    a vertex ring's H counted ``VERTEX_RING_WEIGHT`` times (a max over half as many faces is smaller on
    noise alone); on a tie the first face ring, then the first corner. Noise tilts single faces by nearly
    as much as a crease turns, but the mean of a patch on one side is steady: the filter's weights
    compare these. At a corner every patch is mixed, and the guidance is a blend of the sides.

    Blocked over rows of the ring pattern (about 13 entries per face): its gathers stay in cache."""
    t = normals.shape[0]
    indptr, indices = rings.indptr, rings.indices
    planar = np.ascontiguousarray(normals.T, dtype=np.float64)
    means = _unit(rings.ring @ normals)
    mean_planar = np.ascontiguousarray(means.T)
    steep, summed = np.zeros(t), np.zeros(t)
    for k in range(3):
        other = rings.across[:, k]
        step = np.zeros(t)
        for c in range(3):
            step += (planar[c] - planar[c].take(other)) ** 2
        np.sqrt(step, out=step)
        np.maximum(steep, step, out=steep)
        summed += step
    spread, steepest = np.empty(t), np.empty(t)
    blocks = _row_blocks(indptr, t)
    for a, b in blocks:
        columns, starts = indices[indptr[a] : indptr[b]], indptr[a:b] - indptr[a]
        rows = np.repeat(np.arange(a, b), rings.counts[a:b])
        cosine = planar[0].take(columns) * mean_planar[0].take(rows)
        for c in (1, 2):
            cosine += planar[c].take(columns) * mean_planar[c].take(rows)
        spread[a:b] = np.maximum.reduceat(1.0 - cosine, starts)
        steepest[a:b] = np.maximum.reduceat(steep.take(columns), starts)
    consistency = spread * steepest / (1e-9 + rings.ring @ summed)
    chosen, best = np.empty(t, dtype=indices.dtype), np.empty(t)
    for a, b in blocks:
        columns, starts = indices[indptr[a] : indptr[b]], indptr[a:b] - indptr[a]
        counts = rings.counts[a:b]
        candidates = consistency.take(columns)
        best[a:b] = np.minimum.reduceat(candidates, starts)
        place = np.where(candidates <= np.repeat(best[a:b], counts), np.arange(columns.size), columns.size)
        chosen[a:b] = columns[np.minimum.reduceat(place, starts)]
    guidance = means[chosen]
    vertex_means, vertex_consistency = _vertex_ring_consistency(normals, rings, steep, summed)
    corner_consistency = VERTEX_RING_WEIGHT * vertex_consistency[rings.triangles]
    corner = np.argmin(corner_consistency, axis=1)
    smaller = np.flatnonzero(np.take_along_axis(corner_consistency, corner[:, None], axis=1)[:, 0] < best)
    guidance[smaller] = vertex_means[rings.triangles[smaller, corner[smaller]]]
    return guidance


def _vertex_ring_consistency(normals, rings, steep, summed):
    """The unit mean normal and the consistency H (``guidance_normals``) of each vertex's ring of faces;
    H = inf for a vertex of no face."""
    incidence = rings.incidence
    n = incidence.shape[0]
    means = _unit(incidence @ normals)
    starts = incidence.indptr[:-1]
    around = np.flatnonzero(rings.faces_at > 0)
    rows = np.repeat(np.arange(n), rings.faces_at)
    columns = incidence.indices
    cosine = normals[:, 0].take(columns) * means[:, 0].take(rows)
    for c in (1, 2):
        cosine += normals[:, c].take(columns) * means[:, c].take(rows)
    consistency = np.full(n, np.inf)
    spread = np.maximum.reduceat(1.0 - cosine, starts[around])
    steepest = np.maximum.reduceat(steep.take(columns), starts[around])
    consistency[around] = spread * steepest / (1e-9 + (incidence @ summed)[around])
    return means, consistency


def nearest_plane_normals(points, normals, rings):
    """Each face's normal replaced by the normal n_j of the face j of its ring (itself included) whose plane,
    through j's centroid c_j, lies nearest its corners: least sum_k (n_j . (x_k - c_j))^2 (the first j
    on a tie). Where filtering leaves a row of faces along a crease between the two sides' normals,
    these faces take the side their corners lie on: the crease stays one edge, not a rounded strip.

    Blocked over rows of the ring pattern, as ``guidance_normals``."""
    t = normals.shape[0]
    indptr, indices = rings.indptr, rings.indices
    corners = np.ascontiguousarray(points[rings.triangles].transpose(1, 2, 0), dtype=np.float64)  # (3, 3, t)
    planar = np.ascontiguousarray(normals.T, dtype=np.float64)
    centroids = corners.mean(axis=0)
    offsets = np.einsum("kt,kt->t", planar, centroids)  # n_j . c_j
    chosen = np.empty(t, dtype=indices.dtype)
    for a, b in _row_blocks(indptr, t):
        columns, starts = indices[indptr[a] : indptr[b]], indptr[a:b] - indptr[a]
        rows = np.repeat(np.arange(a, b), rings.counts[a:b])
        candidate = [row.take(columns) for row in planar]
        shift = offsets.take(columns)
        cost = np.zeros(columns.size)
        for corner in corners:
            distance = candidate[0] * corner[0].take(rows) - shift
            for c in (1, 2):
                distance += candidate[c] * corner[c].take(rows)
            cost += distance * distance
        best = np.repeat(np.minimum.reduceat(cost, starts), rings.counts[a:b])
        place = np.where(cost <= best, np.arange(columns.size), columns.size)
        chosen[a:b] = columns[np.minimum.reduceat(place, starts)]
    return normals[chosen]


def _row_blocks(indptr, t):
    """(first, end) row ranges of a CSR pattern with about ``_BLOCK`` entries each."""
    cuts = np.searchsorted(indptr, np.arange(_BLOCK, indptr[-1], _BLOCK))
    bounds = np.unique(np.concatenate([[0], cuts, [t]]))
    return [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]


def filter_normals(normals, rings, cos_threshold, iterations=NORMAL_ITERATIONS, guidance=None):
    """``filter_steps`` run to its end: the filtered (t, 3) normals."""
    return to_end(filter_steps(normals, rings, cos_threshold, iterations, guidance))


def filter_steps(normals, rings, cos_threshold, iterations=NORMAL_ITERATIONS, guidance=None):
    """Sun et al.'s normal filtering, ``iterations`` passes: n_i <- normalize(sum_j w_ij n_j) over the faces j
    sharing a vertex with i (i included), w_ij = (n_i . n_j - T)^2 where n_i . n_j > T, else 0. A face with
    no other face of its ring within the angle (noise tilted it away from all of them) takes the plain mean
    of its ring's normals instead, where that mean is at least a tenth of a unit long (the ring is no corner
    of its own, as a tetrahedron's is): kept as it is, it would be a crease of one face, and the fitting would
    turn it over. A face whose sum vanishes keeps its normal. A generator: yields after each pass, returns
    the normals.

    ``guidance``: (t, 3) unit normals (``guidance_normals``) whose cosines give the weights and the lonely
    faces instead of the filtered normals' own, w_ij = (g_i . g_j - T)^2: the weights are then fixed for
    all the passes, and computed once.

    w_ij = w_ji: a pass computes the weights of the pairs i < j only, in blocks of rows that stay in cache,
    and sums each block both ways at once (its rows of the upper triangle's CSR, and the same arrays read
    as columns of the lower's CSC). A fourth
    column of ones gives each face's sum of the weights of the others: 0 exactly when none is within
    the angle."""
    t = normals.shape[0]
    rows, columns, indptr = rings.upper_rows, rings.upper_indices, rings.upper_indptr
    m = columns.size
    weights = np.empty(m)
    stacked = np.empty((t, 4))  # the normals and a column of ones
    stacked[:, :3] = normals
    stacked[:, 3] = 1.0
    planar = np.ascontiguousarray(normals.T, dtype=np.float64)  # a coordinate at a time: 1-D gathers are fast
    guided = guidance is not None
    judged = np.ascontiguousarray(guidance.T, dtype=np.float64) if guided else planar  # the weights' cosines
    # Every face-sized array of a pass is allocated once: fresh ones of millions of entries cost page faults.
    summed, total = np.empty((t, 4)), np.empty((3, t))
    near, product = np.empty(t), np.empty(t)
    similar, good = np.empty(t, dtype=bool), np.empty(t, dtype=bool)
    # Blocks of whole rows (faces) with about _BLOCK pairs each: a block's weights are summed both ways
    # while they are in cache.
    cuts = np.searchsorted(indptr, np.arange(_BLOCK, m, _BLOCK))
    bounds = np.unique(np.concatenate([[0], cuts, [t]]))
    blocks = [(int(a), int(b), slice(int(indptr[a]), int(indptr[b]))) for a, b in zip(bounds[:-1], bounds[1:])]
    local = [indptr[a : b + 1] - indptr[a] for a, b, _ in blocks]
    widest = max((block.stop - block.start for _, _, block in blocks), default=0)
    buffer = np.empty((4, widest))

    def weigh(block):  # the weights of a block of pairs
        r, c = rows[block], columns[block]
        cosine, product, mine, theirs = buffer[:, : r.size]
        # mode="clip" (the indices are in range) lets take fill ``out`` without a copy of its own
        np.multiply(judged[0].take(r, out=mine, mode="clip"), judged[0].take(c, out=theirs, mode="clip"), out=cosine)
        for k in (1, 2):
            np.multiply(
                judged[k].take(r, out=mine, mode="clip"), judged[k].take(c, out=theirs, mode="clip"), out=product
            )
            cosine += product
        cosine -= cos_threshold
        np.maximum(cosine, 0.0, out=cosine)
        np.multiply(cosine, cosine, out=weights[block])

    def pair_sums(weighing):  # summed = (W + W^T) @ stacked, W the weights of the pairs i < j
        summed[...] = 0.0
        if _csr_matvecs is None:  # the public products, on the whole matrices
            for _, _, block in blocks if weighing else ():
                weigh(block)
            summed[...] += sp.csr_matrix((weights, columns, indptr), shape=(t, t)) @ stacked
            summed[...] += sp.csc_matrix((weights, columns, indptr), shape=(t, t)) @ stacked
            return
        into, read = summed.reshape(-1), stacked.reshape(-1)
        for (a, b, block), block_indptr in zip(blocks, local):
            if weighing:
                weigh(block)
            # y += A x for the block's rows of W, and for its columns of W^T (the same arrays read as CSC)
            _csr_matvecs(b - a, t, 4, block_indptr, columns[block], weights[block], read, summed[a:b].reshape(-1))
            _csc_matvecs(t, b - a, 4, block_indptr, columns[block], weights[block], stacked[a:b].reshape(-1), into)

    def squares(vectors, out):  # x^2 + y^2 + z^2 of coordinate rows, in the order of the pairs' cosines
        np.multiply(vectors[0], vectors[0], out=out)
        for k in (1, 2):
            out += np.multiply(vectors[k], vectors[k], out=product)
        return out

    own = lonely = None  # guided: each face's own weight and the lonely faces, fixed for all the passes
    for _ in range(iterations):
        pair_sums(own is None)
        if own is None:
            squares(judged, near)  # each face's cosine with itself
            near -= cos_threshold
            np.maximum(near, 0.0, out=near)
            np.greater(near, 0.0, out=similar)
            lonely = _lonely(judged, rings, cos_threshold, similar, summed[:, 3])
            near *= near
            if guided:
                own = near.copy()
        total[:] = summed[:, :3].T  # coordinate rows: element-wise work on (t, 3) columns is slow
        for k in range(3):
            total[k] += np.multiply(near if own is None else own, planar[k], out=product)
        if lonely.size:
            ring = rings.ring[lonely] @ stacked  # the sums of the ring's normals, and its size
            mean = ring[:, :3] / ring[:, 3:]
            agree = np.einsum("ij,ij->i", mean, mean) >= 0.01  # a ring that is no corner of its own
            total[:, lonely[agree]] = mean[agree].T
        lengths = np.sqrt(squares(total, near), out=near)
        np.greater(lengths, 0.0, out=good)  # else the face keeps its normal
        if good.all():
            np.divide(1.0, lengths, out=lengths)
            np.multiply(total, lengths, out=planar)
        else:
            np.divide(1.0, lengths, out=lengths, where=good)
            np.multiply(total, lengths, out=planar, where=good)
        stacked[:, :3] = planar.T
        yield
    return planar.T.copy()


def _lonely(planar, rings, cos_threshold, similar_self, others):
    """The faces with at most one face of their ring (itself included) within the angle: those within it
    of themselves with a zero sum of the others' weights, and those that are not (a zero normal, or an
    angle so small that its cosine rounds to 1) with at most one other face within it. Overwrites
    ``similar_self``."""
    odd = np.flatnonzero(~similar_self)
    lonely = np.logical_and(similar_self, others == 0.0, out=similar_self)
    if odd.size:
        ring = rings.ring[odd]
        mine, theirs = np.repeat(odd, np.diff(ring.indptr)), ring.indices
        cosine = planar[0, mine] * planar[0, theirs]  # in the order of the pairs' cosines
        for k in (1, 2):
            cosine += planar[k, mine] * planar[k, theirs]
        similar = np.add.reduceat((cosine > cos_threshold).astype(np.int64), ring.indptr[:-1])
        lonely[odd] = similar <= 1
    return np.flatnonzero(lonely)


def fit_vertices(points, normals, rings, step_share, iterations=FIT_ITERATIONS):
    """``fit_steps`` run to its end: the fitted (n, 3) positions."""
    return to_end(fit_steps(points, normals, rings, step_share, iterations))


def fit_steps(points, normals, rings, step_share, iterations=FIT_ITERATIONS):
    """Sun et al.'s vertex update, ``iterations`` passes: x_i += share_i / |F_i| sum_f n_f n_f^T (c_f - x_i)
    over the triangles f around i (``step_share``: (n,) 0 for vertices that stay, else the influence).

    On the coordinates as one (3n,) vector (x's, then y's, then z's) a pass is five products with matrices
    fixed for the step: the (t, 3n) one of each triangle's normal at its corners' coordinates (3 n_f . c_f),
    per coordinate k the (n, t) one of n_f[k] share_i / (3 |F_i|) at each vertex's triangles, and the
    (3n, 3n) one of -share_i / |F_i| sum_f n_f n_f^T at each vertex's coordinates. A generator: yields once
    the matrices are built and after every ``FIT_SLICE`` passes but the last, returns the positions."""
    triangles, incidence = rings.triangles, rings.incidence
    t, n = triangles.shape[0], points.shape[0]
    scale = np.divide(step_share, rings.faces_at, out=np.zeros(step_share.size), where=rings.faces_at > 0)
    outer = (normals[:, :, None] * normals[:, None, :]).reshape(-1, 9)
    tensor = (incidence @ outer).reshape(-1, 3, 3)  # sum_f n_f n_f^T per vertex
    dots = sp.csr_matrix(
        (np.tile(normals, (1, 3)).ravel(), rings.corner_columns, np.arange(0, 9 * t + 1, 9)), shape=(t, 3 * n)
    )
    share = np.repeat(scale / 3.0, rings.faces_at)  # at each of the incidence's entries
    pulls = [
        sp.csr_matrix((row.take(incidence.indices) * share, incidence.indices, incidence.indptr), shape=(n, t))
        for row in np.ascontiguousarray(normals.T)
    ]
    columns = np.arange(n)[None, :, None] + n * np.arange(3)[None, None, :]  # vertex i's x, y, z
    own = sp.csr_matrix(
        (
            (-scale[None, :, None] * tensor.transpose(1, 0, 2)).ravel(),
            np.broadcast_to(columns, (3, n, 3)).ravel(),
            np.arange(0, 9 * n + 1, 3),
        ),
        shape=(3 * n, 3 * n),
    )
    flat = np.array(points.T, dtype=np.float64).reshape(-1)
    moved, offsets = np.empty_like(flat), np.empty(t)  # allocated once, as the filtering's
    yield  # building the matrices takes as long as a few passes
    for done in range(1, iterations + 1):
        offsets[:] = 0.0
        _add_product(dots, flat, offsets)
        moved[:] = flat
        for k, pull in enumerate(pulls):
            _add_product(pull, offsets, moved[k * n : (k + 1) * n])
        _add_product(own, flat, moved)
        flat, moved = moved, flat
        if done % FIT_SLICE == 0 and done < iterations:
            yield
    return np.ascontiguousarray(flat.reshape(3, n).T)


def _add_product(matrix, x, y):
    """y += matrix @ x for a CSR matrix and vectors: by SciPy's private kernel (no fresh array), or the
    public product where it is missing."""
    if _csr_matvec is None:
        y += matrix @ x
    else:
        _csr_matvec(*matrix.shape, matrix.indptr, matrix.indices, matrix.data, x, y)


def _mean_of_neighbours(values, operator):
    """mean over adj(i) of ``values`` (n, 3); a vertex without neighbours gets its own value."""
    degree = operator.degree
    weights = np.repeat(1.0 / np.maximum(degree, 1), degree)
    average = sp.csr_matrix((weights, operator.indices, operator.indptr), shape=(operator.n_vertices,) * 2)
    out = average @ values
    lonely = degree == 0
    out[lonely] = values[lonely]
    return out


class SharpSmoothing:
    """Keep Sharp Edges in slices: everything is checked on construction; ``steps(chunk)`` runs ``chunk``
    steps at a time (all if None) and yields the fraction done; ``result()`` gives the positions.

    Parameters
    ----------
    positions : (n, 3) float32 or float64
        Never modified; the result has the same shape and dtype.
    faces : (f, k) integer array, list of faces, or (offsets, corner_verts)
        The faces (any polygons: fanned into triangles).
    sharpness_angle : float, radians in (0, pi)
        Faces meeting at more than this angle keep their crease.
    iterations : int >= 0
        Steps (each ``NORMAL_ITERATIONS`` filtering and ``FIT_ITERATIONS`` fitting passes, one push-back).
    alpha, beta : floats in [0, 1]
        The push-back's weights (paper section 4).
    fixed : bool mask or vertex indices, optional
        Vertices that never move (bit for bit).
    influence : (n,) floats in [0, 1], optional
        Each vertex's share of every step's move (0 stays bit for bit).
    max_deviation : float >= 0, or (n,) floats
        The farthest a vertex may end a step from its input position (0: no limit).
    tolerance : float >= 0
        Stop once a step's largest move is below this times the bounding-box diagonal.
    operator : Umbrella, optional
        The mesh's core.umbrella_operator (the push-back's neighbours); built from the faces if None.
    push_back : bool
        False: Sun et al.'s two steps alone, without HC's push-back.
    guided : bool
        True: the filter's weights compare guidance normals, and the faces take their nearest planes (what
        core.MeshSmoother runs where core.mesh.noise finds noise). False: Sun et al.'s filter alone.
        The guidance is for meshes fine enough that most faces lie in a patch on one side of every crease
        (scans): on a coarse model (a cube of 12 triangles) every face is at a corner and it blends the sides.

    Examples
    --------
    >>> import numpy as np, core
    >>> from core.mesh.sharp_edges import SharpSmoothing
    >>> positions = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    >>> faces = [[0, 1, 3, 2], [2, 3, 7, 6], [6, 7, 5, 4], [4, 5, 1, 0], [2, 6, 4, 0], [7, 3, 1, 5]]
    >>> run = SharpSmoothing(positions, faces, iterations=2)
    >>> [round(f, 2) for f in run.steps(chunk=1)]
    [0.5, 1.0]
    >>> bool(np.allclose(run.result(), positions))  # a cube is all planes and creases: nothing to smooth
    True
    """

    def __init__(
        self,
        positions: ArrayLike,
        faces,
        *,
        sharpness_angle: float = DEFAULT_SHARPNESS_ANGLE,
        iterations: int = 1,
        alpha: float = DEFAULT_ALPHA,
        beta: float = DEFAULT_BETA,
        fixed: ArrayLike | None = None,
        influence: ArrayLike | None = None,
        max_deviation: float | np.ndarray = 0.0,
        tolerance: float = 0.0,
        operator: Umbrella | None = None,
        push_back: bool = True,
        guided: bool = False,
    ) -> None:
        self.positions = check_positions(positions)
        n = self.positions.shape[0]
        self.triangles = check_triangles(faces, n)
        self.cos_threshold = math.cos(check_sharpness_angle(sharpness_angle))
        self.iterations = check_iterations(iterations)
        self.alpha = check_unit_interval(alpha, "alpha")
        self.beta = check_unit_interval(beta, "beta")
        self.fixed = check_fixed(fixed, n)
        self.influence = check_influence(influence, n)
        self.max_deviation = check_max_deviation(max_deviation, n)
        self.tolerance = check_tolerance(tolerance)
        self.push_back = bool(push_back)
        self.guided = bool(guided)
        if operator is None:
            edges = self.triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
            operator = umbrella_operator(edges, n)
        elif not isinstance(operator, Umbrella) or operator.n_vertices != n:
            raise ValueError(f"operator must be a core.umbrella_operator built for {n} vertices")
        self.operator = operator
        share = np.ones(n) if self.influence is None else self.influence.copy()
        share[self.fixed] = 0.0
        self.share = share
        self.still = share <= 0.0
        self.moving = (~self.still).astype(np.float64)  # the fitting moves these fully; the step's end scales
        self.original = self.positions.astype(np.float64)
        self.current = self.original.copy()
        self.rings = None
        self.done = 0
        self.stopped_early = False

    def steps(self, chunk: int | None = None) -> Iterator[float]:
        """Run the steps left, ``chunk`` at a time, yielding the fraction done after each slice; on meshes of
        ``PASS_SLICES_FROM`` triangles or more also between the stages of building the face rings (yielding
        0.0) and within a step (at most ``STEP_SLICES`` slices: after the guidance, each filtering pass, each
        choice of the nearest planes, each fitting's set-up, every ``FIT_SLICE`` fitting passes and each
        unfolding round but the last; a step takes seconds there)."""
        chunk = self.iterations if chunk is None else max(1, int(chunk))
        passes = self.triangles.shape[0] >= PASS_SLICES_FROM
        if self.rings is None and self.iterations > 0:
            building = FaceRings.in_slices(self.triangles, self.positions.shape[0])
            self.rings = (yield from _counted(building, itertools.repeat(0.0))) if passes else to_end(building)
        while self.done < self.iterations and not self.stopped_early:
            for _ in range(min(chunk, self.iterations - self.done)):
                for k in self._step():
                    if passes:
                        yield (self.done + k / STEP_SLICES) / self.iterations
                if self.stopped_early:
                    break
            yield self.done / self.iterations
        if self.iterations == 0:
            yield 1.0

    def advance(self):
        """One step: filter the normals, fit the vertices, relax, push back, unfold, keep to the limit."""
        to_end(self._step())

    def _step(self):
        """``advance`` as a generator, yielding the slices done (of ``STEP_SLICES``) between them."""
        if self.rings is None:
            self.rings = FaceRings(self.triangles, self.positions.shape[0])
        start = self.current
        slices = itertools.count(1)  # the slice numbers this step yields, in order
        normals = before = face_normals(start, self.triangles)
        guidance = None
        if self.guided:
            guidance = guidance_normals(normals, self.rings)
            yield next(slices)
        filtering = filter_steps(normals, self.rings, self.cos_threshold, NORMAL_ITERATIONS, guidance)
        normals = yield from _counted(filtering, slices)
        if self.guided:
            normals = nearest_plane_normals(start, normals, self.rings)
            yield next(slices)
        fitting = fit_steps(start, normals, self.rings, self.moving, FIT_ITERATIONS)
        moved = yield from _counted(fitting, slices)
        if self.guided:  # the fitted corners, much less noisy, place the faces on their sides again
            normals = nearest_plane_normals(moved, normals, self.rings)
            yield next(slices)
            refitting = fit_steps(moved, normals, self.rings, self.moving, REFIT_ITERATIONS)
            moved = yield from _counted(refitting, slices)
        if TANGENTIAL:
            _relax(moved, normals, self.rings, self.operator, self.cos_threshold, self.still)
        if self.push_back:
            pushed = moved - (self.alpha * self.original + (1.0 - self.alpha) * start)
            pushed[self.still] = 0.0
            moved -= self.beta * pushed + (1.0 - self.beta) * _mean_of_neighbours(pushed, self.operator)
        if self.influence is not None:  # vertex i ends the step at q_i + w_i (p_i - q_i), as in core.smoothing
            moved = start + self.share[:, None] * (moved - start)
        moved[self.still] = start[self.still]
        unfolding = _unfold(moved, start, before, self.triangles, normals, _unit(self.rings.ring @ normals))
        yield from _counted(unfolding, slices)
        if np.any(self.max_deviation):
            project_rows_within(moved, self.original, self.max_deviation)
        self.done += 1
        if self.tolerance:
            largest = float(np.sqrt(np.max(np.einsum("ij,ij->i", moved - start, moved - start), initial=0.0)))
            self.stopped_early = largest < self.tolerance * bbox_diagonal(self.original)
        self.current = moved

    def result(self) -> np.ndarray:
        """The positions after the steps run so far, in the input's dtype; still vertices bit for bit."""
        out = self.current.astype(self.positions.dtype)
        out[self.still] = self.positions[self.still]
        return out


def _relax(points, normals, rings, operator, cos_threshold, still):
    """Move, in place, each vertex off the open borders whose faces all agree (their mean filtered normal
    within half the angle of every one: no crease) ``TANGENTIAL`` of the way to its neighbours' mean
    along its tangent plane: evens out the triangles that noise along the surface made uneven, without
    moving the surface."""
    around = rings.incidence @ normals
    length = np.sqrt(np.einsum("ij,ij->i", around, around))
    counts = np.maximum(rings.faces_at, 1)
    flat = (length / counts > math.sqrt((1.0 + cos_threshold) / 2.0)) & ~still & ~rings.border
    normal = around[flat] / length[flat, None]
    umbrella = _mean_of_neighbours(points, operator)[flat] - points[flat]
    umbrella -= np.einsum("ij,ij->i", umbrella, normal)[:, None] * normal
    points[flat] += TANGENTIAL * umbrella


def _counted(generator, slices):
    """``yield from _counted(g, slices)``: g's value, yielding the next number of ``slices`` (an iterator) for
    each of g's slices."""
    while True:
        try:
            next(generator)
        except StopIteration as done:
            return done.value
        yield next(slices)


def _unfold(points, start, before, triangles, normals, around, rounds=FOLD_ROUNDS):
    """Halve, in place, the step's move of the corners of every triangle it turned over (its normal now more
    than 90° from its filtered normal, or from the mean ``around`` of its ring's, and its normal ``before``
    the step not), ``rounds`` times at most: the fitting moves along the faces' normals, and on curved parts
    those moves add up along the surface. A triangle already turned over before the step (noise folded it)
    keeps its corners' moves: the step is what unfolds it. A generator: yields after each round that leaves
    rounds to go."""
    folded = _turned(before, normals, around)
    faces = slice(None)  # the triangles whose corners moved: all at first, then those of the halved corners
    turned = np.zeros(triangles.shape[0], dtype=bool)
    halved = np.zeros(points.shape[0], dtype=bool)
    for round_ in range(rounds):
        now = face_normals(points, triangles[faces])
        turned[faces] = _turned(now, normals[faces], around[faces]) & ~folded[faces]
        if not turned.any():
            return
        halved[:] = False
        halved[triangles[turned]] = True
        corners = np.flatnonzero(halved)
        points[corners] = start[corners] + 0.5 * (points[corners] - start[corners])
        faces = np.flatnonzero(halved[triangles].any(axis=1))
        if faces.size > triangles.shape[0] // 4:  # gathering most of them costs more than measuring all
            faces = slice(None)
        if round_ + 1 < rounds:
            yield


def _turned(now, normals, around):
    """The triangles whose normals ``now`` lie more than 90° from their filtered ``normals`` or ring means."""
    return (np.einsum("ij,ij->i", now, normals) < 0.0) | (np.einsum("ij,ij->i", now, around) < 0.0)


def sharp_smooth(positions: ArrayLike, faces, **options) -> np.ndarray:
    """Keep Sharp Edges run to the end: ``SharpSmoothing(positions, faces, **options)``'s result.

    Examples
    --------
    >>> import numpy as np
    >>> from core.mesh.sharp_edges import sharp_smooth
    >>> u, v = np.meshgrid(np.linspace(0, 1, 12), np.linspace(0, 1, 12))
    >>> grid = np.arange(144).reshape(12, 12)
    >>> quads = np.stack([grid[:-1, :-1], grid[:-1, 1:], grid[1:, 1:], grid[1:, :-1]], -1).reshape(-1, 4)
    >>> flat = np.c_[u.ravel(), v.ravel(), np.zeros(144)]
    >>> noisy = flat + [0, 0, 0.01] * np.random.default_rng(1).normal(size=(144, 1))
    >>> smoothed = sharp_smooth(noisy, quads, iterations=3)
    >>> bool(smoothed[:, 2].std() < 0.3 * noisy[:, 2].std())
    True
    """
    run = SharpSmoothing(positions, faces, **options)
    for _ in run.steps():
        pass
    return run.result()
