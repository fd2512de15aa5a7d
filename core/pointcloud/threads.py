"""Split element-wise NumPy work over the CPU cores with threads.

NumPy's element-wise loops, gathers and sorts release the GIL, so plain threads run them in parallel.
``blocks`` cuts a range into one contiguous block per thread; each block is computed by exactly the
same code as the whole, so results do not depend on the thread count. Small work stays on one
thread. The threads and their cap (``HC_SMOOTH_THREADS``) are core.parallel's.
"""

from ..parallel import run_all, thread_count

MIN_BLOCK = 100_000  # elements per thread below which the hand-off costs more than it saves


def blocks(size, share=1.0):
    """Contiguous (start, stop) blocks covering range(size), one per thread, each at least
    ``share`` x MIN_BLOCK long (share < 1 for work that is heavy per element)."""
    count = max(1, min(thread_count(), int(size // max(share * MIN_BLOCK, 1))))
    bounds = [size * i // count for i in range(count + 1)]
    return list(zip(bounds[:-1], bounds[1:]))


def run_blocks(function, size, share=1.0):
    """[function(start, stop) for each block], the blocks run in parallel threads (core.parallel's pool)."""
    return run_all([lambda part=part: function(*part) for part in blocks(size, share)])


def run_chunks(function, size, chunk, share=1.0):
    """[function(start, stop) for consecutive chunks of at most ``chunk`` elements], in order (one
    empty chunk for size 0): the chunks of each thread's block run one after another, so the
    temporaries of element-wise work stay small and are reused instead of filling fresh memory."""

    def block(first, last):
        return [function(start, min(start + chunk, last)) for start in range(first, last, chunk)] or [
            function(first, last)
        ]

    return [result for results in run_blocks(block, size, share) for result in results]
