"""Short-lived arrays on small pages.

NumPy asks the kernel for transparent huge pages on every array of 4 MiB or more (madvise). Where the
kernel compacts memory to find a free huge page at the first touch (Linux's ``defrag`` set to
``madvise``, a common default), a fresh array on a heap that earlier arrays left fragmented costs
milliseconds a megabyte in the kernel. A stage that makes many such arrays once and reads them in order
gains nothing from huge pages (they help the smoothing's gathers, which reuse their arrays step after
step): Keep in Place on a million vertices spent 0.5-0.7 s of system time there after the smoothing,
more than its own work. ``small_pages`` turns NumPy's request off for the arrays made within it.
"""

import contextlib
import threading

try:  # NumPy 2
    from numpy._core.multiarray import _set_madvise_hugepage
except ImportError:  # NumPy 1.x
    try:
        from numpy.core.multiarray import _set_madvise_hugepage
    except ImportError:  # a NumPy without the switch: nothing to turn off
        _set_madvise_hugepage = None

_lock = threading.Lock()
_depth = 0
_before = None


@contextlib.contextmanager
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
    global _depth, _before
    if _set_madvise_hugepage is None:
        yield
        return
    with _lock:
        if _depth == 0:
            _before = _set_madvise_hugepage(False)
        _depth += 1
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0:
                _set_madvise_hugepage(_before)
