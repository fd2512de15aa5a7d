"""Sparse lower-triangular solves, the heart of the sequential (Gauss–Seidel) smoothers.

SciPy's public ``spsolve_triangular`` copies the matrix and rewrites its diagonal on every call, which
costs more than the solve itself on large meshes. The system here is fixed for a whole run, so we
prepare it once and call the SuperLU kernel that ``spsolve_triangular`` itself calls (the same
signature in SciPy 1.15 through 1.17); if that private entry point is missing or changes, we fall
back to the public function, which gives the same result more slowly.

All coordinates go to SuperLU in one call, as the columns of one right-hand side. Threads would gain
nothing, since SciPy lets one SuperLU call run at a time, and one call with three columns beats
three calls because most of a call's cost is per row, not per non-zero (figures:
bench/results/2026-11-23-core-speed.md, "The sequential mode and its 1.5× target").
"""

import numpy as np
import scipy.sparse as sp
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

    def fast(b):
        # Planar rows (k, n) are the columns of a Fortran (n, k) array, the same memory, which is
        # SuperLU's layout; it hands back a Fortran (n, k) array, whose transpose is planar again.
        try:
            x, info = _gstrs(
                "N",
                n,
                matrix.nnz,
                matrix.data,
                indices,
                indptr,
                n,
                0,
                empty_data,
                empty_indices,
                empty_indptr,
                b.reshape(-1, n).T,
            )
            if info:
                raise ValueError(f"SuperLU gstrs returned {info}")
        except (TypeError, ValueError):  # the private kernel changed or failed: the public path from now on
            solver.fast = False
            return fallback(b)
        return x.T.reshape(b.shape)

    def solver(b):
        return fast(b) if solver.fast else fallback(b)

    solver.fast = _gstrs is not None and n > 0
    return solver
