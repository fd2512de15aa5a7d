"""Split element-wise NumPy work over the CPU cores with threads.

NumPy's element-wise loops, gathers and sorts release the GIL, so plain threads run them in parallel.
``blocks`` cuts a range into one contiguous block per thread; each block is computed by exactly the
same code as the whole, so results do not depend on the thread count. Small work stays on one
thread. ``HC_SMOOTH_THREADS`` (environment) caps the threads, as for the mesh smoothing.
"""

import os
import threading
from concurrent.futures import ThreadPoolExecutor

MIN_BLOCK = 100_000  # elements per thread below which the hand-off costs more than it saves
_pool = None
_lock = threading.Lock()


def thread_count():
    try:
        cap = int(os.environ.get("HC_SMOOTH_THREADS", "0"))
    except ValueError:
        cap = 0
    available = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, min(available, cap) if cap > 0 else min(available, 8))


def blocks(size, share=1.0):
    """Contiguous (start, stop) blocks covering range(size), one per thread, each at least
    ``share`` x MIN_BLOCK long (share < 1 for work that is heavy per element)."""
    count = max(1, min(thread_count(), int(size // max(share * MIN_BLOCK, 1))))
    bounds = [size * i // count for i in range(count + 1)]
    return list(zip(bounds[:-1], bounds[1:]))


def run_blocks(function, size, share=1.0):
    """[function(start, stop) for each block], the blocks run in parallel threads."""
    parts = blocks(size, share)
    if len(parts) == 1:
        return [function(*parts[0])]
    global _pool
    with _lock:
        if _pool is None or _pool._max_workers < len(parts) - 1:
            _pool = ThreadPoolExecutor(max_workers=len(parts) - 1, thread_name_prefix="hc_points")
        pool = _pool
    futures = [pool.submit(function, *part) for part in parts[1:]]
    try:
        first = function(*parts[0])
    finally:
        rest = [future.result() for future in futures]
    return [first] + rest
