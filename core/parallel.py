"""Spread NumPy and SciPy work over the CPU cores with threads: row blocks of a sparse matrix, and
blocks of a range for element-wise work.

SciPy's sparse kernels and NumPy's element-wise loops, gathers and sorts release the GIL, so plain
threads run them in parallel. Sparse rows are split into blocks of about equal non-zeros
(``RowBlocks``), a range into contiguous blocks (``run_blocks``, ``run_chunks``); every block is
computed by exactly the same code as the whole, so results are bit-identical whatever the thread
count. Small problems stay on one thread: below ~1M non-zeros, or ~100k elements per thread, the
hand-off costs more than it saves.

``HC_SMOOTH_THREADS`` (environment) caps the threads; 1 turns this off. (The sequential smoothers'
passes run one task per coordinate, so they use three threads whenever threads are on.)
"""

import os
import threading
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np
import scipy.sparse as sp

try:  # the kernel behind ``csr_matrix @ vector`` (y += A x); private, so it has a public fallback
    from scipy.sparse._sparsetools import csr_matvec as _csr_matvec
except ImportError:  # SciPy without the private kernel
    _csr_matvec = None

MIN_WORK = 1_000_000  # non-zeros below which one thread is faster
MIN_BLOCK = 100_000  # elements per thread below which the hand-off costs more than it saves

# Block sizes. Element-wise work goes over its arrays a block at a time: each NumPy call then works on
# temporaries that stay in the cache (a few MB at most, one block per thread), and a pass over a big
# mesh needs no full-size temporaries. The wider an element's temporaries, the smaller its block.
WIDE_BLOCK = 1 << 14  # elements carrying tens of values each (batched fits over a neighbourhood)
TRIANGLE_BLOCK = 1 << 15  # triangles with their corners' coordinates (a dozen float64 each)
BLOCK = 1 << 16  # elements carrying a few values each (a normal, a key, a pair of indices)
VECTOR_BLOCK = 1 << 17  # elements carrying one vector or less (a vertex, a non-zero, a volume term)
PATTERN_BLOCK = 1 << 20  # integer pattern entries alone
_pool = None
_pool_size = 0  # the pool's max_workers, kept here: ThreadPoolExecutor does not expose it
_pool_lock = threading.Lock()
_background = None  # one thread of its own: the pool's threads stay free for the passes


def thread_count():
    try:
        cap = int(os.environ.get("HC_SMOOTH_THREADS", "0"))
    except ValueError:
        cap = 0
    available = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, min(available, cap) if cap > 0 else min(available, 8))


def _executor(workers):
    """The shared pool, replaced by a larger one when it has fewer than ``workers`` threads."""
    global _pool, _pool_size
    with _pool_lock:
        if _pool is None or _pool_size < workers:
            _pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="hc_smooth")
            _pool_size = workers
        return _pool


_on_pool = threading.local()  # ``inside`` is set on the pool's threads while they run a task


def _pool_task(task):
    _on_pool.inside = True
    try:
        return task()
    finally:
        _on_pool.inside = False


def run_all(tasks):
    """Run the callables, the first on this thread and the rest on the pool; return their results in
    order and re-raise any error. Called from a task the pool runs, it runs them one after another
    (the pool's threads are busy: waiting there for more of them could wait for ever)."""
    if len(tasks) == 1 or getattr(_on_pool, "inside", False):
        return [task() for task in tasks]
    futures = [_executor(len(tasks) - 1).submit(_pool_task, task) for task in tasks[1:]]
    try:
        first = tasks[0]()
    finally:
        rest = [future.result() for future in futures]
    return [first] + rest


def in_background(task):
    """A Future of ``task()`` run on a thread of its own, beside whatever runs here meanwhile (its
    NumPy work releases the GIL); with threads off, run now.

    Examples
    --------
    >>> import core
    >>> core.in_background(lambda: 6 * 7).result()
    42
    """
    global _background
    if thread_count() == 1:
        future = Future()
        try:
            future.set_result(task())
        except Exception as error:  # handed over like a thread's: raised by future.result()
            future.set_exception(error)
        return future
    with _pool_lock:
        if _background is None:
            _background = ThreadPoolExecutor(max_workers=1, thread_name_prefix="hc_smooth_background")
    return _background.submit(task)


