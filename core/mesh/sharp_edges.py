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
sharing a vertex with each face, about 13: the corners' pattern times the incidence), built once per run
in blocks of rows, and every pass over it works a chunk of rows at a time (its gathers in cache), the
chunks shared out over the threads (core.parallel). The guided filter keeps one single-precision weight
a pair for its passes; the plain one weighs each chunk as it sums it. A fitting pass sums each
triangle's corners (one product with the corners' pattern) and sums around each vertex (one product
with the incidence).
Fixed vertices never move (their positions still place their faces' planes); ``influence`` scales each
step's move, as core.smoothing scales an iteration's.
"""

import itertools
import math
from collections.abc import Iterator

import numpy as np
import scipy.sparse as sp

try:  # the kernel behind ``csr_matrix @ x`` (y += A x); private: a public fallback
    from scipy.sparse._sparsetools import csr_matvec as _csr_matvec

    _probe = (np.array([0, 1], dtype=np.int32), np.zeros(1, dtype=np.int32), np.ones(1), np.ones(1), np.zeros(1))
    _csr_matvec(1, 1, *_probe)
    _csr_matvec(1, 1, *_probe)
    if _probe[-1][0] != 2.0:
        raise ValueError("y += A x expected")
except (ImportError, TypeError, ValueError):  # SciPy without this kernel, or with another signature
    _csr_matvec = None
from numpy.typing import ArrayLike

from .. import parallel
from ..adjacency import Umbrella, pair_keys, umbrella_operator
from ..geometry import SYMMETRIC_ENTRIES, face_normals, fan_triangles, project_rows_within
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
GUIDED_SLICES = 5  # within and after the guidance (guidance_steps) and after each choice of the nearest planes
STEP_SLICES = GUIDED_SLICES + NORMAL_ITERATIONS + FIT_SLICES + REFIT_SLICES + FOLD_ROUNDS  # a step's, at most
# The guidance's vertex rings (about 6 faces) count their consistency this many times against the face
# rings' (about 13): on the tuning parts at 0.5 % noise 1.5-3 leave the same dihedral error, 1 more.
VERTEX_RING_WEIGHT = 2.0
_BLOCK = BLOCK  # face pairs per chunk of the passes over the rings: their temporaries stay in cache
FILTER_DTYPE = np.float32  # the normal filtering's precision (filter_steps)


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
    triangles : (t, 3) the triangles; corners : (3, t) the same, a corner at a time (intp).
    incidence : (n, t) CSR, 1 where vertex i is a corner of triangle f.
    vertex_blocks, corner_blocks : core.parallel.RowBlocks of the incidence's pattern and of its transpose's
        (each triangle's corners, in order: a product sums them).
    indptr, indices, counts : the faces sharing a vertex with each face, itself included: a CSR pattern
        of (t, t), columns increasing, without values (each pass reads it with weights of its own).
    chunks : (first, end) row ranges of that pattern with about ``_BLOCK`` entries each: a pass works a
        chunk at a time, so its gathers stay in cache, and the chunks are shared out over the threads;
        chunk_indptrs : each chunk's indptr, from 0.
    faces_at : (n,) the number of triangles around each vertex, |F_i|.
    border : (n,) bool, the vertices on an edge of one triangle.
    across : (3, t) the triangle across each triangle's edge from corner k to corner k + 1 (itself on an
        open border; one of them where more than two triangles share the edge).
    """

    def __init__(self, triangles, n_vertices):
        to_end(self._build(triangles, n_vertices))

    @classmethod
    def in_slices(cls, triangles, n_vertices):
        """The rings built in slices: a generator yielding after each stage (a fraction of a second at a
        million triangles), returning the rings."""
        rings = cls.__new__(cls)
        yield from rings._build(triangles, n_vertices)
        return rings

    def _build(self, triangles, n_vertices):
        t = triangles.shape[0]
        self.triangles = triangles
        self.corners = np.ascontiguousarray(triangles.T, dtype=np.intp)  # NumPy's gathers take intp as it is
        columns = np.repeat(np.arange(t, dtype=np.int32 if t < 2**31 else np.int64), 3)
        self.incidence = sp.csr_matrix((np.ones(3 * t), (triangles.ravel(), columns)), shape=(n_vertices, t))
        self.incidence.sum_duplicates()
        self.incidence.data[:] = 1.0  # a triangle with a repeated corner counts once at that vertex
        self.faces_at = np.diff(self.incidence.indptr)
        self.vertex_blocks = parallel.RowBlocks(self.incidence.indptr, self.incidence.indices, t)
        index = np.int32 if 3 * t < 2**31 else np.int64  # one type for both, as SciPy's kernels need
        corner_indptr = np.arange(0, 3 * t + 1, 3, dtype=index)
        self.corner_blocks = parallel.RowBlocks(corner_indptr, triangles.astype(index).ravel(), n_vertices)
        yield
        self.indptr, self.indices = yield from _ring_pattern(self.corners, self.incidence)
        self.counts = np.diff(self.indptr)
        self.chunks = _row_blocks(self.indptr, t)
        rebased = (self.indptr[a : b + 1] - self.indptr[a] for a, b in self.chunks)
        self.chunk_indptrs = [part.astype(self.indices.dtype) for part in rebased]
        self.blocks = parallel.RowBlocks(self.indptr, self.indices, t)
        self.threads = parallel.thread_count() if self.indices.size >= parallel.MIN_WORK else 1
        yield
        self.across, self.border = _edge_neighbours(triangles, n_vertices)
        yield

    @property
    def ring(self):
        """The pattern as a (t, t) CSR of ones (made on each call: its values take as much memory as it)."""
        t = self.counts.size
        return sp.csr_matrix((np.ones(self.indices.size), self.indices, self.indptr), shape=(t, t))

    def each_chunk(self, task):
        """``task(first, end)`` for every chunk of rows, the chunks shared out over the threads in runs."""
        runs = np.array_split(np.arange(len(self.chunks)), self.threads)
        parallel.run_all([lambda run=run: [task(*self.chunks[i]) for i in run] for run in runs if run.size])

    def each_chunk_index(self, task):
        """``task(index)`` for every chunk's index in ``chunks``, the chunks shared out over the threads in runs."""
        runs = np.array_split(np.arange(len(self.chunks)), self.threads)
        parallel.run_all([lambda run=run: [task(i) for i in run] for run in runs if run.size])

    def ring_sums(self, values):
        """(k, t) sums over each face's ring of planar ``values`` (k, t) (or (t,) to (t,))."""
        out = np.empty_like(values)
        rows = out.reshape(-1, out.shape[-1])

        def combine(chunk_rows, sums):
            rows[:, chunk_rows] = sums

        self.blocks.run(lambda block: block.neighbour_sums(values, combine))
        return out

    def padded(self, first, end):
        """Rows first:end of the pattern as a (K, rows) intp array, K the longest row: entry (k, r) is row r's
        k-th column, its last column repeated past its end (the same face again: no new candidate for a
        smallest or largest value, and the first of a tie stays first); and the (K, rows) mask of the real
        entries. Row-side values then broadcast, and a reduction over the first axis is element-wise."""
        counts = self.counts[first:end]
        reach = np.arange(int(counts.max()) if counts.size else 0)[:, None]
        positions = self.indptr[first:end] + np.minimum(reach, counts - 1)
        return self.indices.take(positions).astype(np.intp), reach < counts

    def rows_of(self, rows):
        """The pattern's ``rows`` (an index array): (their columns, each row's count, each row's start)."""
        positions, counts, starts = self.entries_of(rows)
        return self.indices[positions], counts, starts

    def entries_of(self, rows):
        """The places in the pattern of its ``rows``' entries (an index array), each row's count and start."""
        counts = self.counts[rows]
        starts = np.zeros(rows.size, dtype=np.int64)
        np.cumsum(counts[:-1], out=starts[1:])
        return np.repeat(self.indptr[rows] - starts, counts) + np.arange(int(counts.sum())), counts, starts


RING_ROWS = 1 << 17  # faces per block of the rings' product: a block takes a fraction of a second


def _ring_pattern(corners, incidence):
    """The face rings' CSR pattern (indptr, indices), columns increasing: the (t, n) pattern of each
    triangle's corners times the (n, t) incidence, in blocks of rows (on the threads); a generator
    yielding after each round of blocks."""
    t, n = corners.shape[1], incidence.shape[0]
    ones = np.ones(3 * t, dtype=np.int8)  # the product's values are not used: the smallest type
    faces = sp.csr_matrix((ones, corners.T.ravel(), np.arange(0, 3 * t + 1, 3)), shape=(t, n))
    vertices = sp.csr_matrix((ones[: incidence.nnz], incidence.indices, incidence.indptr), shape=incidence.shape)

    def rows(first, end):
        product = faces[first:end] @ vertices
        product.sort_indices()
        return product.indptr, product.indices

    bounds = list(range(0, t, RING_ROWS)) + [t]
    blocks = list(zip(bounds[:-1], bounds[1:]))
    threads = parallel.thread_count()
    parts = []
    for round_ in range(0, len(blocks), threads):
        parts += parallel.run_all([lambda b=b: rows(*b) for b in blocks[round_ : round_ + threads]])
        if round_ + threads < len(blocks):
            yield
    sizes = [part[1].size for part in parts]
    index = np.int32 if sum(sizes) < 2**31 else np.int64  # one type for both, as SciPy's kernels need
    indptr = np.zeros(t + 1, dtype=index)
    np.cumsum(np.concatenate([np.diff(part[0]) for part in parts]), out=indptr[1:])
    indices = np.empty(indptr[-1], dtype=index)
    offset = 0
    for (_, part), size in zip(parts, sizes):
        indices[offset : offset + size] = part
        offset += size
    return indptr, indices


def _edge_neighbours(triangles, n_vertices):
    """(across, border) of FaceRings: each triangle's neighbour across each edge, the open border's vertices.

    Each triangle's edges (edge 3 f + k from its corner k to corner k + 1) keyed by their vertex pair, low
    end first, sorted by key: a pair met twice is an edge between two triangles, a pair met once an open
    border (its umbrella leans inwards)."""
    t = triangles.shape[0]
    start = triangles.ravel()
    end = np.empty_like(triangles)  # each corner's next: columns 1, 2, 0
    end[:, :2], end[:, 2] = triangles[:, 1:], triangles[:, 0]
    end = end.ravel()
    keys = pair_keys(start, end, n_vertices)
    order = np.argsort(keys, kind="stable")
    ordered = keys.take(order)
    same = ordered[1:] == ordered[:-1]
    first, second = order[:-1][same], order[1:][same]
    across = np.arange(3 * t) // 3  # on a border: itself
    across[first], across[second] = second // 3, first // 3
    alone = order[~(np.r_[same, False] | np.r_[False, same])]
    border = np.zeros(n_vertices, dtype=bool)
    border[start[alone]] = True
    border[end[alone]] = True
    index = np.int32 if t < 2**31 else np.int64
    return np.ascontiguousarray(across.reshape(t, 3).T, dtype=index), border


def _unit(vectors, good=None):
    """(k, 3) unit vectors, (0, 0, 0) for a zero one; fills the bool mask ``good`` of the non-zero ones."""
    lengths = np.sqrt(np.einsum("ij,ij->i", vectors, vectors))
    good = np.greater(lengths, 0.0, out=good)
    np.divide(1.0, lengths, out=lengths, where=good)
    if not good.all():  # zero, or not a number
        lengths[~good] = 0.0
    return vectors * lengths[:, None]


def _unit_planar(vectors):
    """Planar (3, t) vectors scaled, in place, to unit length; a zero one stays zero."""
    lengths = np.sqrt(np.einsum("kt,kt->t", vectors, vectors))
    good = lengths > 0.0
    np.divide(1.0, lengths, out=lengths, where=good)
    lengths[~good] = 0.0
    vectors *= lengths
    return vectors


def guidance_normals(normals, rings):
    """``guidance_steps`` run to its end: the (t, 3) guidance normals."""
    return to_end(guidance_steps(normals, rings))


def guidance_steps(normals, rings):
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

    A chunk of the ring pattern's rows at a time (FaceRings.each_chunk). A generator: yields after the
    patches' spread and after the face rings' choice (each about a third of the work), returns the (t, 3)
    guidance normals."""
    t = normals.shape[0]
    planar = np.ascontiguousarray(normals.T, dtype=np.float64)
    means = _unit_planar(rings.ring_sums(planar))
    steep, summed = np.empty(t), np.empty(t)

    def edge_steps(first, end):  # s_a and S_a over the three edges of triangles first:end
        steep[first:end], summed[first:end] = 0.0, 0.0
        for other in rings.across[:, first:end]:
            step = np.zeros(end - first)
            for c in range(3):
                step += (planar[c, first:end] - planar[c].take(other)) ** 2
            np.sqrt(step, out=step)
            np.maximum(steep[first:end], step, out=steep[first:end])
            summed[first:end] += step

    parallel.run_chunks(edge_steps, t, _FACE_CHUNK)
    spread, steepest = np.empty(t), np.empty(t)

    def patches(first, end):  # max (1 - n_a . m) = 1 - min n_a . m
        columns, _ = rings.padded(first, end)
        cosine = means[0, first:end] * planar[0].take(columns)
        for c in (1, 2):
            cosine += means[c, first:end] * planar[c].take(columns)
        spread[first:end] = 1.0 - cosine.min(axis=0)
        steepest[first:end] = steep.take(columns).max(axis=0)

    rings.each_chunk(patches)
    yield
    consistency = spread * steepest / (1e-9 + rings.ring_sums(summed))
    spread = steepest = None  # the peak of a run is here: what is no longer read goes
    chosen, best = np.empty(t, dtype=np.intp), np.empty(t)

    def most_consistent(first, end):
        columns, _ = rings.padded(first, end)
        place, best[first:end] = _first_smallest(consistency.take(columns))  # the first on a tie
        chosen[first:end] = columns[place, np.arange(end - first)]

    rings.each_chunk(most_consistent)
    guidance = np.stack([row.take(chosen) for row in means])
    yield
    consistency = chosen = means = None
    vertex_means, vertex_consistency = _vertex_ring_consistency(normals, planar, rings, steep, summed)
    weighted = VERTEX_RING_WEIGHT * vertex_consistency
    lowest = weighted.take(rings.corners[0])  # the corners' smallest, a corner at a time (no three arrays)
    for corner in rings.corners[1:]:
        np.minimum(lowest, weighted.take(corner), out=lowest)
    smaller = np.flatnonzero(lowest < best)
    lowest = lowest[smaller]
    at = [weighted.take(corner[smaller]) for corner in rings.corners[:2]]
    corner = np.where(at[0] == lowest, 0, np.where(at[1] == lowest, 1, 2))
    guidance[:, smaller] = vertex_means[:, rings.corners[corner, smaller]]  # the first corner on a tie
    return guidance.T


def _vertex_ring_consistency(normals, planar, rings, steep, summed):
    """The unit mean normals (3, n) and the consistency H (``guidance_normals``) of each vertex's ring of
    faces; H = inf for a vertex of no face. ``planar``: the normals as (3, t) rows. A chunk of vertices at a
    time."""
    incidence = rings.incidence
    n = incidence.shape[0]
    planar_means = np.ascontiguousarray(_unit(incidence @ normals).T)
    summed_around = incidence @ summed
    consistency = np.full(n, np.inf)

    def chunk(first, end):  # max (1 - n_a . m) = 1 - min n_a . m
        counts = rings.faces_at[first:end]
        starts = incidence.indptr[first:end] - incidence.indptr[first]
        columns = incidence.indices[incidence.indptr[first] : incidence.indptr[end]].astype(np.intp)
        if columns.size == 0:
            return
        cosine = planar[0].take(columns) * np.repeat(planar_means[0, first:end], counts)
        for c in (1, 2):
            cosine += planar[c].take(columns) * np.repeat(planar_means[c, first:end], counts)
        around = np.flatnonzero(counts > 0)
        spread = 1.0 - np.minimum.reduceat(cosine, starts[around])
        steepest = np.maximum.reduceat(steep.take(columns), starts[around])
        consistency[first + around] = spread * steepest / (1e-9 + summed_around[first + around])

    parallel.run_chunks(chunk, n, _FACE_CHUNK)
    return planar_means, consistency


def nearest_plane_normals(points, normals, rings):
    """Each face's normal replaced by the normal n_j of the face j of its ring (itself included) whose plane,
    through j's centroid c_j, lies nearest its corners: least sum_k (n_j . (x_k - c_j))^2 (the first j
    on a tie). Where filtering leaves a row of faces along a crease between the two sides' normals,
    these faces take the side their corners lie on: the crease stays one edge, not a rounded strip.

    The sum is taken as sum_k (n_j . x_k - o_j)^2 with o_j = n_j . c_j: per pair the candidate's normal and
    offset (gathered), face i's corners broadcast. Positions about their mean: the offsets stay of the
    mesh's size. A chunk of the ring pattern's rows at a time (``FaceRings.padded``)."""
    t = normals.shape[0]
    x = np.ascontiguousarray(points.T, dtype=np.float64)
    x = x - x.mean(axis=1, keepdims=True)
    planar = np.ascontiguousarray(normals.T, dtype=np.float64)
    offsets = np.empty(t)  # n_j . c_j

    def plane_offsets(faces, corner_sums):
        corner_sums /= 3.0
        offsets[faces] = np.einsum("kt,kt->t", planar[:, faces], corner_sums)

    rings.corner_blocks.run(lambda block: block.neighbour_sums(x, plane_offsets))
    chosen = np.empty(t, dtype=np.intp)

    def nearest(first, end):
        columns, _ = rings.padded(first, end)
        candidate = [row.take(columns) for row in planar]
        offset = offsets.take(columns)
        cost, residual = np.zeros(columns.shape), np.empty(columns.shape)
        for corner in rings.corners[:, first:end]:
            np.multiply(candidate[0], x[0].take(corner), out=residual)
            for c in (1, 2):
                residual += candidate[c] * x[c].take(corner)
            residual -= offset
            residual *= residual
            cost += residual
        chosen[first:end] = columns[_first_smallest(cost)[0], np.arange(end - first)]

    rings.each_chunk(nearest)
    return np.take(normals, chosen, axis=0)  # twice as fast as normals[chosen]


_FACE_CHUNK = 1 << 15  # triangles per chunk of the per-triangle work: its temporaries stay in cache


def _first_smallest(values):
    """(the index along the first axis of each column's smallest of ``values`` (K, m), the first on a tie;
    that smallest): ``values.argmin(axis=0)`` without its transposed copy (a smallest, a comparison, a
    largest rank)."""
    smallest = values.min(axis=0)
    rank = np.arange(values.shape[0], 0, -1, dtype=np.min_scalar_type(values.shape[0]))[:, None]
    found = np.multiply(values == smallest, rank, dtype=rank.dtype).max(axis=0, initial=1)
    return values.shape[0] - found.astype(np.intp), smallest


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
    at most one face of its ring (itself included) within the angle (noise tilted it away from all of them)
    takes the plain mean of its ring's normals instead, where that mean is at least a tenth of a unit long
    (the ring is no corner of its own, as a tetrahedron's is): kept as it is, it would be a crease of one
    face, and the fitting would turn it over. A face whose sum vanishes keeps its normal. A generator:
    yields after each pass, returns the normals.

    ``guidance``: (t, 3) unit normals (``guidance_normals``) whose cosines give the weights and the lonely
    faces instead of the filtered normals' own, w_ij = (g_i . g_j - T)^2: the weights are then fixed for
    all the passes, computed once and kept (one number a pair); without it each pass computes its weights
    chunk by chunk and uses them while they are in cache.

    The normals are filtered in single precision (``FILTER_DTYPE``): a pass averages a dozen unit vectors,
    and the fitting needs their directions to far fewer digits than positions."""
    planar = np.ascontiguousarray(normals.T, dtype=FILTER_DTYPE)
    total = np.empty_like(planar)
    weights = None
    if guidance is not None:
        weights = np.empty(rings.indices.size, dtype=FILTER_DTYPE)
        judged = np.ascontiguousarray(guidance.T, dtype=FILTER_DTYPE)
        del guidance  # the caller's may go: the weights are what the passes need
        lonely = _fixed_weights(rings, cos_threshold, judged, weights)
        del judged
        # The lonely faces weigh their whole ring alike: each pass then sums their rings, the plain mean's
        # direction, in the same product as the others' weighted sums.
        entries, counts, _ = rings.entries_of(lonely)
        weights[entries] = 1.0
        del entries
    for _ in range(iterations):
        if weights is None:
            _ring_means(total, planar, _lonely_rings(rings, _filter_pass(rings, cos_threshold, planar, total)))
        else:
            _weighted_pass(rings, weights, planar, total)
            _short_sums(total, planar, lonely, counts)
        _unit_or_kept(total, planar)
        planar, total = total, planar
        yield
    return np.ascontiguousarray(planar.T, dtype=np.float64)


