"""The RFS mesh ("replacement for surface", paper section 7) built from the surface description graph.

1. Around each vertex a corona (umbrella) of faces: its graph neighbours in angular order in the
   vertex's tangent plane (PCA of the vertex and its neighbours), each consecutive pair with the
   vertex forming a face, including the closing pair; the face's third side is a new edge if the
   graph lacks it. A consecutive pair more than ``max_gap`` apart in angle (a corona's open side, at
   a boundary) makes no face: it would fold over the vertex.
2. Faces below the Bank & Smith quality threshold are deleted.
3. Where more than two faces share an edge, the pair enclosing the largest dihedral angle stays
   (the flattest continuation of the surface); the others go.
4. Edges without faces are dropped: the mesh's edges are those of its faces.

Faces may cross and overlap; the mesh is not a valid surface, only a carrier of neighbourhoods.
"""

from dataclasses import dataclass

import numpy as np

from ..adjacency import umbrella_operator
from ..geometry import SYMMETRIC_ENTRIES, smallest_eigenvectors
from ..parallel import run_blocks, run_chunks
from ..slices import to_end
from .geometry import (
    Incidence,
    face_normals,
    faces_of_keys,
    normals_and_quality,
    triple_keys,
)
from .stepwise import Slices

_CORONA_CHUNK = 1 << 15  # vertices per piece of the corona's work: its temporaries stay small
_PAIR_BLOCK = 1 << 16  # incidences per block of _best_pairs
_INT32_LIMIT = 2**31  # incidence and edge numbers below this are handled as int32


@dataclass(frozen=True)
class RFSMesh:
    """A triangle mesh over points, made by ``rfs_mesh``: a carrier of neighbourhoods (faces may cross).

    Examples
    --------
    >>> import numpy as np, core
    >>> mesh = core.pointcloud.RFSMesh(faces=np.array([[0, 1, 2]]), edges=np.array([[0, 1], [0, 2], [1, 2]]))
    >>> mesh.faces.shape, mesh.other is None
    ((1, 3), True)
    """

    faces: np.ndarray  # (f, 3) vertex indices
    edges: np.ndarray  # (e, 2) the edges of the faces, each once
    # Incidence 3*f + j (the edge of face f opposite its vertex j): the incidence across that edge, -1
    # if none. Set by rfs_mesh from the grouping it already made, so edge swapping need not regroup.
    other: np.ndarray | None = None


def _normals_from_offsets(offset, row, degree):
    """Per vertex the unit normal of the PCA plane of the vertex and its neighbours (the
    eigenvector of the smallest eigenvalue of their covariance), given the neighbours' offsets
    from their vertex as three component arrays (local differences: no cancellation far from the
    origin) and each offset's vertex ``row``."""
    n = degree.size
    total = [np.bincount(row, offset[j], minlength=n) for j in range(3)]
    # Centre on the mean of the vertex and its neighbours (the vertex is the origin here).
    entries = [
        np.bincount(row, offset[i] * offset[j], minlength=n) - total[i] * total[j] / (degree + 1.0)
        for i, j in SYMMETRIC_ENTRIES
    ]
    return smallest_eigenvectors(*entries)


def _corona_block(points, indptr, indices, first, last, max_gap, keys_of=None):
    """corona_faces for the vertices first..last-1 (their rows of the adjacency); with ``keys_of``
    (the number of points), their geometry.triple_keys instead."""
    degree = np.diff(indptr[first : last + 1])
    neighbours = indices[indptr[first] : indptr[last]]
    row = np.repeat(np.arange(degree.size), degree)  # local vertex number
    columns = [points[:, j] for j in range(3)]
    here = [x[first:last] for x in columns]
    offset = [x[neighbours] - h[row] for x, h in zip(columns, here)]  # 1-D gathers: faster than rows
    frames = tangent_frames_from_normals(_normals_from_offsets(offset, row, degree))
    along = [sum(offset[j] * frames[k][j][row] for j in range(3)) for k in (0, 1)]
    angle = np.arctan2(along[1], along[0])  # (-pi, pi]
    # Row-major then angle: rows are already contiguous, so one sort of row + fraction does it.
    order = np.argsort(row + (angle + np.pi) / (2 * np.pi + 1e-9), kind="stable")
    neighbour, angle = neighbours[order], angle[order]
    # Each neighbour's successor in its row's angular order; the last one's is the row's first.
    nxt = np.arange(1, neighbours.size + 1)
    ends = np.cumsum(degree)
    has = degree > 0
    nxt[ends[has] - 1] = ends[has] - degree[has]
    gap = np.mod(angle[nxt] - angle, 2 * np.pi)
    gap[degree[row] < 2] = 2 * np.pi  # a single neighbour makes no face
    ok = np.flatnonzero(gap < max_gap)
    centre, left, right = row[ok] + first, neighbour[ok], neighbour[nxt[ok]]
    if keys_of is not None:
        return triple_keys(centre, left, right, keys_of)
    out = np.empty((ok.size, 3), dtype=np.int64)
    out[:, 0], out[:, 1], out[:, 2] = centre, left, right
    return out


