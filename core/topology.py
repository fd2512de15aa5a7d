"""Which faces close a surface and where it is open: integer work on face corners, no positions.

Blender stores a mesh's faces as corners, each with its vertex and the edge to the next corner of its
face; core callers pass faces as arrays. Both layouts are answered here in O(corners), without a sort.
"""

import numpy as np
import scipy.sparse as sp


def faces_per_edge(n_edges, corner_edges):
    """How many face corners start on each edge (two for an edge inside a surface, one on a border).

    Examples
    --------
    >>> from core import topology
    >>> topology.faces_per_edge(4, [0, 1, 2, 0, 2, 3]).tolist()
    [2, 1, 2, 1]
    """
    return np.bincount(corner_edges, minlength=n_edges)


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
    >>> from core import topology
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


def boundary_vertices(n_vertices, edges, corner_edges):
    """Vertices on an open boundary: on an edge used by exactly one face (edges without faces don't count).

    Examples
    --------
    >>> import numpy as np
    >>> from core import topology
    >>> edges = np.array([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]])
    >>> corner_verts = np.array([0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3])  # a tetrahedron, 4 triangles
    >>> corner_edges = np.array([1, 3, 0, 0, 4, 2, 2, 5, 1, 3, 5, 4])  # each corner's edge to the next
    >>> topology.boundary_vertices(4, edges, corner_edges[:9]).tolist()  # without the face (1, 2, 3)
    [False, True, True, True]
    """
    mask = np.zeros(n_vertices, dtype=bool)
    mask[edges[faces_per_edge(len(edges), corner_edges) == 1].ravel()] = True
    return mask


def closed_from_triangles(triangles):
    """Every directed edge of the (t, 3) triangles is matched by exactly one in the opposite direction.

    Examples
    --------
    >>> import numpy as np
    >>> from core import topology
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
