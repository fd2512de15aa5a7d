"""Threaded products and solves give bit-identical results to the one-thread path."""

import numpy as np
import pytest
import scipy.sparse as sp

import core
from core import parallel


def grid_edges(side):
    index = np.arange(side * side).reshape(side, side)
    right = np.stack([index[:, :-1].ravel(), index[:, 1:].ravel()], axis=1)
    down = np.stack([index[:-1, :].ravel(), index[1:, :].ravel()], axis=1)
    diagonal = np.stack([index[:-1, :-1].ravel(), index[1:, 1:].ravel()], axis=1)
    return np.concatenate([right, down, diagonal])


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("mode", ["simultaneous", "sequential"])
@pytest.mark.parametrize("method", ["hc", "original"])
def test_threads_change_nothing_but_speed(monkeypatch, dtype, mode, method):
    rng = np.random.default_rng(5)
    side = 40
    edges = rng.permutation(grid_edges(side))
    positions = rng.normal(size=(side * side, 3)).astype(dtype)
    fixed = rng.random(side * side) < 0.1
    kwargs = dict(method=method, alpha=0.2, beta=0.7, iterations=6, mode=mode, fixed=fixed)

    monkeypatch.setattr(parallel, "thread_count", lambda: 1)
    one = core.smooth(positions, edges, **kwargs).positions
    monkeypatch.setattr(parallel, "thread_count", lambda: 3)
    monkeypatch.setattr(parallel, "MIN_WORK", 0)
    threaded = core.smooth(positions, edges, **kwargs).positions
    assert threaded.dtype == dtype
    assert np.array_equal(threaded.view(np.uint8), one.view(np.uint8))


def test_row_blocks_cover_every_row_once():
    indptr = np.array([0, 5, 5, 6, 20, 21, 40])
    bounds = parallel._row_blocks(indptr, 3)
    assert bounds[0] == 0 and bounds[-1] == 6 and np.all(np.diff(bounds) > 0)