def _fixed_weights(rings, cos_threshold, judged, out):
    """``out`` (the pattern's entries) = the weights (g_i . g_j - T)^2 where positive, else 0, from the
    cosines of ``judged`` (3, t), a chunk of rows at a time in the pattern's order; returns the lonely
    faces: at most one positive weight in their row (``filter_steps``)."""
    lonely = [None] * len(rings.chunks)

    def chunk(index):
        first, end = rings.chunks[index]
        pairs = slice(rings.indptr[first], rings.indptr[end])
        columns, counts = rings.indices[pairs].astype(np.intp), rings.counts[first:end]
        weights = np.repeat(judged[0, first:end], counts) * judged[0].take(columns)
        for k in (1, 2):
            weights += np.repeat(judged[k, first:end], counts) * judged[k].take(columns)
        weights -= cos_threshold
        np.maximum(weights, 0.0, out=weights)
        weights *= weights
        out[pairs] = weights
        positive = np.add.reduceat(weights != 0.0, rings.chunk_indptrs[index][:-1], dtype=np.intp)
        lonely[index] = first + np.flatnonzero(positive <= 1)

    rings.each_chunk_index(chunk)
    return np.concatenate(lonely)


def _weighted_pass(rings, weights, planar, total):
    """``total`` (3, t) = W ``planar`` (3, t) over the face rings, W's entries ``weights``, a chunk at a time."""

    def chunk(index):
        first, end = rings.chunks[index]
        pairs = slice(rings.indptr[first], rings.indptr[end])
        _weighted_rows(weights[pairs], rings.indices[pairs], rings.chunk_indptrs[index], planar, total[:, first:end])

    rings.each_chunk_index(chunk)


