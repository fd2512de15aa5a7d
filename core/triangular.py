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
    """Return solve(b) -> x with ``lower_unit`` @ x = b, for a CSC lower-triangular matrix whose diagonal
    is stored and equal to 1. ``b`` is (n,) or (n, k) of the matrix dtype and may be overwritten."""
    matrix = sp.csc_matrix(lower_unit)
    matrix.sort_indices()
    n = matrix.shape[0]
    indices = matrix.indices.astype(np.intc, copy=False)
    indptr = matrix.indptr.astype(np.intc, copy=False)
    empty_data = np.zeros(0, dtype=matrix.dtype)
    empty_indices = np.zeros(0, dtype=np.intc)
    empty_indptr = np.zeros(n + 1, dtype=np.intc)

    def fallback(b):
        return spsolve_triangular(matrix, b, lower=True, unit_diagonal=True, overwrite_b=True)

    def kernel(b):
        x, info = _gstrs("N", n, matrix.nnz, matrix.data, indices, indptr,
                         n, 0, empty_data, empty_indices, empty_indptr, np.asfortranarray(b))
        if info:
            raise ValueError(f"SuperLU gstrs returned {info}")
        return x

    def fast(b):
        # SuperLU solves column by column and releases the GIL, so the columns (x, y, z) are spread
        # over threads; each column's solve is unchanged, so the result is too. It comes back
        # row-major, as the sparse products want it.
        groups = _column_groups(b, matrix.nnz)
        try:
            if len(groups) == 1:
                return np.ascontiguousarray(kernel(b))
            out = np.empty(b.shape, dtype=b.dtype)

            def solve_group(columns):
                out[:, columns] = kernel(b[:, columns])

            parallel._run_all([lambda columns=columns: solve_group(columns) for columns in groups])
            return out
        except (TypeError, ValueError):  # the private kernel changed or failed: the public path from now on
            solver.fast = False
            return fallback(b)

    def solver(b):
        return fast(b) if solver.fast else fallback(b)

    solver.fast = _gstrs is not None and n > 0
    return solver


def _column_groups(b, nnz):
    """Slices of the columns of ``b`` for the threads (one group for a vector or a small system)."""
    if b.ndim == 1 or b.shape[1] == 1 or nnz < parallel.MIN_WORK:
        return [slice(None)]
    workers = min(parallel.thread_count(), b.shape[1])
    bounds = np.linspace(0, b.shape[1], workers + 1).round().astype(int)
    return [slice(int(start), int(stop)) for start, stop in zip(bounds[:-1], bounds[1:]) if stop > start]
