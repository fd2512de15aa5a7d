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
from .geometry import Incidence, face_quality, unique_faces

_CHUNK = 1 << 18


@dataclass(frozen=True)
class RFSMesh:
    faces: np.ndarray  # (f, 3) vertex indices
    edges: np.ndarray  # (e, 2) the edges of the faces, each once


def tangent_frames(points, indptr, indices):
    """Per vertex an orthonormal (t1, t2, normal) from the PCA of the vertex and its neighbours."""
    n = points.shape[0]
    degree = np.diff(indptr)
    row = np.repeat(np.arange(n), degree)
    offset = points[indices] - points[row]  # local differences: no cancellation far from the origin
    total = np.stack([np.bincount(row, offset[:, j], minlength=n) for j in range(3)], axis=1)
    cov = np.empty((n, 3, 3))
    for i in range(3):
        for j in range(i, 3):
            cov[:, i, j] = cov[:, j, i] = np.bincount(row, offset[:, i] * offset[:, j], minlength=n)
    # Centre on the mean of the vertex and its neighbours (the vertex is the origin here).
    cov -= total[:, :, None] * total[:, None, :] / (degree + 1.0)[:, None, None]
    frames = np.empty((n, 3, 3))
    for start in range(0, n, _CHUNK):
        block = slice(start, min(start + _CHUNK, n))
        _, vectors = np.linalg.eigh(cov[block])  # ascending eigenvalues: normal first
        frames[block, 2] = vectors[:, :, 0]
        frames[block, 0] = vectors[:, :, 2]
        frames[block, 1] = np.cross(vectors[:, :, 0], vectors[:, :, 2])
    return frames


def corona_faces(points, edges, max_gap=np.pi):
    """Candidate faces of every vertex's corona (may repeat across coronas)."""
    n = points.shape[0]
    umbrella = umbrella_operator(edges, n)
    indptr = umbrella.indptr.astype(np.int64)
    indices = umbrella.indices.astype(np.int64)
    degree = np.diff(indptr)
    frames = tangent_frames(points, indptr, indices)
    row = np.repeat(np.arange(n), degree)
    offset = points[indices] - points[row]
    angle = np.arctan2(np.einsum("ij,ij->i", offset, frames[row, 1]),
                       np.einsum("ij,ij->i", offset, frames[row, 0]))  # (-pi, pi]
    # Row-major then angle: rows are already contiguous, so one sort of row + fraction does it.
    order = np.argsort(row + (angle + np.pi) / (2 * np.pi + 1e-9), kind="stable")
    neighbour, angle = indices[order], angle[order]
    position = np.arange(indices.size)
    start = indptr[row]
    nxt = start + (position - start + 1) % np.maximum(degree[row], 1)
    gap = np.mod(angle[nxt] - angle, 2 * np.pi)
    gap[nxt == position] = 2 * np.pi  # a single neighbour makes no face
    ok = (degree[row] >= 2) & (gap < max_gap)
    return np.stack([row[ok], neighbour[ok], neighbour[nxt[ok]]], axis=1)