def _filter_pass(rings, cos_threshold, planar, total):
    """``total`` (3, t) = W ``planar`` (3, t) over the face rings with Sun et al.'s weights from the cosines
    of ``planar`` itself, computed and used a chunk at a time (the gathered normals serve both); returns
    the lonely faces: at most one positive weight in their row (``filter_steps``)."""
    lonely = [None] * len(rings.chunks)

    def chunk(index):
        first, end = rings.chunks[index]
        columns, real = rings.padded(first, end)
        gathered = [row.take(columns) for row in planar]
        chunk_weights = planar[0, first:end] * gathered[0]
        for k in (1, 2):
            chunk_weights += planar[k, first:end] * gathered[k]
        chunk_weights -= cos_threshold
        np.maximum(chunk_weights, 0.0, out=chunk_weights)
        chunk_weights *= chunk_weights
        chunk_weights *= real  # the repeated columns past each row's end weigh nothing
        lonely[index] = first + np.flatnonzero(np.count_nonzero(chunk_weights, axis=0) <= 1)
        for k, values in enumerate(gathered):
            np.sum(chunk_weights * values, axis=0, out=total[k, first:end])

    rings.each_chunk_index(chunk)
    return np.concatenate(lonely)


def _lonely_rings(rings, lonely):
    """(the ``lonely`` faces, their rings' columns, counts and starts: ``FaceRings.rows_of``)."""
    return (lonely, *rings.rows_of(lonely))


