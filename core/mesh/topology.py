"""Which faces close a surface and where it is open: integer work on face corners, no positions.

Blender stores a mesh's faces as corners, each with its vertex and the edge to the next corner of its
face; core callers pass faces as arrays. Both layouts are answered here in O(corners), without a sort.

``surface`` answers both, and which vertices the triangles connect, for a mesh given as triangles.
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..adjacency import grouped_pairs, pair_keys
from ..parallel import BLOCK
from ..slices import to_end
from .parts import parts as connected_parts

_ROW_BLOCK = BLOCK  # vertices per block where each of their half-edges is compared (several int64 each)


def closed_from_corners(edges, corner_verts, corner_edges):
    """Whether the faces form a closed, consistently oriented surface: every edge of a face is in exactly
    two faces, which run along it in opposite directions (loose edges do not matter).

    Parameters
    ----------
    edges : (m, 2) int ndarray
    corner_verts, corner_edges : (c,) int ndarrays
        Per face corner, its vertex and the edge to the next corner of its face (Blender's layout).

    Returns
    -------
    bool

    Examples
    --------
    >>> import numpy as np
    >>> from core.mesh import topology
    >>> edges = np.array([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]])
    >>> corner_verts = np.array([0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3])  # a tetrahedron, 4 triangles
    >>> corner_edges = np.array([1, 3, 0, 0, 4, 2, 2, 5, 1, 3, 5, 4])  # each corner's edge to the next
    >>> topology.closed_from_corners(edges, corner_verts, corner_edges)
    True
    >>> topology.closed_from_corners(edges, corner_verts[:9], corner_edges[:9])  # one face less
    False
    """
    if corner_verts.size == 0 or len(edges) == 0:
        return False
    # Key 2e + 1 marks a corner running along edge e from its first vertex, 2e one running against it:
    # closed and oriented <=> no key twice and every used edge has both.
    first = np.ascontiguousarray(edges[:, 0])
    wide = 2 * len(edges) > np.iinfo(np.int32).max
    keys = np.left_shift(corner_edges, 1, dtype=np.int64 if wide else corner_edges.dtype)
    keys |= corner_verts == np.take(first, corner_edges)
    seen = np.zeros(2 * len(edges), dtype=bool)
    seen[keys] = True
    return bool(np.count_nonzero(seen) == keys.size and np.array_equal(seen[0::2], seen[1::2]))


def every_edge_shared(corner_edges, n_edges):
    """Whether no edge of a face lies on that face alone (Blender's layout: per face corner, the edge to
    the next corner). Such a mesh has no seam that a file or an exporter split into copies of its
    vertices, so there is nothing to weld.

    Examples
    --------
    >>> import numpy as np
    >>> import core
    >>> corner_edges = np.array([1, 3, 0, 0, 4, 2, 2, 5, 1, 3, 5, 4])  # a tetrahedron, 4 triangles
    >>> core.every_edge_shared(corner_edges, 6), core.every_edge_shared(corner_edges[:9], 6)
    (True, False)
    """
    return not np.any(np.bincount(corner_edges, minlength=n_edges) == 1)


def closed_from_triangles(triangles):
    """Every directed edge of the (t, 3) triangles is matched by exactly one in the opposite direction.

    Examples
    --------
    >>> import numpy as np
    >>> from core.mesh import topology
    >>> triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> topology.closed_from_triangles(triangles), topology.closed_from_triangles(triangles[:3])
    (True, False)
    >>> topology.closed_from_triangles(triangles[[0, 1, 2, 3, 3]])  # a face twice
    False
    """
    if triangles.size == 0:
        return False
    heads = triangles.ravel()
    tails = np.roll(triangles, -1, axis=1).ravel()
    n = int(triangles.max()) + 1
    # Fan diagonals appear once in each direction inside their own face, so they cancel like real edges.
    # Directed-edge counts as a sparse matrix D (SciPy's O(nnz) placement, no global sort): closed and
    # consistently oriented <=> every directed edge once (entries all 1) and D == D^T.
    counts = sp.coo_matrix((np.ones(heads.size, dtype=np.int32), (heads, tails)), shape=(n, n)).tocsr()
    if counts.nnz != heads.size:  # a directed edge used twice: duplicate faces or flipped neighbours
        return False
    return (counts != counts.T.tocsr()).nnz == 0


@dataclass(frozen=True)
class Surface:
    """What the (t, 3) triangles of a mesh of n vertices make (``surface``).

    Attributes
    ----------
    parts : int
        Connected parts: vertices linked through triangles (a vertex on none is a part of its own),
        numbered in the order of their lowest vertex.
    part_of_vertex : (n,) int32 ndarray
    used : (n,) bool ndarray
        The vertices on a triangle.
    closed : (parts,) bool ndarray
        Whether a part's triangles close a consistently oriented surface: every directed edge once,
        and its reverse once (a part without triangles counts as closed: it has nothing open).
    border : (m, 2) int ndarray
        The edges in exactly one triangle, as (low, high) pairs, sorted.
    unmatched : (n,) bool ndarray
        The vertices with a half-edge out or in that has no single reverse: a part is closed where it has
        none. A vertex's own triangles decide it, so a tile of a mesh answers it for the vertices whose
        triangles it holds (core.mesh.tile_volume).
    """

    parts: int
    part_of_vertex: np.ndarray
    used: np.ndarray
    closed: np.ndarray
    border: np.ndarray
    unmatched: np.ndarray


def surface(triangles, n_vertices):
    """The Surface of (t, 3) ``triangles`` on ``n_vertices`` vertices (see ``surface_steps``)."""
    return to_end(surface_steps(triangles, n_vertices))


def surface_steps(triangles, n_vertices):
    """``surface`` in slices (a generator that yields between its passes and returns the Surface): one
    counting sort of the half-edges (each corner to the next) and its transpose, a few bytes a
    half-edge. A vertex whose outgoing half-edges (sorted) equal its incoming ones, none twice, lies
    inside a closed surface; only the others can touch a border edge.

    Examples
    --------
    >>> import numpy as np
    >>> from core.mesh import topology
    >>> tetrahedron = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> whole = topology.surface(tetrahedron, 5)  # and vertex 4 on no triangle
    >>> whole.parts, whole.part_of_vertex.tolist(), whole.closed.tolist(), whole.border.tolist()
    (2, [0, 0, 0, 0, 1], [True, True], [])
    >>> topology.surface(tetrahedron[:3], 4).border.tolist()  # without the face (1, 2, 3)
    [[1, 2], [1, 3], [2, 3]]
    """
    n = int(n_vertices)
    triangles = np.asarray(triangles)
    index = np.int32 if n < np.iinfo(np.int32).max else np.int64
    heads = np.ascontiguousarray(triangles, dtype=index).ravel()
    tails = np.empty_like(heads)
    corners, nexts = heads.reshape(-1, 3), tails.reshape(-1, 3)
    nexts[:, :2], nexts[:, 2] = corners[:, 1:], corners[:, 0]
    del corners, nexts
    indptr, tails = grouped_pairs(heads, tails, n)  # row h: the tails of its half-edges, increasing
    del heads
    yield
    degree = np.diff(indptr)
    twice = np.zeros(tails.size, dtype=bool)  # a pair the row already has (sorted rows: the one before)
    np.equal(tails[1:], tails[:-1], out=twice[1:])
    twice[indptr[:-1][degree > 0]] = False  # a row's first entry follows another row's
    bad = np.zeros(n, dtype=bool)
    if twice.any():
        bad[np.searchsorted(indptr, np.flatnonzero(twice), side="right") - 1] = True
        pattern = sp.csr_matrix((np.ones(tails.size, np.int8), tails, indptr), shape=(n, n), copy=True)
        pattern.sum_duplicates()  # SciPy's strong components do not finish on a pattern with a pair twice
        parts, part_of_vertex = connected_parts(pattern.indptr, pattern.indices, n, cyclic=True)
        del pattern
    else:  # every triangle is a cycle h -> t: the half-edges' strong components are the parts
        parts, part_of_vertex = connected_parts(indptr, tails, n, cyclic=True)
    del twice
    # Row t of the transpose: the heads of the half-edges into t, increasing.
    transposed = sp.csr_matrix((np.ones(tails.size, np.int8), tails, indptr), shape=(n, n), copy=False).tocsc()
    heads, into = transposed.indices, transposed.indptr
    bad |= degree != np.diff(into)
    if np.array_equal(indptr, into):  # every row as long out as in (closed meshes): one comparison
        bad[np.searchsorted(indptr, np.flatnonzero(tails != heads), side="right") - 1] = True
    else:  # row by row, in blocks, where the lengths agree
        for low in range(0, n, _ROW_BLOCK):
            high = min(n, low + _ROW_BLOCK)
            rows = np.arange(low, high)[~bad[low:high]]
            counts = degree[rows]
            offset = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
            wrong = tails[np.repeat(indptr[rows], counts) + offset] != heads[np.repeat(into[rows], counts) + offset]
            bad[np.repeat(rows, counts)[wrong]] = True
    closed = np.bincount(part_of_vertex[bad], minlength=parts) == 0
    border = _border(np.flatnonzero(bad), indptr, tails, into, heads, n).astype(index)
    return Surface(parts, part_of_vertex, degree > 0, closed, border, bad)


def _border(rows, indptr, tails, into, heads, n):
    """(low, high) pairs, sorted, of the edges in one triangle: from the ``rows`` whose half-edges out
    (``indptr``, ``tails``) and in (``into``, ``heads``) differ, the pairs {h, x} with one half-edge
    h -> x or x -> h in all (a self-loop, from a collapsed side, is its own reverse: never once)."""
    keys = []
    for starts, entries in ((indptr, tails), (into, heads)):
        counts = starts[rows + 1] - starts[rows]
        offset = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        other = entries[np.repeat(starts[rows], counts) + offset].astype(np.int64)
        keys.append(np.repeat(rows, counts).astype(np.int64) * n + other)
    key, count = np.unique(np.concatenate(keys), return_counts=True)
    once = key[count == 1]
    pair = np.unique(pair_keys(once // n, once % n, n))
    return np.stack([pair // n, pair % n], axis=1)
