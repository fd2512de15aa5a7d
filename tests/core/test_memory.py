"""core.memory: NumPy's request for huge pages is off within small_pages and comes back after it; memory
freed within reused_memory is reused, and a run's slices hand it back at its end."""

import resource
import threading

import numpy as np
import pytest
import small_meshes

import core
from core import memory

switch = pytest.mark.skipif(memory._set_madvise_hugepage is None, reason="this NumPy has no such switch")


def _asked():
    """Whether NumPy asks for huge pages now (reading the switch sets it: set it back)."""
    now = memory._set_madvise_hugepage(True)
    memory._set_madvise_hugepage(now)
    return now


@switch
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


@switch
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


glibc = pytest.mark.skipif(memory._LIBC is None, reason="glibc's malloc only")
_BYTES = 128 << 20  # a block glibc would map on its own, and hand back when freed


def _faults(action):
    """The minor page faults ``action()`` took (first touches of fresh pages)."""
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    action()
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before


def _touch():
    values = np.empty(_BYTES // 8)
    values.fill(1.0)
    del values


@glibc
def test_memory_freed_within_is_touched_again_without_faults_nested_or_not():
    with memory.reused_memory():
        first = _faults(_touch)
        with memory.reused_memory():
            pass
        again = _faults(_touch)  # the outer one still runs
    assert first >= 32  # 128 MiB are 32 huge pages at the least
    assert again <= first // 8
    assert memory._reused.depth == 0


@glibc
def test_a_run_in_slices_reuses_between_them_and_hands_memory_back_at_its_end():
    seen = []

    def run():
        for _ in range(3):
            seen.append(_faults(_touch))
            yield memory._reused.depth
        return "done"

    def caller():
        return (yield from memory.reusing(run()))

    slices = caller()
    depths = []
    with pytest.raises(StopIteration) as ended:
        while True:
            depths.append(next(slices))
    assert ended.value.value == "done"
    assert depths == [1, 1, 1]  # each slice ran within reused_memory
    assert memory._reused.depth == 0  # and between slices and after, glibc maps and trims again
    assert seen[1] <= seen[0] // 8 and seen[2] <= seen[0] // 8
    assert _faults(_touch) >= seen[0] // 2  # handed back: fresh pages again


def test_a_run_closed_early_or_failing_leaves_the_defaults():
    def run():
        yield 0.5
        raise RuntimeError("a failed slice")

    slices = memory.reusing(run())
    next(slices)
    slices.close()
    assert memory._reused.depth == 0
    slices = memory.reusing(run())
    next(slices)
    with pytest.raises(RuntimeError):
        next(slices)
    assert memory._reused.depth == 0


def _noisy_grid(cells, seed):
    """(positions, edges, faces) of a flat triangulated grid with noise along z."""
    positions, faces = small_meshes.grid(cells, cells)
    positions[:, 2] = 0.05 * np.random.default_rng(seed).normal(size=len(positions))
    return positions, small_meshes.edges_of(faces), faces


def test_smoothing_runs_leave_the_defaults_and_the_same_result():
    noisy, edges, faces = _noisy_grid(30, 0)
    first = core.smooth_mesh(noisy, edges, faces=faces, keep_sharp_edges=True)
    assert memory._reused.depth == 0
    with pytest.raises(core.Cancelled):
        core.smooth_mesh(noisy, edges, faces=faces, keep_sharp_edges=True, progress=lambda fraction: False)
    assert memory._reused.depth == 0
    assert np.array_equal(core.smooth_mesh(noisy, edges, faces=faces, keep_sharp_edges=True), first)
    core.smooth_point_cloud(noisy)
    assert memory._reused.depth == 0


def test_keep_sharp_edges_and_clouds_reuse_memory_hcs_iterations_do_not(monkeypatch):
    """Keep Sharp Edges' passes and a cloud's stages make fresh arrays of the mesh's size: their slices run
    within reused_memory. HC's iterations keep their arrays: its runs leave glibc as it is."""
    entered = []
    real = memory.reused_memory

    def counted():
        entered.append(True)
        return real()

    monkeypatch.setattr(memory, "reused_memory", counted)
    noisy, edges, faces = _noisy_grid(12, 1)
    core.smooth_mesh(noisy, edges, faces=faces)
    assert not entered
    core.smooth_mesh(noisy, edges, faces=faces, keep_sharp_edges=True)
    assert entered
    entered.clear()
    core.smooth_point_cloud(noisy)
    assert entered