def _ring_means(total, planar, lonely):
    """The lonely faces' (``lonely``: ``_lonely_rings``) weighted sums in ``total`` (3, t) replaced, in place,
    by their rings' means of ``planar`` where these are at least a tenth of a unit long."""
    faces, columns, counts, starts = lonely
    if faces.size:
        mean = np.add.reduceat(planar[:, columns], starts, axis=1) / counts
        agree = np.einsum("kt,kt->t", mean, mean) >= 0.01  # a ring that is no corner of its own
        total[:, faces[agree]] = mean[:, agree]


def _short_sums(total, planar, faces, counts):
    """The lonely ``faces``' ring sums in ``total`` (3, t) (their rows of ``counts`` entries weigh 1 in the
    guided pass) where their mean is under a tenth of a unit long (the ring is a corner of its own)
    replaced, in place, by the face's own normal in ``planar``: it keeps it, as its own weight alone would."""
    if faces.size:
        sums = total[:, faces]
        short = faces[np.einsum("kt,kt->t", sums, sums) < 0.01 * counts.astype(total.dtype) ** 2]
        total[:, short] = planar[:, short]


def _unit_or_kept(total, planar):
    """The pass's sums ``total`` (3, t) scaled, in place, to unit length; a face whose sum vanishes keeps its
    normal in ``planar``."""
    lengths = np.sqrt(np.einsum("kt,kt->t", total, total))
    good = lengths > 0.0  # else the face keeps its normal
    np.divide(1.0, lengths, out=lengths, where=good)
    total *= lengths
    if not good.all():
        total[:, ~good] = planar[:, ~good]


