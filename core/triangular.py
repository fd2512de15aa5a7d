"""Sparse lower-triangular solves, the heart of the sequential (Gauss–Seidel) smoothers.

SciPy's public ``spsolve_triangular`` copies the matrix and rewrites its diagonal on every call, which
costs more than the solve itself on large meshes. The system here is fixed for a whole run, so we
prepare it once and call the SuperLU kernel that ``spsolve_triangular`` itself calls (the same
signature in SciPy 1.15 through 1.17); if that private entry point is missing or changes, we fall
back to the public function, which gives the same result more slowly.
"""

import numpy as np
import scipy.sparse as sp

from . import parallel
from scipy.sparse.linalg import spsolve_triangular


try:
    from scipy.sparse.linalg._dsolve._superlu import gstrs as _gstrs
except ImportError:  # pragma: no cover - depends on the SciPy build
    _gstrs = None


def triangular_solver(lower_unit):
    """Return solve(b) -> x with ``lower_unit`` @ x = b for every row of planar ``b`` ((k, n) or (n,),
    C-contiguous, of the matrix dtype; it may be overwritten), for a CSC lower-triangular matrix whose
    diagonal is stored and equal to 1. x is planar too."""
    matrix = sp.csc_matrix(lower_unit)
    matrix.sort_indices()
    n = matrix.shape[0]
    indices = matrix.indices.astype(np.intc, copy=False)
    indptr = matrix.indptr.astype(np.intc, copy=False)
    empty_data = np.zeros(0, dtype=matrix.dtype)
    empty_indices = np.zeros(0, dtype=np.intc)
    empty_indptr = np.zeros(n + 1, dtype=np.intc)

    def fallback(b):
        x = spsolve_triangular(matrix, b.T, lower=True, unit_diagonal=True, overwrite_b=True)
        return np.ascontiguousarray(np.asarray(x).T)

    def kernel(rows):
        """Solve for planar rows (k, n): SuperLU wants them as the columns of a Fortran (n, k) array,
        which is the same memory, and hands back the same layout."""
        x, info = _gstrs("N", n, matrix.nnz, matrix.data, indices, indptr,
                         n, 0, empty_data, empty_indices, empty_indptr, np.asfortranarray(rows.T))
        if info:
            raise ValueError(f"SuperLU gstrs returned {info}")
        return x.T

    def fast(b):
        # SuperLU solves one vector at a time and releases the GIL, so the coordinates are spread
        # over threads; each coordinate's solve is unchanged, so the result is too.
        planar = b.reshape(-1, n)
        groups = _row_groups(planar.shape[0], matrix.nnz)
        try:
            out = np.empty_like(planar)

            def solve_group(rows):
                out[rows] = kernel(planar[rows])

            parallel.run_all([lambda rows=rows: solve_group(rows) for rows in groups])
            return out.reshape(b.shape)
        except (TypeError, ValueError):  # the private kernel changed or failed: the public path from now on
            solver.fast = False
            return fallback(b)

    def solver(b):
        return fast(b) if solver.fast else fallback(b)

    solver.fast = _gstrs is not None and n > 0
    return solver


def _row_groups(count, nnz):
    """Slices of the ``count`` vectors for the threads (one group for one vector or a small system)."""
    if count == 1 or nnz < parallel.MIN_WORK:
        return [slice(None)]
    workers = min(parallel.thread_count(), count)
    bounds = np.linspace(0, count, workers + 1).round().astype(int)
    return [slice(int(start), int(stop)) for start, stop in zip(bounds[:-1], bounds[1:]) if stop > start]
