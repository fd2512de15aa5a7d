"""The uniform umbrella operator T of paper section 5: row i averages the positions of adj(i).

Built once per mesh (counting placement into CSR, duplicates merged within each short row)
and reused across iterations, runs and dtypes. Only the sparsity pattern is stored; the smoothers
apply the weights 1/|adj(i)| themselves.

A mesh's edges give a symmetric adj() (j in adj(i) <=> i in adj(j)). Some rules give a vertex fewer
neighbours than its edges do (a border vertex follows only its border, core.mesh.borders): the pattern is
then directed, built from pairs i -> j (``umbrella_from_pairs``, ``Umbrella.with_rows``), and the
smoothers read both triangles of it from the pattern itself.
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


def pair_keys(u: ArrayLike, v: ArrayLike, n: int) -> np.ndarray:
    """int64 keys low * n + high of the unordered vertex pairs (u, v) of a mesh of ``n`` vertices: the same
    key for (a, b) and (b, a), sorted keys sort the pairs. (Elementwise minimum and maximum: a sort of rows
    of two costs four times as much.)

    Examples
    --------
    >>> from core.adjacency import pair_keys
    >>> pair_keys([0, 3, 2], [3, 0, 2], 10).tolist()
    [3, 3, 22]
    """
    u, v = np.asarray(u, dtype=np.int64), np.asarray(v, dtype=np.int64)
    return np.minimum(u, v) * n + np.maximum(u, v)


def _exclusive_cumsum(counts, dtype):
    out = np.zeros(counts.size + 1, dtype=dtype)
    np.cumsum(counts, out=out[1:])
    return out


@dataclass(eq=False)
class Umbrella:
    """The pattern of adj(): row i lists all neighbours of i, increasing. The strict upper triangle by
    rows (row i: neighbours j > i) and the strict lower triangle by columns (column j: the vertices
    i > j with j in adj(i)), which only the sequential smoothers need, are derived on first use; for a
    symmetric pattern they are the same arrays.

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
    symmetric: bool = True  # j in adj(i) <=> i in adj(j)
    _upper: tuple = field(default=None, repr=False)
    _lower: tuple = field(default=None, repr=False)
    _renumbering: object = field(default=None, repr=False)  # core.locality's, once it has looked

    @property
    def upper_indptr(self):
        return self._upper_pattern()[0]

    @property
    def upper_indices(self):
        return self._upper_pattern()[1]

    def _upper_pattern(self):
        if self._upper is None:
            row = self.rows()
            upper = self.indices > row
            counts = np.bincount(row[upper], minlength=self.n_vertices).astype(self.indptr.dtype)
            self._upper = (_exclusive_cumsum(counts, self.indptr.dtype), self.indices[upper])
        return self._upper

    @property
    def lower_columns(self):
        """(indptr, indices) of the strict lower triangle in CSC: column j lists, increasing, the vertices
        i > j whose row holds j."""
        if self.symmetric:
            return self._upper_pattern()
        if self._lower is None:
            rows = self.rows()
            lower = self.indices < rows
            by_column = sp.csr_matrix(
                (np.ones(np.count_nonzero(lower), dtype=np.int8), (self.indices[lower], rows[lower])),
                shape=(self.n_vertices,) * 2,
            )
            self._lower = (by_column.indptr.astype(self.indptr.dtype), by_column.indices.astype(self.indices.dtype))
        return self._lower

    def rows(self):
        """The row of every stored neighbour: (rows(), indices) are the pattern's pairs i -> j."""
        return np.repeat(np.arange(self.n_vertices, dtype=self.indices.dtype), self.degree)

    @property
    def isolated(self):
        """Vertices without neighbours: fixed by the paper's convention (section 2)."""
        return self.degree == 0

    @property
    def n_edges(self):
        """Undirected edges: pairs {i, j} with j in adj(i) or i in adj(j)."""
        if self.symmetric:
            return int(self.indices.size // 2)
        pattern = self._matrix()
        return int((pattern + pattern.T).nnz // 2)

    def _matrix(self):
        data = np.ones(self.indices.size, dtype=np.int8)
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n_vertices,) * 2)

    def renumbered(self, order):
        """The same graph with vertex k of the result being vertex ``order[k]`` of this one."""
        inverse = np.empty(self.n_vertices, dtype=self.indices.dtype)
        inverse[order] = np.arange(self.n_vertices, dtype=self.indices.dtype)
        return _from_pairs(inverse[self.rows()], inverse[self.indices], self.n_vertices, self.symmetric)

    def with_rows(self, vertices: ArrayLike, edges: ArrayLike) -> "Umbrella":
        """This umbrella with adj(i) of every vertex i in ``vertices`` (a boolean mask or indices) made
        of its neighbours along ``edges`` (undirected pairs) alone; every other row stays as it is. A
        listed vertex on none of the edges gets no neighbours (and so stays fixed)."""
        n = self.n_vertices
        listed = np.zeros(n, dtype=bool)
        listed[np.asarray(vertices)] = True
        edges = check_edges(edges, n).astype(self.indices.dtype, copy=False)
        rows = self.rows()
        kept = ~listed[rows]
        heads = np.concatenate((edges[:, 0], edges[:, 1]))
        tails = np.concatenate((edges[:, 1], edges[:, 0]))
        new = listed[heads] & (heads != tails)
        return _from_pairs(
            np.concatenate((rows[kept], heads[new])), np.concatenate((self.indices[kept], tails[new])), n, None
        )


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
    n = _vertex_count(n_vertices)
    edges = check_edges(edges, n)
    index = _index_dtype(n)

    # Both directions of every edge, self-loops dropped.
    rows = np.concatenate((edges[:, 0], edges[:, 1])).astype(index, copy=False)
    columns = np.concatenate((edges[:, 1], edges[:, 0])).astype(index, copy=False)
    loops = rows == columns
    if loops.any():
        rows, columns = rows[~loops], columns[~loops]
    return _from_pairs(rows, columns, n, True)