def _best_pairs(points, inc, edges, order, start, count):
    """For each edge in ``edges`` (with its live incidences ``order[start:start + count]``): the
    two incidences of the pair with the largest dihedral angle, and that angle's cos. Edges are
    handled in buckets of equal face count, so the all-pairs arrays have no padding."""
    first = np.empty(edges.size, dtype=np.int64)
    second = np.empty(edges.size, dtype=np.int64)
    best_cos = np.empty(edges.size)
    for width in np.unique(count[edges]):
        rows = np.flatnonzero(count[edges] == width)
        edge = edges[rows]
        incidence = order[start[edge][:, None] + np.arange(width)[None, :]]
        # Unit vectors from the edge towards each face's third vertex, perpendicular to the edge:
        # the dihedral angle of two faces is the angle between their vectors.
        u, v = inc.edges[edge, 0], inc.edges[edge, 1]
        axis = points[v] - points[u]
        axis /= np.linalg.norm(axis, axis=1, keepdims=True)
        w = points[inc.third[incidence]] - points[u][:, None, :]
        w -= (w * axis[:, None, :]).sum(axis=2, keepdims=True) * axis[:, None, :]
        with np.errstate(invalid="ignore", divide="ignore"):
            w /= np.linalg.norm(w, axis=2, keepdims=True)
        cos = np.matmul(w, w.transpose(0, 2, 1))
        cos[:, np.arange(width), np.arange(width)] = np.inf
        cos[np.isnan(cos)] = np.inf  # degenerate faces never win
        flat = np.argmin(cos.reshape(rows.size, -1), axis=1)
        best_cos[rows] = cos.reshape(rows.size, -1)[np.arange(rows.size), flat]
        first[rows] = incidence[np.arange(rows.size), flat // width]
        second[rows] = incidence[np.arange(rows.size), flat % width]
    return first, second, best_cos


_EDGE_BITS = 26


def _priority(best_cos, edge, n_edges):
    """Distinct int64 priorities, larger for a larger best dihedral angle (smaller cos), ties by edge
    number; without a sort: the angle quantized to 2^-35 in the high bits, the edge in the low."""
    if n_edges >= 1 << _EDGE_BITS:  # too many edges for the packed key: rank by sorting
        priority = np.empty(edge.size, dtype=np.int64)
        priority[np.lexsort((edge, -best_cos))] = np.arange(edge.size)
        return priority
    level = np.round((1.0 - np.clip(best_cos, -1.0, 1.0)) * 2.0 ** 35).astype(np.int64)
    return (level << _EDGE_BITS) | edge


def keep_best_pairs(points, faces):
    """Delete faces until no edge has more than two: at an overfull edge the pair with the largest
    dihedral angle stays. Returns the boolean mask of faces kept.

    This is the paper's edge-by-edge rule, done in rounds: each round settles a set of overfull
    edges that share no face (so their choices cannot conflict), flattest best pair first, exactly
    as if they were handled one after another; then the counts are updated. Settling all edges
    at once instead would delete a face that one edge keeps because another edge drops it, and
    lose about half of the faces. An edge's best pair is recomputed only after it lost a face.
    """
    n_faces = faces.shape[0]
    inc = Incidence(faces, max(points.shape[0], 1))
    n_edges = inc.edge_count.size
    edge_sorted = np.repeat(np.arange(n_edges), inc.edge_count)  # edge of each incidence in inc.order
    alive = np.ones(n_faces, dtype=bool)
    known = np.zeros(n_edges, dtype=bool)  # best pair cached and still valid
    first = np.full(n_edges, -1, dtype=np.int64)
    second = np.full(n_edges, -1, dtype=np.int64)
    best_cos = np.zeros(n_edges)
    order, edge = inc.order, edge_sorted
    while True:
        # Only incidences of overfull edges matter, and counts only fall: shrink the work each round.
        live = alive[order // 3]
        order, edge = order[live], edge[live]
        count = np.bincount(edge, minlength=n_edges)
        count[count <= 2] = 0
        keep = count[edge] > 0
        order, edge = order[keep], edge[keep]
        over = np.flatnonzero(count)
        if over.size == 0:
            break
        start = np.cumsum(count) - count
        stale = over[~known[over]]
        if stale.size:
            first[stale], second[stale], best_cos[stale] = _best_pairs(points, inc, stale, order, start, count)
            known[stale] = True
        # Priority: flatter best pair first, ties by edge number; distinct, so each face has one top edge.
        priority = np.full(n_edges, -1, dtype=np.int64)
        priority[over] = _priority(best_cos[over], over, n_edges)
        member, member_edge = order, edge
        face = member // 3
        top = np.full(n_faces, -1, dtype=np.int64)
        np.maximum.at(top, face, priority[member_edge])
        # An edge settles when it is the top priority at every one of its faces.
        blocked = np.zeros(n_edges, dtype=bool)
        blocked[member_edge[top[face] != priority[member_edge]]] = True
        losing = ~blocked[member_edge] & (member != first[member_edge]) & (member != second[member_edge])
        was_alive = alive.copy()
        alive[face[losing]] = False
        dead = np.flatnonzero(was_alive != alive)  # a mask, not np.unique: no hashing per round
        known[inc.edge_of[(3 * dead[:, None] + np.arange(3)).ravel()]] = False
    return alive


def rfs_mesh(points, edges, *, min_quality=0.3, max_gap=np.pi):
    """Build the RFS mesh of ``points`` (n, 3) float64 from graph ``edges`` (m, 2)."""
    n = points.shape[0]
    faces = unique_faces(corona_faces(points, edges, max_gap), max(n, 1))
    faces = faces[face_quality(points, faces) >= min_quality]
    faces = faces[keep_best_pairs(points, faces)]
    return RFSMesh(faces, Incidence(faces, max(n, 1)).edges)
