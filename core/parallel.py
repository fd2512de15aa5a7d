"""Sparse matrix products spread over CPU cores with threads.

SciPy's sparse kernels release the GIL, so plain threads run them in parallel.
A product is split into row blocks of about equal non-zeros: each output row is computed by exactly
the same loop as in the one-call product, so the results are bit-identical, whatever the thread
count. Small problems stay on one thread: below ~1M non-zeros the hand-off costs more than it saves.

``HC_SMOOTH_THREADS`` (environment) caps the threads; 1 turns this off.
"""

import os
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np

try:  # the kernel behind ``csr_matrix @ dense``; private, so it has a public fallback
    from scipy.sparse._sparsetools import csr_matvecs as _csr_matvecs
except ImportError:  # pragma: no cover - depends on the SciPy build
    _csr_matvecs = None

MIN_WORK = 1_000_000  # non-zeros (times columns) below which one thread is faster
_pool = None
_pool_lock = threading.Lock()


def thread_count():
    try:
        cap = int(os.environ.get("HC_SMOOTH_THREADS", "0"))
    except ValueError:
        cap = 0
    available = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, min(available, cap) if cap > 0 else min(available, 8))


def _executor(workers):
    global _pool
    with _pool_lock:
        if _pool is None or _pool._max_workers < workers:
            _pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="hc_smooth")
        return _pool


def _run_all(tasks):
    """Run the callables, the first on this thread and the rest on the pool; re-raise any error."""
    if len(tasks) == 1:
        tasks[0]()
        return
    futures = [_executor(len(tasks) - 1).submit(task) for task in tasks[1:]]
    tasks[0]()
    for future in futures:
        future.result()


def _row_blocks(indptr, count):
    """Boundaries splitting the rows into ``count`` runs of about equal non-zeros."""
    targets = np.linspace(0, indptr[-1], count + 1)
    bounds = np.searchsorted(indptr, targets, side="left")
    bounds[0], bounds[-1] = 0, indptr.size - 1
    return np.unique(bounds)


def product(matrix):
    """Return ``multiply(x) -> matrix @ x`` for a CSR ``matrix`` and (n,) or (n, k) ``x``, over threads."""
    rows, columns = matrix.shape
    workers = thread_count()
    if workers == 1 or matrix.nnz < MIN_WORK or _csr_matvecs is None:
        return matrix.__matmul__
    bounds = _row_blocks(matrix.indptr, workers)
    blocks = []
    for start, stop in zip(bounds[:-1], bounds[1:]):
        first, last = matrix.indptr[start], matrix.indptr[stop]
        # Views of the matrix arrays (no copy); only the block's indptr is rebased.
        blocks.append((int(start), int(stop), matrix.indptr[start:stop + 1] - first,
                       matrix.indices[first:last], matrix.data[first:last]))

    def multiply(x):
        if x.dtype != matrix.dtype:  # the kernel wants one dtype: let SciPy convert
            return matrix @ x
        x = np.ascontiguousarray(x)
        vectors = 1 if x.ndim == 1 else x.shape[1]
        out = np.zeros((rows,) + x.shape[1:], dtype=x.dtype)
        flat_x = x.reshape(-1)

        def block_task(block):
            start, stop, indptr, indices, data = block
            return lambda: _csr_matvecs(stop - start, columns, vectors, indptr, indices, data, flat_x,
                                        out[start:stop].reshape(-1))

        _run_all([block_task(block) for block in blocks])
        return out

    return multiply