def umbrella_from_pairs(
    rows: ArrayLike, columns: ArrayLike, n_vertices: int, *, symmetric: bool | None = None
) -> Umbrella:
    """The umbrella with adj(i) = {j : (i, j) among the directed pairs (rows, columns)}: duplicates
    merged, self-loops dropped. Holding both directions of every pair, it equals ``umbrella_operator``.
    ``symmetric``: True if the caller knows that it does (else it is found out).

    Examples
    --------
    >>> import core
    >>> umbrella = core.umbrella_from_pairs([0, 1, 1, 2], [1, 0, 2, 1], 3)  # 2 sees 1, 1 sees 0 and 2, 0 sees 1
    >>> umbrella.degree.tolist(), bool(umbrella.symmetric)
    ([1, 2, 1], True)
    >>> core.umbrella_from_pairs([0, 1], [1, 2], 3).degree.tolist()  # directed: 2 has no neighbour
    [1, 1, 0]
    """
    n = _vertex_count(n_vertices)
    pairs = check_edges(np.stack([np.ravel(rows), np.ravel(columns)], axis=1), n)
    index = _index_dtype(n)
    keep = pairs[:, 0] != pairs[:, 1]
    return _from_pairs(pairs[keep, 0].astype(index), pairs[keep, 1].astype(index), n, symmetric)


def _vertex_count(n_vertices):
    if isinstance(n_vertices, bool) or not isinstance(n_vertices, (int, np.integer)) or n_vertices < 0:
        raise ValueError(f"n_vertices must be a whole number >= 0, got {n_vertices!r}")
    return int(n_vertices)


def _index_dtype(n):
    return np.int32 if n < np.iinfo(np.int32).max // 2 else np.int64


def _from_pairs(rows, columns, n, symmetric):
    """Umbrella from directed pairs (rows sorted and unique). ``symmetric``: True or False if known
    (both directions of every pair present, or not), None to find out."""
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
    umbrella = Umbrella(n_vertices=n, degree=np.diff(indptr), indptr=indptr, indices=indices)
    if symmetric is None:  # the pattern against its transpose (the counts in ``pattern`` may differ)
        ones = umbrella._matrix()
        symmetric = (ones != ones.T).nnz == 0
    umbrella.symmetric = bool(symmetric)
    return umbrella


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


def grouped_pairs(rows, columns, n):
    """(indptr, columns) of the pairs (rows, columns) in [0, n)^2 as a CSR pattern: grouped by row, each
    row's columns increasing, duplicates kept. A counting placement (SciPy's coo -> csr kernel) and an
    in-place sort of each row: about 5 bytes a pair besides the input; where the kernel is missing or
    the indices are not int32, a sort of row * n + column, which takes more time and memory."""
    if _coo_tocsr is not None and rows.dtype == np.int32 and columns.dtype == np.int32:
        indptr, placed, data = np.empty(n + 1, np.int32), np.empty(rows.size, np.int32), np.empty(rows.size, np.int8)
        try:
            _coo_tocsr(n, n, rows.size, rows, columns, np.ones(rows.size, np.int8), indptr, placed, data)
        except (TypeError, ValueError):  # the private kernel changed its signature
            pass
        else:
            pattern = sp.csr_matrix((data, placed, indptr), shape=(n, n), copy=False)
            pattern.has_sorted_indices = False
            pattern.sort_indices()  # in place
            return pattern.indptr, pattern.indices
    order = np.argsort(rows.astype(np.int64) * n + columns, kind="stable")
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=n), out=indptr[1:])
    return indptr, np.asarray(columns)[order]