def tangent_frames_from_normals(normal):
    """(t1, t2) as (2, 3, n) component arrays: an orthonormal pair across each unit normal."""
    axis = np.argmin(np.abs(normal), axis=1)
    t1 = np.cross(normal, np.eye(3)[axis])
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(normal, t1)
    return np.ascontiguousarray(np.stack([t1.T, t2.T]))


def corona_faces(points, edges, max_gap=np.pi, keys=False):
    """Candidate faces of every vertex's corona (may repeat across coronas). Each vertex's corona
    is its own business, so blocks of vertices run in parallel threads. ``keys=True``: instead the
    list of the blocks' geometry.triple_keys, from which faces_of_keys gives the distinct candidates
    (as sorted triples) without the (f, 3) array of all candidates."""
    n = points.shape[0]
    umbrella = umbrella_operator(edges, n)
    indptr = umbrella.indptr.astype(np.int64)
    indices = umbrella.indices.astype(np.int64)
    keys_of = max(n, 1) if keys else None
    parts = run_chunks(
        lambda first, last: _corona_block(points, indptr, indices, first, last, max_gap, keys_of),
        n,
        _CORONA_CHUNK,
        share=0.2,
    )
    if keys:
        return parts
    return np.concatenate(parts) if len(parts) > 1 else parts[0]


