"""The uniform umbrella operator T of paper section 5: row i averages the positions of adj(i).

Built once per mesh (counting placement into CSR, duplicates merged within each short row)
and reused across iterations, runs and dtypes. Only the sparsity pattern is stored; the smoothers
apply the weights 1/|adj(i)| themselves.
"""

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from .validation import check_edges

try:  # the kernels behind coo -> csr and csr -> csc; private, so pairs_in_order has a public fallback
    from scipy.sparse._sparsetools import coo_tocsr as _coo_tocsr
    from scipy.sparse._sparsetools import csr_tocsc as _csr_tocsc
except ImportError:  # SciPy without them
    _coo_tocsr = _csr_tocsc = None


def _exclusive_cumsum(counts, dtype):
    out = np.zeros(counts.size + 1, dtype=dtype)
    np.cumsum(counts, out=out[1:])
    return out


@dataclass(eq=False)
class Umbrella:
    """The pattern of adj(): row i lists all neighbours of i, increasing. Made by ``umbrella_operator``.

    The upper triangle (row i: neighbours j > i, i.e. each edge once), which only the sequential
    smoothers need, is derived on first use.

    Attributes
    ----------
    n_vertices : int
    degree : (n,) int ndarray
        |adj(i)|.
    indptr, indices : int ndarrays
        The CSR pattern: the neighbours of i are ``indices[indptr[i]:indptr[i + 1]]``, increasing.
    isolated : (n,) bool ndarray
        Vertices without neighbours (fixed, paper section 2).
    n_edges : int
        Distinct edges.

    Examples
    --------
    >>> import core
    >>> umbrella = core.umbrella_operator([[0, 1], [1, 2], [2, 0], [1, 0], [3, 3]], 5)
    >>> umbrella.n_edges, umbrella.degree.tolist(), umbrella.isolated.tolist()
    (3, [2, 2, 2, 0, 0], [False, False, False, True, True])
    >>> umbrella.indices[umbrella.indptr[1] : umbrella.indptr[2]].tolist()
    [0, 2]
    """

    n_vertices: int
    degree: np.ndarray  # |adj(i)|
    indptr: np.ndarray
    indices: np.ndarray
    _upper: tuple = field(default=None, repr=False)
    _renumbering: object = field(default=None, repr=False)  # core.locality's, once it has looked

    @property
    def upper_indptr(self):
        return self._upper_pattern()[0]

    @property
    def upper_indices(self):
        return self._upper_pattern()[1]

    def _upper_pattern(self):
        if self._upper is None:
            row = np.repeat(np.arange(self.n_vertices, dtype=self.indices.dtype), self.degree)
            upper = self.indices > row
            counts = np.bincount(row[upper], minlength=self.n_vertices).astype(self.indptr.dtype)
            self._upper = (_exclusive_cumsum(counts, self.indptr.dtype), self.indices[upper])
        return self._upper

    @property
    def isolated(self):
        """Vertices without neighbours: fixed by the paper's convention (section 2)."""
        return self.degree == 0

    @property
    def n_edges(self):
        return int(self.indices.size // 2)

    def renumbered(self, order):
        """The same graph with vertex k of the result being vertex ``order[k]`` of this one."""
        inverse = np.empty(self.n_vertices, dtype=self.indices.dtype)
        inverse[order] = np.arange(self.n_vertices, dtype=self.indices.dtype)
        rows = inverse[np.repeat(np.arange(self.n_vertices, dtype=self.indices.dtype), self.degree)]
        return _from_pairs(rows, inverse[self.indices], self.n_vertices)


def umbrella_operator(edges: ArrayLike, n_vertices: int) -> Umbrella:
    """Build the umbrella structure of a mesh with ``n_vertices`` vertices from its undirected edges.

    Build it once and pass it as ``operator=`` to every smoother that runs on the same mesh.

    Parameters
    ----------
    edges : (m, 2) array_like of int
        Vertex pairs. Order, direction and duplicates do not matter; self-loops are ignored.
    n_vertices : int
        Vertex count (vertices on no edge are isolated).

    Returns
    -------
    Umbrella

    Raises
    ------
    ValueError
        ``edges`` not integer pairs of shape (m, 2), an index outside [0, n_vertices), or
        ``n_vertices`` not a whole number >= 0.

    Examples
    --------
    >>> import numpy as np, core
    >>> positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> operator = core.umbrella_operator([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]], 4)
    >>> operator.degree.tolist()
    [3, 3, 3, 3]
    >>> core.hc_smooth(positions, None, operator=operator, alpha=0.1, beta=0.6, iterations=1).shape
    (4, 3)
    """
    if isinstance(n_vertices, bool) or not isinstance(n_vertices, (int, np.integer)) or n_vertices < 0:
        raise ValueError(f"n_vertices must be a whole number >= 0, got {n_vertices!r}")
    n = int(n_vertices)
    edges = check_edges(edges, n)
    index = np.int32 if n < np.iinfo(np.int32).max // 2 else np.int64

    # Both directions of every edge, self-loops dropped.
    rows = np.concatenate((edges[:, 0], edges[:, 1])).astype(index, copy=False)
    columns = np.concatenate((edges[:, 1], edges[:, 0])).astype(index, copy=False)
    loops = rows == columns
    if loops.any():
        rows, columns = rows[~loops], columns[~loops]
    return _from_pairs(rows, columns, n)


def _from_pairs(rows, columns, n):
    """Umbrella from directed pairs holding both directions of every edge: rows sorted and unique."""
    index = rows.dtype
    placed = pairs_in_order(rows, columns, n, np.ones(rows.size, dtype=np.int8))
    if placed is not None:
        pattern = sp.csr_matrix(placed[::-1], shape=(n, n))
    else:  # SciPy's public coo -> csr (placement by counting, then a sort of every row)
        pattern = sp.coo_matrix((np.ones(rows.size, dtype=np.int8), (rows, columns)), shape=(n, n)).tocsr()
    del rows, columns
    pattern.sum_duplicates()  # one linear check when rows are sorted and unique already
    indptr = pattern.indptr.astype(index, copy=False)
    indices = pattern.indices.astype(index, copy=False)
    return Umbrella(n_vertices=n, degree=np.diff(indptr), indptr=indptr, indices=indices)


def pairs_in_order(rows, columns, n, data):
    """(indptr, columns, data) of the pairs (rows, columns) in [0, n)^2 sorted by row, then column,
    then input position (a stable sort by row * n + column), as CSR arrays; None where SciPy's
    kernels are missing or refuse the call (changed), or the indices are not int32: callers then
    take a public path to the same result.

    Two counting passes (SciPy's coo -> csr and csr -> csc kernels, O(pairs), no comparison sort):
    placing the pairs by column keeps each column's entries in input order, and transposing by
    counting then lists every row's entries by column, ties in that order.
    """
    if _coo_tocsr is None or rows.dtype != np.int32 or columns.dtype != np.int32:
        return None
    count = rows.size
    by_column = (np.empty(n + 1, np.int32), np.empty(count, np.int32), np.empty(count, data.dtype))
    by_row = (np.empty(n + 1, np.int32), np.empty(count, np.int32), np.empty(count, data.dtype))
    try:
        _coo_tocsr(n, n, count, columns, rows, data, *by_column)
        _csr_tocsc(n, n, *by_column, *by_row)
    except (TypeError, ValueError):  # the private kernels changed their signature
        return None
    return by_row