@pytest.mark.parametrize("threads", ["1", "3"])
@pytest.mark.parametrize("size, chunk", [(0, 4), (1, 4), (10, 3), (10, 10), (250_000, 70_000)])
def test_chunks_cover_the_range_in_order_each_at_most_chunk_long(monkeypatch, threads, size, chunk):
    from core.parallel import run_chunks

    monkeypatch.setenv("HC_SMOOTH_THREADS", threads)
    parts = run_chunks(lambda start, stop: (start, stop), size, chunk)
    starts, stops = np.array(parts).T
    assert starts[0] == 0 and stops[-1] == size and np.array_equal(starts[1:], stops[:-1])
    assert np.all(stops - starts <= chunk) and (size == 0 or np.all(stops > starts))
    assert len(parts) >= -(-size // chunk)


def test_thread_cap_from_the_environment(monkeypatch):
    monkeypatch.delenv("HC_SMOOTH_THREADS", raising=False)
    uncapped = parallel.thread_count()
    monkeypatch.setattr(parallel.os, "sched_getaffinity", lambda pid: set(range(12)), raising=False)
    assert parallel.thread_count() == 8  # no cap: the available cores, at most 8
    monkeypatch.setenv("HC_SMOOTH_THREADS", "1")
    assert parallel.thread_count() == 1
    monkeypatch.setenv("HC_SMOOTH_THREADS", "3")
    assert parallel.thread_count() == 3
    monkeypatch.setenv("HC_SMOOTH_THREADS", "20")
    assert parallel.thread_count() == 12  # a cap above the cores: the cores
    for ignored in ("not a number", "0", "-2"):  # as if unset
        monkeypatch.setenv("HC_SMOOTH_THREADS", ignored)
        assert parallel.thread_count() == 8
    monkeypatch.undo()
    monkeypatch.setenv("HC_SMOOTH_THREADS", "not a number")
    assert parallel.thread_count() == uncapped


def test_pool_grows_to_the_largest_request(monkeypatch):
    # run_all hands all tasks but the first to the shared pool; a barrier that every task must reach
    # before any can finish only passes when the pool has a thread for each of them.
    import threading

    monkeypatch.setattr(parallel, "_pool", None)
    monkeypatch.setattr(parallel, "_pool_size", 0)
    for count in (2, 4, 3):
        barrier = threading.Barrier(count, timeout=10)
        names = parallel.run_all([lambda barrier=barrier: (barrier.wait(), threading.current_thread().name)[1]] * count)
        assert len(set(names)) == count
    assert parallel._executor(1) is parallel._executor(3)  # big enough: kept


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("mode", ["simultaneous", "sequential"])
@pytest.mark.parametrize("method", ["hc", "central", "plain"])
def test_public_product_path_when_the_private_kernel_is_missing(monkeypatch, method, mode, dtype):
    # SciPy's csr_matvec is private: without it the blocks multiply through the public API, which
    # sums every row in the same order, so the results are bit-identical.
    rng = np.random.default_rng(8)
    side = 12
    edges = grid_edges(side)
    positions = rng.normal(size=(side * side, 3)).astype(dtype)
    kwargs = dict(method=method, alpha=0.3, beta=0.6, iterations=4, fixed=[0, 5, 77], mode=mode)
    fast = core.smooth(positions, edges, **kwargs).positions
    monkeypatch.setattr(parallel, "_csr_matvec", None)
    public = core.smooth(positions, edges, **kwargs).positions
    assert public.dtype == dtype
    assert np.array_equal(public.view(np.uint8), fast.view(np.uint8))
    assert np.array_equal(public[[0, 5, 77]], positions[[0, 5, 77]])


@pytest.mark.parametrize("mode", ["simultaneous", "sequential"])
def test_a_changed_private_kernel_switches_to_the_public_product(monkeypatch, mode):
    # A csr_matvec that refuses our call (a changed signature) is dropped at the first chunk; that
    # chunk and every later product take the public path, with the same bits.
    rng = np.random.default_rng(11)
    side = 20
    edges = rng.permutation(grid_edges(side))
    positions = rng.normal(size=(side * side, 3))
    kwargs = dict(method="hc", alpha=0.2, beta=0.7, iterations=5, mode=mode)
    monkeypatch.setattr(parallel, "CHUNK_NONZEROS", 100)  # many chunks per product
    expected = core.smooth(positions, edges, **kwargs).positions
    calls = []

    def changed(*args):
        calls.append(len(args))
        raise TypeError("csr_matvec() takes different arguments now")

    monkeypatch.setattr(parallel, "_csr_matvec", changed)
    got = core.smooth(positions, edges, **kwargs).positions
    assert np.array_equal(got.view(np.uint8), expected.view(np.uint8))
    # Tried once per task that was already running (the sequential passes run one per coordinate),
    # then the public path for good.
    assert 1 <= len(calls) <= 3 and parallel._csr_matvec is None


@pytest.mark.parametrize("mode", ["simultaneous", "sequential"])
def test_chunked_products_change_nothing(monkeypatch, mode):
    # Products run chunk by chunk (all coordinates of a chunk first); every row is still computed by
    # the same loop, so the results are bit-identical to one chunk.
    rng = np.random.default_rng(6)
    side = 30
    edges = rng.permutation(grid_edges(side))
    positions = rng.normal(size=(side * side, 3))
    kwargs = dict(method="hc", alpha=0.1, beta=0.6, iterations=5, mode=mode, fixed=rng.random(side * side) < 0.2)
    whole = core.smooth(positions, edges, **kwargs).positions
    monkeypatch.setattr(parallel, "CHUNK_NONZEROS", 37)
    monkeypatch.setattr(parallel, "MIN_WORK", 0)
    monkeypatch.setattr(parallel, "thread_count", lambda: 2)
    chunked = core.smooth(positions, edges, **kwargs).positions
    assert np.array_equal(chunked.view(np.uint8), whole.view(np.uint8))
    blocks = parallel.RowBlocks(*_pattern(edges, side * side))
    assert sum(len(block._chunks) for block in blocks.blocks) > 10


def _pattern(edges, n):
    operator = core.umbrella_operator(edges, n)
    return operator.indptr, operator.indices, n


def test_sequential_passes_run_one_thread_per_coordinate(monkeypatch):
    # The passes around the Gauss-Seidel solve are split by coordinate; the tasks really run on other
    # threads when threads are on, and never when HC_SMOOTH_THREADS=1.
    import threading

    rng = np.random.default_rng(9)
    side = 20
    edges = grid_edges(side)
    positions = rng.normal(size=(side * side, 3))
    kwargs = dict(alpha=0.1, beta=0.6, iterations=3, mode="sequential")
    seen = set()
    original_run_all = parallel.run_all

    def recording_run_all(tasks):
        return original_run_all([lambda task=task: (seen.add(threading.get_ident()), task())[1] for task in tasks])

    monkeypatch.setattr(parallel, "run_all", recording_run_all)
    monkeypatch.setattr(parallel, "MIN_WORK", 0)
    monkeypatch.setenv("HC_SMOOTH_THREADS", "1")
    alone = core.hc_smooth(positions, edges, **kwargs)
    assert seen == set()
    monkeypatch.setenv("HC_SMOOTH_THREADS", "2")
    threaded = core.hc_smooth(positions, edges, **kwargs)
    assert len(seen) >= 2
    assert np.array_equal(threaded.view(np.uint8), alone.view(np.uint8))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_neighbour_sums_are_the_pattern_product(monkeypatch, dtype):
    # Each chunk's sums equal the 0/1 pattern times x (per coordinate); the shared array of ones
    # they multiply by stays read-only and all ones.
    rng = np.random.default_rng(10)
    side = 25
    n = side * side
    monkeypatch.setattr(parallel, "CHUNK_NONZEROS", 50)
    blocks = parallel.RowBlocks(*_pattern(grid_edges(side), n), workers=2)
    x = rng.normal(size=(3, n)).astype(dtype)
    got = np.full((3, n), np.nan, dtype=dtype)

    def combine(rows, sums):
        got[:, rows] = sums

    blocks.run(lambda block: block.neighbour_sums(x, combine))
    indptr, indices, _ = _pattern(grid_edges(side), n)
    pattern = sp.csr_matrix((np.ones(indices.size), indices, indptr), shape=(n, n))
    np.testing.assert_allclose(
        got, (pattern @ x.T.astype(np.float64)).T, rtol=0, atol=1e-5 if dtype == np.float32 else 1e-13
    )
    ones = parallel._ones(dtype, 1)
    assert not ones.flags.writeable and np.all(ones == 1)


@pytest.mark.parametrize("threads", [1, 2])
def test_in_background_hands_back_the_result_or_the_error(monkeypatch, threads):
    monkeypatch.setattr(parallel, "thread_count", lambda: threads)
    assert parallel.in_background(lambda: 6 * 7).result() == 42
    with pytest.raises(ZeroDivisionError):
        parallel.in_background(lambda: 1 / 0).result()


def test_run_all_inside_a_pool_task_runs_there():
    """A task the pool runs that runs tasks itself runs them on its own thread: waiting there for the
    pool's other threads could wait for ever (the pool may have no other)."""
    import threading

    def nested():
        return threading.get_ident(), parallel.run_all([threading.get_ident, threading.get_ident])

    here, (pool_thread, inner) = parallel.run_all([threading.get_ident, nested])
    assert pool_thread != here and inner == [pool_thread, pool_thread]
