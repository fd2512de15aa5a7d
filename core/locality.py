"""Vertex order for cache locality in the simultaneous smoothers.

Every iteration multiplies by the umbrella operator, which gathers the neighbours' positions. When
neighbours sit close in memory (meshes from grids, subdivision, most exporters) those gathers hit
the cache; when the numbering is scattered (some scanners, decimators and file converters) almost
every gather misses, and a product gets many times slower (bench/bench_core.py prints both orders;
bench/results/2026-11-23-core-speed.md, "Random vertex order").
For those meshes the simultaneous smoothers work in reverse Cuthill-McKee order (SciPy's csgraph),
which puts neighbours close together, and hand the result back in the caller's order. The
simultaneous update gives the same positions in any order (up to the rounding of each neighbour
sum); the sequential smoothers are defined by the vertex order and are never renumbered. The mesh
pipeline (core.mesh.smooth) renumbers the whole mesh the same way before its first pass, so that the
noise test, the choice, Keep in Place and the volume restore read neighbours close together too.
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee

MIN_VERTICES = 200_000  # below this the positions stay in cache whatever the order
SCATTERED_GAP = 32_768  # index distance (rows) beyond which a neighbour is typically a cache miss
SAMPLES = 4_096
_BUCKETS = 2**16  # the triangles' order: their first corners to this many ranks (uint16, NumPy's radix sort)


@dataclass(frozen=True)
class Renumbering:
    """Vertex k of the renumbered mesh is vertex ``order[k]`` of the caller's; ``operator`` is the umbrella
    operator in the new numbering.

    Examples
    --------
    >>> import numpy as np
    >>> from core.locality import Renumbering
    >>> renumbering = Renumbering(np.array([2, 0, 1]), None)
    >>> renumbering.rows(np.array([10, 11, 12])).tolist()  # per-vertex values in the new numbering
    [12, 10, 11]
    >>> renumbering.triangles(np.array([[0, 1, 2], [2, 1, 0]])).tolist()  # new numbers, rows by first corner
    [[0, 2, 1], [1, 2, 0]]
    >>> renumbering.scatter(np.array([12, 10, 11])).tolist()  # back in the caller's numbering
    [10, 11, 12]
    """

    order: np.ndarray
    operator: object

    def rows(self, values):
        """Per-vertex ``values`` (rows; None stays None) in the new numbering."""
        return None if values is None else values[self.order]

    def triangles(self, triangles):
        """(t, k) corner indices of the caller's numbering in the new one, the rows in the order of their
        first corners (to a _BUCKETS-th of the vertices): a block of rows then reads and sums at vertices
        close together, where rows in the caller's order (a subdivision's, say) reach all over the mesh."""
        n = self.order.size
        number = np.empty(n, dtype=triangles.dtype)
        number[self.order] = np.arange(n, dtype=triangles.dtype)
        renumbered = number[triangles]
        if renumbered.size == 0:
            return renumbered
        bucket = (renumbered[:, 0].astype(np.int64) * _BUCKETS // n).astype(np.uint16)
        return np.take(renumbered, np.argsort(bucket, kind="stable"), axis=0)  # a radix sort: one pass

    def scatter(self, values):
        """Per-vertex ``values`` of the new numbering back in the caller's."""
        back = np.empty_like(values)
        back[self.order] = values
        return back


def median_gap(operator):
    """Median index distance |i - j| over an even sample of the operator's non-zeros (i, j)."""
    nnz = operator.indices.size
    if nnz == 0:
        return 0
    picks = np.linspace(0, nnz - 1, min(SAMPLES, nnz)).astype(np.int64)
    rows = np.searchsorted(operator.indptr, picks, side="right") - 1
    return int(np.median(np.abs(rows - operator.indices[picks].astype(np.int64))))


def is_scattered(operator):
    return operator.n_vertices >= MIN_VERTICES and median_gap(operator) > SCATTERED_GAP


def renumbering(operator):
    """A cache-friendly renumbering of a scattered mesh (cached on the operator), or None."""
    if operator._renumbering is None:
        if not is_scattered(operator):
            operator._renumbering = False
        else:
            pattern = sp.csr_matrix(
                (np.ones(operator.indices.size, dtype=np.int8), operator.indices, operator.indptr),
                shape=(operator.n_vertices,) * 2,
            )
            order = reverse_cuthill_mckee(pattern, symmetric_mode=operator.symmetric)
            operator._renumbering = Renumbering(order, operator.renumbered(order))
    return operator._renumbering or None
