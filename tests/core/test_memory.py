"""core.memory: NumPy's request for huge pages is off within small_pages and comes back after it."""

import threading

import pytest

from core import memory

pytestmark = pytest.mark.skipif(memory._set_madvise_hugepage is None, reason="this NumPy has no such switch")


def _asked():
    """Whether NumPy asks for huge pages now (reading the switch sets it: set it back)."""
    now = memory._set_madvise_hugepage(True)
    memory._set_madvise_hugepage(now)
    return now


def test_the_request_is_off_inside_and_back_after_nested_and_on_error():
    before = _asked()
    with memory.small_pages():
        assert not _asked()
        with memory.small_pages():
            assert not _asked()
        assert not _asked()  # the outer one still runs
    assert _asked() == before
    with pytest.raises(RuntimeError), memory.small_pages():
        raise RuntimeError("a failed run")
    assert _asked() == before


def test_threads_overlapping_leave_it_as_it_was():
    before, inside, go = _asked(), threading.Event(), threading.Event()

    def worker():
        with memory.small_pages():
            inside.set()
            go.wait(5)

    thread = threading.Thread(target=worker)
    thread.start()
    inside.wait(5)
    with memory.small_pages():
        pass
    assert not _asked()  # the thread's is still open
    go.set()
    thread.join()
    assert _asked() == before
