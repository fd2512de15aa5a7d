"""Short-lived arrays on small pages.

NumPy asks the kernel for transparent huge pages on every array of 4 MiB or more (madvise). Where the
kernel compacts memory to find a free huge page at the first touch (Linux's ``defrag`` set to
``madvise``, a common default), a fresh array on a heap that earlier arrays left fragmented costs
milliseconds a megabyte in the kernel. A stage that makes many such arrays once and reads them in order
gains nothing from huge pages (they help the smoothing's gathers, which reuse their arrays step after
step): Keep in Place on a million vertices spent 0.5-0.7 s of system time there after the smoothing,
more than its own work. ``small_pages`` turns NumPy's request off for the arrays made within it.

The other cost is the same first touch of arrays that were there a moment before. glibc's malloc gives
each big block its own mapping (from 128 KiB, a threshold it raises up to 32 MiB as such blocks are freed)
and hands it back when it is freed (and trims its heap as soon as enough of its top is free): a run that
makes and frees arrays of the mesh's size pass after pass gets fresh pages from the kernel for each, and
the kernel zeroes (and, on huge pages, compacts) them on every first touch. Keep Sharp Edges on a million
vertices spent 3.3-3.6 s of system time there, a point cloud of a million points 9-10 s. ``reused_memory``
keeps what is freed within it in the heap for the next arrays (no block gets its own mapping, the heap is
not trimmed); when it ends, glibc maps and trims again, from the thresholds its own adjustment reaches in
a process that frees big arrays (setting them ends that adjustment: from the defaults, every array over
128 KiB would be mapped afresh). ``reusing`` runs each slice of a run's generator within it and hands the
free memory back to the kernel (``malloc_trim``) when the run ends. Elsewhere (another C library, or a
malloc that replaces glibc's) they do nothing.
"""

import contextlib
import ctypes
import platform
import threading

try:  # NumPy 2
    from numpy._core.multiarray import _set_madvise_hugepage
except ImportError:  # NumPy 1.x
    try:
        from numpy.core.multiarray import _set_madvise_hugepage
    except ImportError:  # a NumPy without the switch: nothing to turn off
        _set_madvise_hugepage = None


class _Switch:
    """A process-wide setting turned on by the first of nested or threaded uses and back by the last:
    ``on()`` returns what ``off(state)`` sets back."""

    def __init__(self, on, off):
        self.on, self.off = on, off
        self.lock, self.depth, self.state = threading.Lock(), 0, None

    @contextlib.contextmanager
    def held(self):
        with self.lock:
            if self.depth == 0:
                self.state = self.on()
            self.depth += 1
        try:
            yield
        finally:
            with self.lock:
                self.depth -= 1
                if self.depth == 0:
                    self.off(self.state)


_small = _Switch(lambda: _set_madvise_hugepage(False), lambda before: _set_madvise_hugepage(before))


def small_pages():
    """Within it NumPy does not ask for huge pages for new arrays (nested and threaded uses are counted:
    the setting comes back when the last one ends).

    Examples
    --------
    >>> import numpy as np
    >>> from core.memory import small_pages
    >>> with small_pages():
    ...     values = np.zeros(1 << 20)
    >>> float(values.sum())
    0.0
    """
    return contextlib.nullcontext() if _set_madvise_hugepage is None else _small.held()


# mallopt's parameters (glibc's malloc.h); glibc's default count of mappings; the thresholds where its own
# adjustment takes them in a process that frees big arrays (its largest mapping threshold, 32 MiB on 64
# bits, and twice that for trimming): ``roomy_heap``'s.
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD, _M_MMAP_MAX = -1, -3, -4
_MMAP_MAX = 65536
MMAP_THRESHOLD, TRIM_THRESHOLD = 32 << 20, 64 << 20
_KEPT_TRIM_THRESHOLD = 1 << 30  # no trimming within reused_memory (mallopt takes a C int)


def _glibc():
    """glibc's mallopt and malloc_trim, or None where the C library is another."""
    if platform.system() != "Linux" or platform.libc_ver()[0] != "glibc":
        return None
    try:
        libc = ctypes.CDLL("libc.so.6")
        return libc if hasattr(libc, "mallopt") and hasattr(libc, "malloc_trim") else None
    except OSError:
        return None


_LIBC = _glibc()


def _keep_freed():
    _LIBC.mallopt(_M_MMAP_MAX, 0)
    _LIBC.mallopt(_M_TRIM_THRESHOLD, _KEPT_TRIM_THRESHOLD)


def _map_and_trim(_):
    _LIBC.mallopt(_M_MMAP_MAX, _MMAP_MAX)
    roomy_heap()


def roomy_heap():
    """glibc maps (and hands back when freed) only blocks of ``MMAP_THRESHOLD`` or more, and trims its heap
    once ``TRIM_THRESHOLD`` is free at its top: a process's heap keeps large freed arrays for the next
    ones. Where the environment fixed the thresholds at glibc's defaults (Dask's nanny starts its workers
    with ``MALLOC_TRIM_THRESHOLD_``, which pins mapping at 128 KiB) every such array is mapped and faulted
    in anew (a batch took 1.6 times as long, most of it system time: bench/README.md, "batch"). Returns
    whether they were set (glibc only; elsewhere nothing changes).

    Examples
    --------
    >>> from core.memory import roomy_heap
    >>> roomy_heap() in (True, False)
    True
    """
    if _LIBC is None:
        return False
    return bool(_LIBC.mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and bool(
        _LIBC.mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD)
    )


_reused = _Switch(_keep_freed, _map_and_trim)


def reused_memory():
    """Within it memory freed stays in the heap for the next arrays (glibc; nested and threaded uses are
    counted: glibc maps and trims again when the last one ends).

    Examples
    --------
    >>> import numpy as np
    >>> from core.memory import reused_memory
    >>> with reused_memory():
    ...     values = np.ones(1 << 20)
    >>> float(values.sum())
    1048576.0
    """
    return contextlib.nullcontext() if _LIBC is None else _reused.held()


def hand_back():
    """The heap's free memory back to the kernel (glibc's malloc_trim), at the end of a run. (Not between a
    point cloud's stages: their arrays differ, yet its EMST, graph and mesh reuse each other's memory: 2-3 s
    of system time at a million points, for a peak 5-8 % higher.)

    Examples
    --------
    >>> from core.memory import hand_back
    >>> hand_back()
    """
    if _LIBC is not None:
        _LIBC.malloc_trim(0)


def reusing(steps):
    """The slices of the generator ``steps``, each run within ``reused_memory`` (what one slice frees, the
    next reuses), and its value; the free memory goes back to the kernel when it ends or is closed.

    Examples
    --------
    >>> from core.memory import reusing
    >>> def run():
    ...     yield 0.5
    ...     return "done"
    >>> def caller():
    ...     result = yield from reusing(run())
    ...     print(result)
    >>> list(caller())
    done
    [0.5]
    """
    try:
        while True:
            with reused_memory():
                try:
                    value = next(steps)
                except StopIteration as done:
                    return done.value
            yield value
    finally:
        steps.close()
        hand_back()