def _best_pairs(normals, forward, edges, order, start, count):
    """For each edge in ``edges`` (with its live incidences ``order[start:start + count]``): the
    two incidences of the pair with the largest dihedral angle, and that angle's cos. Edges are
    handled in buckets of equal face count, so the all-pairs arrays have no padding.

    The cos comes from the faces' unit normals, ``normals`` (f, 3) (a face's normal in one cache
    line: the incidences' faces are scattered), as in ``incidence_cos``: each incidence contributes its
    face's normal, signed by the direction in which the face runs along the edge. The pairs are
    visited in np.triu_indices order keeping a running minimum that only a strictly smaller cos
    replaces, so ties go to the first pair (as np.argmin would); NaN (a degenerate face) never
    wins: an edge whose every pair is NaN gets its first pair and cos inf."""
    first = np.empty(edges.size, dtype=np.int64)
    second = np.empty(edges.size, dtype=np.int64)
    best_cos = np.empty(edges.size)
    widths = count[edges]
    for width in np.unique(widths):
        i, j = np.triu_indices(width, 1)
        bucket = np.flatnonzero(widths == width)
        # Blocks of edges small enough that the temporaries stay in cache and are reused.
        step = max(1, _PAIR_BLOCK // int(width))
        for lo in range(0, bucket.size, step):
            rows = bucket[lo : lo + step]
            incidence = order[start[edges[rows]][:, None] + np.arange(width)[None, :]]  # (rows, width)
            face = incidence // 3
            sign = np.where(forward[incidence], 1.0, -1.0)
            # Gathered face by face, then one contiguous row per slot and component.
            signed = np.take(normals, face, axis=0)  # take: a fast path that indexing with [] misses
            signed *= sign[:, :, None]
            v = [np.ascontiguousarray(signed[:, :, c].T) for c in range(3)]
            best = np.full(rows.size, np.inf)
            pick = np.zeros(rows.size, dtype=np.intp)
            cos = np.empty(rows.size)
            term = np.empty(rows.size)
            better = np.empty(rows.size, dtype=bool)
            for k in range(i.size):
                a, b = i[k], j[k]
                np.multiply(v[0][a], v[0][b], out=cos)  # the same sum, in the same order, as a vectorized dot
                cos += np.multiply(v[1][a], v[1][b], out=term)
                cos += np.multiply(v[2][a], v[2][b], out=term)
                np.less(cos, best, out=better)  # False for NaN
                np.copyto(best, cos, where=better)
                np.copyto(pick, k, where=better)
            at = np.arange(rows.size)
            best_cos[rows] = best
            first[rows] = incidence[at, i[pick]]
            second[rows] = incidence[at, j[pick]]
    return first, second, best_cos


_EDGE_BITS = 26


def _priority(best_cos, edge, n_edges):
    """Distinct int64 priorities, larger for a larger best dihedral angle (smaller cos), ties by edge
    number; without a sort: the angle quantized to 2^-35 in the high bits, the edge in the low."""
    if n_edges >= 1 << _EDGE_BITS:  # too many edges for the packed key: rank by sorting
        priority = np.empty(edge.size, dtype=np.int64)
        priority[np.lexsort((edge, -best_cos))] = np.arange(edge.size)
        return priority
    level = np.round((1.0 - np.clip(best_cos, -1.0, 1.0)) * 2.0**35).astype(np.int64)
    return (level << _EDGE_BITS) | edge


def keep_best_pairs(points, faces, normals=None):
    """Delete faces until no edge has more than two: at an overfull edge the pair with the largest
    dihedral angle stays. Returns the boolean mask of faces kept.

    This is the paper's edge-by-edge rule (which leaves the order open), done in rounds: each round
    settles the overfull edges that are the top priority (flattest best pair first) at both faces
    of their best pair and delete no face that another of them keeps. Those give the same result
    in whatever order they are handled one after another (each one's best pair survives the
    others, so it stays the best of what is left), so a round is a stretch of the sequential rule.
    Then the counts are updated. Settling all edges at once instead would delete a face that one
    edge keeps because another edge drops it, and lose about half of the faces. An edge's best
    pair is recomputed only after it lost a face. Each round works only on the incidences of the
    edges still overfull (kept sorted by edge), so the long tail of rounds costs little.
    ``normals``: the faces' face_normals, if the caller has them.
    """
    return _prune(points, faces, normals)[0]


def _prune(points, faces, normals=None, settled=None):
    """keep_best_pairs, also returning the faces' Incidence. ``settled`` (optional, one int per
    edge of the Incidence, preset to -1) receives the round in which each overfull edge settled."""
    return to_end(_prune_steps(points, faces, normals, settled))


def _prune_steps(points, faces, normals=None, settled=None):
    """_prune stepwise (core.pointcloud.stepwise): yields between rounds, the fraction of the
    overfull edges' incidences settled."""
    pruning = _Pruning(points, faces, normals)
    order, edge = pruning.overfull()
    total, slices = max(order.size, 1), Slices()
    while order.size:
        work = order.size
        order, edge = pruning.settle_round(order, edge, settled)
        if slices.due(work) and order.size:
            yield 1.0 - order.size / total
    return pruning.alive, pruning.inc


class _Pruning:
    """The state of keep_best_pairs between its rounds (see there)."""

    def __init__(self, points, faces, normals):
        n_faces = faces.shape[0]
        self.inc = inc = Incidence(faces, max(points.shape[0], 1))
        self.normals = face_normals(points, faces) if normals is None else normals
        # Whether each incidence's face runs along its edge from the edge's low end (incidence_cos).
        # Slot j's edge runs from slot j+1 to slot j+2; it starts at the edge's low end when that is lower.
        forward = np.empty(faces.shape, dtype=bool)
        for j in range(3):
            np.less_equal(faces[:, (j + 1) % 3], faces[:, (j + 2) % 3], out=forward[:, j])
        self.forward = forward.reshape(-1)
        self.n_edges = n_edges = inc.edge_count.size
        # Incidence and edge numbers in int32 when they fit: half the bytes to move in every round.
        self.narrow = narrow = np.int32 if max(3 * n_faces, n_edges) < _INT32_LIMIT else np.int64
        self.alive = np.ones(n_faces, dtype=bool)
        self.known = np.zeros(n_edges, dtype=bool)  # best pair cached and still valid
        self.first = np.full(n_edges, -1, dtype=narrow)
        self.second = np.full(n_edges, -1, dtype=narrow)
        self.best_cos = np.zeros(n_edges)
        self.count = np.zeros(n_edges, dtype=narrow)
        self.start = np.zeros(n_edges, dtype=narrow)
        # Scratch, reset after each use: per face the top priority and whether a candidate keeps it;
        # per edge whether a candidate would delete a kept face.
        self.top = np.full(n_faces, -1, dtype=np.int64)
        self.kept = np.zeros(n_faces, dtype=bool)
        self.flag = np.zeros(n_edges, dtype=bool)
        self.rounds = 0  # rounds that settled edges

    def overfull(self):
        """The incidences of the overfull edges, sorted by edge (inc.order is), and their edges."""
        inc = self.inc
        overfull = inc.edge_count > 2
        order = inc.order[np.repeat(overfull, inc.edge_count)].astype(self.narrow, copy=False)
        edge = np.repeat(np.flatnonzero(overfull).astype(self.narrow), inc.edge_count[overfull])
        return order, edge

    def _refresh(self, order, over, run, run_count):
        """Best pairs of the live overfull edges ``over`` whose cached pair is stale."""
        self.count[over] = run_count
        self.start[over] = run
        stale = over[~self.known[over]]
        if stale.size:
            parts = run_blocks(
                lambda lo, hi: _best_pairs(self.normals, self.forward, stale[lo:hi], order, self.start, self.count),
                stale.size,
                share=0.5,
            )
            self.first[stale], self.second[stale], self.best_cos[stale] = (np.concatenate(x) for x in zip(*parts))
            self.known[stale] = True

    def settle_round(self, order, edge, settled):
        """One round; the incidences (order, edge) still to settle."""
        # Runs of equal edge: the live overfull edges and their incidences.
        run = np.flatnonzero(np.concatenate(([True], edge[1:] != edge[:-1])))
        run_count = np.diff(np.append(run, edge.size))
        over = edge[run]
        if not (run_count > 2).all():  # edges that fell to two faces leave the lists
            still = np.repeat(run_count > 2, run_count)
            return order[still], edge[still]
        self._refresh(order, over, run, run_count)
        first, second, top, kept, flag = self.first, self.second, self.top, self.kept, self.flag
        # Priority: flatter best pair first, ties by edge number; distinct, so each face has one top edge.
        priority = _priority(self.best_cos[over], over, self.n_edges)
        face = order // 3
        np.maximum.at(top, face, np.repeat(priority, run_count))
        # Candidates: edges that are the top priority at both faces of their best pair, so no
        # edge before them in the flattest-first order can take those faces away ...
        # (Each live edge's best pair is two of its live incidences: any face loss made it stale.)
        pair_a, pair_b = first[over] // 3, second[over] // 3
        candidate = (top[pair_a] == priority) & (top[pair_b] == priority)
        top[face] = -1
        kept[pair_a[candidate]] = True
        kept[pair_b[candidate]] = True
        # ... and that delete no face another candidate keeps. These settle together: none deletes
        # a face another keeps, so each one's best pair is the same in whatever order they go.
        inside = np.repeat(candidate, run_count)  # the candidates' incidences
        at, at_edge = order[inside], edge[inside]
        at_face = at // 3
        other = (at != first[at_edge]) & (at != second[at_edge])
        clash = at_edge[other & kept[at_face]]
        kept[pair_a[candidate]] = False
        kept[pair_b[candidate]] = False
        flag[clash] = True
        settle = candidate & ~flag[over]
        dead = at_face[other & ~flag[at_edge]]  # may repeat: two settling edges can delete the same face
        flag[clash] = False
        if settled is not None:
            settled[over[settle]] = self.rounds
        self.rounds += 1
        self.alive[dead] = False
        self.known[self.inc.edge_of[(3 * dead[:, None] + np.arange(3)).ravel()]] = False
        del inside, at, at_edge, at_face, other, dead  # before the compaction allocates its copies
        # Drop the incidences of the dead faces and of the settled edges (now exactly two faces).
        survive = self.alive[face]
        del face
        survive &= ~np.repeat(settle, run_count)
        return order[survive], edge[survive]


def rfs_mesh(points, edges, *, min_quality=0.3, max_gap=np.pi):
    """Build the RFS mesh of ``points`` (n, 3) float64 from graph ``edges`` (m, 2).

    Parameters
    ----------
    points : (n, 3) float64 ndarray
    edges : (m, 2) int ndarray
        The surface description graph (``surface_description_graph``).
    min_quality : float in [0, 1], default 0.3
        Faces below this Bank & Smith quality are deleted.
    max_gap : float, default pi
        Consecutive neighbours further apart than this angle around a point make no face.

    Returns
    -------
    RFSMesh

    Examples
    --------
    >>> import numpy as np, core
    >>> from core.pointcloud.spanning_tree import NeighbourIndex, boruvka_emst
    >>> rng = np.random.default_rng(0)
    >>> sphere = rng.normal(size=(500, 3))
    >>> sphere /= np.linalg.norm(sphere, axis=1, keepdims=True)
    >>> index = NeighbourIndex(sphere, 16)  # distinct points, KD-tree, 16 nearest neighbours
    >>> tree, _ = boruvka_emst(index)  # the EMST's edges, as rows of index
    >>> graph = core.pointcloud.surface_description_graph(index, tree, spacing_factor=2.5)
    >>> mesh = core.pointcloud.rfs_mesh(index.points, graph.edges)
    >>> mesh.faces.shape[1], np.unique(mesh.faces).size  # triangles over all but one of the 500 points
    (3, 499)
    >>> sides = np.sort(mesh.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    >>> int(np.unique(sides, axis=0, return_counts=True)[1].max())  # no edge in more than two faces
    2
    """
    return to_end(rfs_steps(points, edges, min_quality=min_quality, max_gap=max_gap))


def rfs_steps(points, edges, *, min_quality=0.3, max_gap=np.pi):
    """rfs_mesh stepwise (core.pointcloud.stepwise): yields after the candidate faces and between
    pruning rounds, the fraction of the stage done; returns the RFSMesh."""
    n = points.shape[0]
    # int32 while the mesh is built when the vertex numbers fit (half the memory), int64 as the mesh's.
    index = np.int32 if n < _INT32_LIMIT else np.int64
    faces = faces_of_keys(corona_faces(points, edges, max_gap, keys=True), max(n, 1), index)
    normals, quality = normals_and_quality(points, faces)
    good = quality >= min_quality
    # np.compress: rows picked by a mask several times faster than indexing with it.
    faces = np.compress(good, faces, axis=0)
    normals = np.compress(good, normals, axis=0)
    if Slices().due(3 * faces.shape[0]):
        yield _CANDIDATES_SHARE
    pruning = _prune_steps(points, faces, normals)
    while True:
        try:
            yield _CANDIDATES_SHARE + (1.0 - _CANDIDATES_SHARE) * next(pruning)
        except StopIteration as stop:
            alive, inc = stop.value
            break
    return _mesh_of(faces, alive, inc)


_CANDIDATES_SHARE = 0.3  # about the share of the stage's time the candidate faces take


def _mesh_of(faces, alive, inc):
    """The RFSMesh of the kept faces (``alive``), with the pairing of their incidences across edges."""
    # The kept faces' incidences, still grouped by edge (ties in face order), at most two per edge.
    live = inc.order[alive[inc.order // 3]]
    live_edge = inc.edge_of[live]
    # The mesh's edges: those with a face left (inc.edges is sorted, like a fresh Incidence's).
    used = np.zeros(inc.edges.shape[0], dtype=bool)
    used[live_edge] = True
    number = np.cumsum(alive) - 1  # the kept faces' new numbers
    live = 3 * number[live // 3] + live % 3
    pair = np.flatnonzero(live_edge[1:] == live_edge[:-1])
    other = np.full(3 * int(np.count_nonzero(alive)), -1, dtype=np.int64)
    other[live[pair]], other[live[pair + 1]] = live[pair + 1], live[pair]
    return RFSMesh(np.compress(alive, faces, axis=0).astype(np.int64), np.compress(used, inc.edges, axis=0), other)
