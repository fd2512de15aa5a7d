"""Triangle geometry shared by the RFS mesh and edge swapping, all vectorized over arrays of faces."""

import numpy as np

from ..adjacency import pairs_in_order
from ..geometry import face_normals as shared_face_normals
from ..parallel import run_chunks
from .sdg import unique_sorted

SQRT3 = np.sqrt(3.0)
_CHUNK = 1 << 16  # faces per piece of element-wise work: its temporaries stay small


def _normals_block(points, faces):
    """Unit normals (3, f) of faces (p0, p1, p2) by (p1 - p0) x (p2 - p0), and twice their areas."""
    p = [tuple(points[faces[:, k], j] for j in range(3)) for k in range(3)]
    e1 = [p[1][j] - p[0][j] for j in range(3)]
    e2 = [p[2][j] - p[0][j] for j in range(3)]
    normal = np.stack([e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]])
    double_area = np.sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2])
    with np.errstate(invalid="ignore", divide="ignore"):
        normal /= double_area  # NaN for a degenerate face
    return normal, double_area, e1, e2


def face_normals(points, faces, out=None):
    """core.geometry.face_normals, NaN for a degenerate face (no dihedral angle to it compares true)."""
    normals = shared_face_normals(points, faces, out)
    normals[~normals.any(axis=1)] = np.nan
    return normals


def _quality(double_area, e1, e2):
    e3 = [e2[j] - e1[j] for j in range(3)]
    squares = sum(x[j] * x[j] for x in (e1, e2, e3) for j in range(3))
    with np.errstate(invalid="ignore", divide="ignore"):
        quality = 2.0 * SQRT3 * double_area / squares
    return np.nan_to_num(quality, nan=0.0)


def normals_and_quality(points, faces):
    """face_normals and the faces' Bank & Smith quality q = 4*sqrt(3)*A / (l1^2 + l2^2 + l3^2) (1 for
    equilateral, 0 degenerate), in one pass over the faces."""
    normals = np.empty((faces.shape[0], 3))
    quality = np.empty(faces.shape[0])

    def block(lo, hi):
        normal, double_area, e1, e2 = _normals_block(points, faces[lo:hi])
        normals[lo:hi] = normal.T
        quality[lo:hi] = _quality(double_area, e1, e2)

    run_chunks(block, faces.shape[0], _CHUNK)
    return normals, quality


def incidence_starts(faces):
    """Per incidence 3*f + j the vertex its edge starts from in face f's order: slot j + 1."""
    return faces[:, [1, 2, 0]].reshape(-1)


def incidence_cos(normals, faces, x, y, starts=None):
    """cos of the dihedral angle between the faces of incidences x and y of one edge (incidence
    3*f + j: the edge of face f opposite its slot j), from the faces' unit normals (f, 3).

    The vector from the edge into face f, perpendicular to the edge, is s * (n_f x e) for the
    edge's direction e, with s = +1 when the face runs along the edge in direction e (its slot
    j+1 holds the edge's start); n_f and n_g are perpendicular to e, so the two vectors' dot is
    s_f s_g (n_f . n_g): +1 when both faces run along the edge the same way. Two faces of a
    consistently oriented flat mesh run opposite ways: cos -1, the angle pi. ``starts``:
    incidence_starts(faces), when the caller has it.
    """
    fx, fy = x // 3, y // 3
    if starts is None:
        starts = incidence_starts(faces)
    same = starts[x] == starts[y]
    dot = dot_rows(normals[fx], normals[fy])
    return np.where(same, dot, -dot)


def dot_rows(x, y):
    """Row-wise dot products of (k, 3) arrays, component by component (much faster than a reduction
    over a length-3 axis), summed left to right."""
    return x[:, 0] * y[:, 0] + x[:, 1] * y[:, 1] + x[:, 2] * y[:, 2]


def triple_keys(x, y, z, n):
    """For faces given as vertex columns x, y, z: the sorted triples (first, middle, last) of those
    without a repeated vertex, as int64 keys (first * n + middle) * n + last when n^3 < 2^62, else
    as an (f, 3) array. The triples are sorted by a min/max network on whole columns (faster than
    np.sort along rows of three)."""
    x, y, z = (np.asarray(c).astype(np.int64, copy=False) for c in (x, y, z))
    low, high = np.minimum(x, y), np.maximum(x, y)
    first, last = np.minimum(low, z), np.maximum(high, z)
    middle = np.maximum(low, np.minimum(high, z, out=high), out=low)
    del high, low
    keep = (first != middle) & (middle != last)
    if n**3 < 2**62:
        keys = first * n
        keys += middle
        keys *= n
        keys += last
        return keys[keep]
    return np.stack([first, middle, last], axis=1)[keep]


def faces_of_keys(keys, n, dtype=np.int64):
    """Distinct faces (f, 3) of ``dtype`` from the triple_keys of faces (in any number of parts)."""
    if isinstance(keys, (list, tuple)):
        keys = np.concatenate(keys) if len(keys) != 1 else keys[0]
    if keys.ndim == 2:  # n^3 too large for keys: the triples themselves
        return np.unique(keys, axis=0).reshape(-1, 3).astype(dtype, copy=False)
    keys = unique_sorted(keys)
    faces = np.empty((keys.size, 3), dtype=dtype)
    first = keys // (n * n)
    faces[:, 0] = first
    keys -= first * (n * n)  # (middle, last) as middle * n + last
    del first
    middle = keys // n
    faces[:, 1] = middle
    keys -= middle * n
    faces[:, 2] = keys
    return faces