def _weighted_rows(weights, columns, indptr, planar, out):
    """``out`` (3, rows) = the rows' weighted sums of planar (3, t) ``planar`` (a CSR chunk of the rings,
    ``indptr`` its own, from 0)."""
    if _csr_matvec is None:  # the public product
        out[...] = (sp.csr_matrix((weights, columns, indptr), shape=(indptr.size - 1, planar.shape[1])) @ planar.T).T
        return
    out[...] = 0.0
    for k in range(3):
        _csr_matvec(indptr.size - 1, planar.shape[1], indptr, columns, weights, planar[k], out[k])


def fit_vertices(points, normals, rings, step_share, iterations=FIT_ITERATIONS):
    """``fit_steps`` run to its end: the fitted (n, 3) positions."""
    return to_end(fit_steps(points, normals, rings, step_share, iterations))


def fit_steps(points, normals, rings, step_share, iterations=FIT_ITERATIONS):
    """Sun et al.'s vertex update, ``iterations`` passes: x_i += share_i / |F_i| sum_f n_f n_f^T (c_f - x_i)
    over the triangles f around i (``step_share``: (n,) 0 for vertices that stay, else the influence).

    That is share_i / |F_i| (sum_f n_f (n_f . c_f) - M_i x_i) with M_i = sum_f n_f n_f^T, fixed for the
    step: a pass sums each triangle's corners for its offset n_f . c_f (one product with the corners'
    pattern), sums n_f times it around each
    vertex (one product with the incidence) and subtracts M_i x_i, on the threads. A generator: yields once
    the M_i are made and after every ``FIT_SLICE`` passes but the last, returns the positions."""
    n, t = points.shape[0], normals.shape[0]
    scale = np.divide(step_share, rings.faces_at, out=np.zeros(n), where=rings.faces_at > 0)
    planar = np.ascontiguousarray(normals.T, dtype=np.float64)
    tensor = np.empty((len(SYMMETRIC_ENTRIES), n))  # M_i's entries, in that order

    def moments(first, end):  # entries first:end of M_i in one product: the pattern read once for them
        products = np.empty((end - first, t))
        for row, (a, b) in zip(products, SYMMETRIC_ENTRIES[first:end]):
            np.multiply(planar[a], planar[b], out=row)

        def combine(rows, sums):
            tensor[first:end, rows] = sums

        rings.vertex_blocks.run(lambda block: block.neighbour_sums(products, combine))

    moments(0, 3)  # in two halves: three rows of t at a time
    moments(3, 6)
    x = np.array(points.T, dtype=np.float64, order="C")  # coordinate rows: 1-D gathers
    moved, pulled = np.empty_like(x), np.empty((3, t))
    yield  # making the M_i takes as long as a few passes

    def offsets(faces, corner_sums):  # pulled = n_f (n_f . c_f) on a chunk of triangles
        corner_sums /= 3.0
        offset = np.einsum("kt,kt->t", planar[:, faces], corner_sums)
        np.multiply(planar[:, faces], offset, out=pulled[:, faces])

    def update(rows, sums):  # moved = x + share / |F| (sums - M x) on a chunk of vertices
        here, m = x[:, rows], tensor[:, rows]
        product, term = np.empty((2, sums.shape[1]))
        for k, entries in enumerate(((0, 3, 4), (3, 1, 5), (4, 5, 2))):  # row k of M, as SYMMETRIC_ENTRIES
            np.multiply(m[entries[0]], here[0], out=product)
            for c in (1, 2):
                product += np.multiply(m[entries[c]], here[c], out=term)
            sums[k] -= product
        sums *= scale[rows]
        np.add(here, sums, out=moved[:, rows])

    for done in range(1, iterations + 1):
        rings.corner_blocks.run(lambda block, x=x: block.neighbour_sums(x, offsets))
        rings.vertex_blocks.run(lambda block: block.neighbour_sums(pulled, update))
        x, moved = moved, x
        if done % FIT_SLICE == 0 and done < iterations:
            yield
    return np.ascontiguousarray(x.T)


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
        0.0) and within a step (at most ``STEP_SLICES`` slices: within and after the guidance, each filtering
        pass, each choice of the nearest planes, each fitting's set-up, every ``FIT_SLICE`` fitting passes and
        each unfolding round but the last; a step takes seconds there)."""
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
            guidance = yield from _counted(guidance_steps(normals, self.rings), slices)
            yield next(slices)
        filtering = filter_steps(normals, self.rings, self.cos_threshold, NORMAL_ITERATIONS, guidance)
        del guidance  # the filter keeps its weights instead
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
        around = _unit(self.rings.ring_sums(np.ascontiguousarray(normals.T)).T)
        unfolding = _unfold(moved, start, before, self.triangles, normals, around, corners=self.rings.corners)
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


def _unfold(points, start, before, triangles, normals, around, rounds=FOLD_ROUNDS, corners=None):
    """Halve, in place, the step's move of the corners of every triangle it turned over (its normal now more
    than 90° from its filtered normal, or from the mean ``around`` of its ring's, and its normal ``before``
    the step not), ``rounds`` times at most: the fitting moves along the faces' normals, and on curved parts
    those moves add up along the surface. A triangle already turned over before the step (noise folded it)
    keeps its corners' moves: the step is what unfolds it. A generator: yields after each round that leaves
    rounds to go. ``corners``: the triangles a corner at a time (FaceRings.corners), if the caller has them."""
    folded = _turned(before, normals, around)
    columns = np.ascontiguousarray(triangles.T) if corners is None else corners  # 1-D gathers
    faces = None  # the triangles whose corners moved: all at first, then those of the halved corners
    turned = np.zeros(triangles.shape[0], dtype=bool)
    halved = np.zeros(points.shape[0], dtype=bool)
    for round_ in range(rounds):
        if faces is None:
            turned[:] = _turned(face_normals(points, triangles), normals, around) & ~folded
        else:  # rows gathered by np.take: twice as fast as indexing (t, 3) arrays
            now = face_normals(points, np.take(triangles, faces, axis=0))
            turned[faces] = _turned(now, np.take(normals, faces, axis=0), np.take(around, faces, axis=0))
            turned[faces] &= ~folded[faces]
        if not turned.any():
            return
        halved[:] = False
        for corner in columns:
            halved[corner[turned]] = True
        corners = np.flatnonzero(halved)
        moved = np.take(points, corners, axis=0)
        kept = np.take(start, corners, axis=0)
        moved -= kept
        moved *= 0.5
        moved += kept
        points[corners] = moved
        touched = halved.take(columns[0])
        touched |= halved.take(columns[1])
        touched |= halved.take(columns[2])
        faces = np.flatnonzero(touched)
        if faces.size > triangles.shape[0] // 4:  # gathering most of them costs more than measuring all
            faces = None
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