def _range_blocks(size, share=1.0):
    """Contiguous (start, stop) blocks covering range(size), one per thread, each at least
    ``share`` x MIN_BLOCK long (share < 1 for work that is heavy per element)."""
    count = max(1, min(thread_count(), int(size // max(share * MIN_BLOCK, 1))))
    bounds = [size * i // count for i in range(count + 1)]
    return list(zip(bounds[:-1], bounds[1:]))


def run_blocks(function, size, share=1.0):
    """[function(start, stop) for each block of range(size)], the blocks run in parallel threads."""
    return run_all([lambda part=part: function(*part) for part in _range_blocks(size, share)])


def run_chunks(function, size, chunk, share=1.0):
    """[function(start, stop) for consecutive chunks of at most ``chunk`` elements], in order (one
    empty chunk for size 0): the chunks of each thread's block run one after another, so the
    temporaries of element-wise work stay small and are reused instead of filling fresh memory."""

    def block(first, last):
        return [function(start, min(start + chunk, last)) for start in range(first, last, chunk)] or [
            function(first, last)
        ]

    return [result for results in run_blocks(block, size, share) for result in results]


def _row_blocks(indptr, count):
    """Boundaries splitting the rows into ``count`` runs of about equal non-zeros."""
    targets = np.linspace(0, indptr[-1], count + 1)
    bounds = np.searchsorted(indptr, targets, side="left")
    bounds[0], bounds[-1] = 0, indptr.size - 1
    return np.unique(bounds)


def run_beside(tasks, nonzeros):
    """Run independent tasks whose work is sparse products over a pattern of ``nonzeros`` entries: side by
    side where RowBlocks gives each one thread (the patches the Automatic Amount runs on), else one after
    another, each on the threads. Their results, in order."""
    if thread_count() > 1 and _one_block(nonzeros):
        return run_all(tasks)
    return [task() for task in tasks]


def _one_block(nonzeros):
    """Whether RowBlocks keeps a pattern of ``nonzeros`` entries in one block (one thread)."""
    return nonzeros < MIN_WORK or _csr_matvec is None


class RowBlocks:
    """The rows of a CSR sparsity pattern cut into blocks of about equal non-zeros, one per thread.

    Vectors are planar: one contiguous row per coordinate, shape (k, n) (or (n,) for one). SciPy's
    one-vector kernel on each coordinate row is faster than its multi-vector kernel on (n, k)
    arrays (bench/results/2026-11-23-core-speed.md, "What makes the simultaneous mode fast").

    ``run(task)`` calls ``task(block)`` for every block at once; ``block.rows`` is its slice of rows
    and ``block.neighbour_sums(x, combine)`` multiplies its rows of the 0/1 pattern by ``x``, leaving
    row weights to ``combine``, so one pattern serves every scaling of a matrix. Tasks write only
    their own rows, so they never race; a product reads all of ``x``, so a step that needs the
    product of something computed in the same pass must wait for the next ``run``.
    """

    def __init__(self, indptr, indices, n_columns, workers=None):
        workers = thread_count() if workers is None else workers
        if _one_block(indptr[-1]):
            workers = 1
        self.n_rows, self.n_columns = indptr.size - 1, n_columns
        bounds = _row_blocks(indptr, workers) if self.n_rows else np.array([0, 0])
        self.blocks = [
            _Block(indptr, indices, n_columns, int(start), int(stop)) for start, stop in zip(bounds[:-1], bounds[1:])
        ]

    def run(self, task):
        run_all([lambda block=block: task(block) for block in self.blocks])


CHUNK_NONZEROS = VECTOR_BLOCK  # a chunk's pattern and rows stay in cache for all the coordinates


class _Block:
    def __init__(self, indptr, indices, n_columns, start, stop):
        self.rows = slice(start, stop)
        self._first, self._last = int(indptr[start]), int(indptr[stop])
        self._n_columns = n_columns
        # Chunks of rows with about CHUNK_NONZEROS non-zeros each: the product runs chunk by chunk,
        # every coordinate of a chunk before the next, so the chunk's slice of the matrix is read
        # from memory once instead of once per coordinate.
        # Views of the pattern (no copy); only each chunk's indptr is rebased.
        count = max(1, -(-(self._last - self._first) // CHUNK_NONZEROS))
        bounds = start + _row_blocks(indptr[start : stop + 1] - self._first, count)
        self._chunks = []
        for low, high in zip(bounds[:-1], bounds[1:]):
            first, last = int(indptr[low]), int(indptr[high])
            self._chunks.append((int(low), int(high), first, last, indptr[low : high + 1] - first, indices[first:last]))
        self._longest_chunk = max((chunk[3] - chunk[2] for chunk in self._chunks), default=0)
        self._widest_chunk = max((chunk[1] - chunk[0] for chunk in self._chunks), default=0)

    def neighbour_sums(self, x, combine):
        """For each chunk of rows: the sums of planar ``x`` over each row's pattern (A @ x with A the
        0/1 matrix of the pattern), handed to ``combine(chunk_rows, sums)`` ((k, rows) array, free
        to overwrite) while they are in cache.

        Row weights belong in ``combine``: the product then reads no values array, only the chunk's
        pattern and a short array of ones that stays in cache (a weighted matrix's values would be a
        third of the memory traffic; bench/results/2026-11-23-core-speed.md, "no weighted matrix")."""
        x_rows = x.reshape(-1, x.shape[-1])
        ones = _ones(x.dtype, self._longest_chunk)
        buffer = np.empty((x_rows.shape[0], self._widest_chunk), dtype=x.dtype)
        for low, high, first, last, chunk_indptr, chunk_indices in self._chunks:
            sums = buffer[:, : high - low]
            sums[...] = 0.0
            if not _private_sums(
                high - low, self._n_columns, chunk_indptr, chunk_indices, ones[: last - first], x_rows, sums
            ):
                # The public product: per row the same sum in the same order, so the same bits.
                part = sp.csr_matrix(
                    (ones[: last - first], chunk_indices, chunk_indptr), shape=(high - low, self._n_columns)
                )
                sums += (part @ x_rows.T).T
            combine(slice(low, high), sums)


def _private_sums(n_rows, n_columns, indptr, indices, data, x_rows, sums):
    """sums[k] += A x_rows[k] by SciPy's private kernel; False (sums zero) where it is missing or
    refuses the call, and from then on the public path."""
    global _csr_matvec
    kernel = _csr_matvec
    if kernel is None:
        return False
    try:
        for x_row, sum_row in zip(x_rows, sums):
            kernel(n_rows, n_columns, indptr, indices, data, x_row, sum_row)
    except (TypeError, ValueError):  # the private kernel changed its signature
        _csr_matvec = None
        sums[...] = 0.0
        return False
    return True


_ones_cache = {}
_ones_lock = threading.Lock()


def _ones(dtype, size):
    """A read-only array of ``size`` ones, shared by every block and call."""
    key = np.dtype(dtype)
    with _ones_lock:
        ones = _ones_cache.get(key)
        if ones is None or ones.size < size:
            ones = np.ones(max(size, 1), dtype=key)
            ones.flags.writeable = False
            _ones_cache[key] = ones
        return ones