def group_by_edge(low, high, n):
    """The pairs (low, high) in [0, n)^2 grouped by edge as (order, edge_start, edges, edge_of):
    ``order`` is np.argsort(low * n + high, kind="stable"), ``edge_start`` where each distinct
    pair's run begins in that order, ``edges`` the distinct pairs (int64, sorted) and ``edge_of``
    each input pair's edge number (``order`` and ``edge_of`` int32: half the bytes to scatter and
    gather); None where the counting kernels are missing or the indices do not fit in int32.

    Two counting passes (core.adjacency.pairs_in_order) group the pairs by low vertex, each
    vertex's pairs by high vertex, ties in input order; the runs of equal pairs are then read off
    the grouped high vertices and the low vertices' row pointers, without building, gathering or
    dividing int64 keys.
    """
    size = low.size
    if n >= 2**31 or size >= 2**31:
        return None
    placed = pairs_in_order(
        low.astype(np.int32, copy=False), high.astype(np.int32, copy=False), n, np.arange(size, dtype=np.int32)
    )
    if placed is None:
        return None
    indptr, high_sorted, order = placed
    new = np.empty(size, dtype=bool)
    if size:
        new[0] = True
        np.not_equal(high_sorted[1:], high_sorted[:-1], out=new[1:])
        row_start = indptr[:-1]
        new[row_start[row_start < indptr[1:]]] = True  # a new low vertex starts a new edge
    before = np.zeros(size + 1, dtype=np.int32)  # edges starting before each position
    np.cumsum(new, dtype=np.int32, out=before[1:])  # a bool input without dtype= is summed far slower
    edge_start = np.flatnonzero(new)
    edge_of = np.empty(size, dtype=np.int32)
    edge_of[order] = before[1:]
    edge_of -= 1
    per_low = before[indptr[1:]] - before[indptr[:-1]]
    edges = np.empty((edge_start.size, 2), dtype=np.int64)
    edges[:, 0] = np.repeat(np.arange(n, dtype=np.int64), per_low)
    edges[:, 1] = high_sorted[edge_start]
    return order, edge_start, edges, edge_of


class Incidence:
    """Face-edge incidences of a triangle list, grouped by edge.

    Incidence 3*f + j is the edge of face f opposite its vertex j. ``order`` sorts incidences by
    edge; ``edge_start``/``edge_count`` delimit each distinct edge's run in that order;
    ``edge_of[i]`` is the edge number of incidence i (``order`` and ``edge_of`` int32 where the
    numbers fit); ``edges`` are the distinct edges (low, high) and ``keys`` their int64 keys
    low * n + high, both sorted.
    """

    def __init__(self, faces, n):
        # int32 where the vertex numbers fit: half the bytes to move before the grouping.
        f = np.asarray(faces).astype(np.int32 if n < 2**31 else np.int64, copy=False).reshape(-1, 3)
        # Edge opposite vertex j: (f[(j+1)%3], f[(j+2)%3]), its ends ordered, column by column.
        low, high = np.empty(f.shape, f.dtype), np.empty(f.shape, f.dtype)
        for j in range(3):
            np.minimum(f[:, (j + 1) % 3], f[:, (j + 2) % 3], out=low[:, j])
            np.maximum(f[:, (j + 1) % 3], f[:, (j + 2) % 3], out=high[:, j])
        low, high = low.reshape(-1), high.reshape(-1)
        grouped = group_by_edge(low, high, n)
        if grouped is not None:
            self.order, self.edge_start, self.edges, self.edge_of = grouped
            self.edge_count = np.diff(np.append(self.edge_start, low.size))
            self.keys = self.edges[:, 0] * n + self.edges[:, 1]
        else:
            low, high = low.astype(np.int64), high.astype(np.int64)
            keys = low * n + high
            self.order = np.argsort(keys, kind="stable")
            sorted_keys = keys[self.order]
            new = np.concatenate(([True], sorted_keys[1:] != sorted_keys[:-1])) if keys.size else np.zeros(0, bool)
            self.edge_start = np.flatnonzero(new)
            self.edge_count = np.diff(np.append(self.edge_start, keys.size))
            edge_number = np.cumsum(new, dtype=np.int64) - 1
            self.edge_of = np.empty(keys.size, dtype=np.int64)
            self.edge_of[self.order] = edge_number
            if max(n, keys.size) < 2**31:  # the counting path's types
                self.order, self.edge_of = self.order.astype(np.int32), self.edge_of.astype(np.int32)
            self.keys = sorted_keys[self.edge_start]
            self.edges = np.stack([self.keys // max(n, 1), self.keys % max(n, 1)], axis=1)


# Off-line spread, relative to the spread along the line, below which points count as on one line: far
# below any scan's noise, far above float32 rounding.
COLLINEAR = 1e-6


def collinear(points):
    """Whether (n, 3) ``points`` lie on one straight line (within COLLINEAR of their extent): no triangle
    of them has an area, so no RFS face can form.

    >>> import numpy as np
    >>> t = np.linspace(0.0, 1.0, 5)[:, None]
    >>> collinear(t * [1.0, 2.0, 3.0]), collinear(np.eye(3))
    (True, False)

    Examples
    --------
    >>> import numpy as np, core
    >>> core.collinear(np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]])), core.collinear(np.eye(3))
    (True, False)
    """
    centred = np.asarray(points, dtype=np.float64)
    centred = centred - centred.mean(axis=0)
    spread = np.sqrt(np.clip(np.linalg.eigvalsh(centred.T @ centred), 0.0, None))  # ascending
    return bool(spread[1] <= COLLINEAR * spread[2])
