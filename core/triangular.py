"""Sparse lower-triangular solves, the heart of the sequential (Gauss–Seidel) smoothers.

SciPy's public ``spsolve_triangular`` copies the matrix and rewrites its diagonal on every call, which
costs more than the solve itself on large meshes. The system here is fixed for a whole run, so we
prepare it once and call the SuperLU kernel that ``spsolve_triangular`` itself calls (the same
signature in SciPy 1.15 through 1.17); if that private entry point is missing or changes, we fall
back to the public function, which gives the same result more slowly.
"""

import numpy as np
import scipy.sparse as sp
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

    def fast(b):
        try:
            x, info = _gstrs("N", n, matrix.nnz, matrix.data, indices, indptr,
                             n, 0, empty_data, empty_indices, empty_indptr, np.asfortranarray(b))
        except (TypeError, ValueError):  # the private kernel changed: use the public path from now on
            solver.fast = False
            return fallback(b)
        if info:
            return fallback(b)
        # SuperLU solves column by column (Fortran order); hand the result back row-major, as SpMV wants it.
        return np.ascontiguousarray(x)

    def solver(b):
        # (Solving the columns on separate threads measured slower here: the sweep is memory-bound.)
        return fast(b) if solver.fast else fallback(b)

    solver.fast = _gstrs is not None and n > 0
    return solver
