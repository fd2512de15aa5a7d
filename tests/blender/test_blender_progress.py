"""The interactive path: chunked runs (progress in the status bar, Esc between chunks).

A window's timer events cannot be sent headless, so this drives the same runner the modal operator
steps through: results must equal the one-call run, progress must rise to 1, and leaving early
(what Esc does) must write nothing.
"""

import importlib
from types import SimpleNamespace

import bpy
import numpy as np

from blender_scene import ADDON, noisy_sphere, positions_of


def jobs_module():
    return importlib.import_module(f"{ADDON}.operators.jobs")


def settings(**overrides):
    values = dict(method="HC", alpha=0.1, beta=0.6, iterations=9, mode="SIMULTANEOUS", tolerance=0.0,
                  vertex_group="", invert_vertex_group=False, pin_boundary=False, output="MESH")
    values.update(overrides)
    return SimpleNamespace(**values)


def test_chunked_run_equals_one_call_and_reports_rising_progress(scene):
    jobs = jobs_module()
    for mode in ("SIMULTANEOUS", "SEQUENTIAL"):
        props = settings(mode=mode)
        whole = [jobs.make_job(noisy_sphere(f"A{mode}"), props)]
        list(jobs.run(whole, props))
        chunked = [jobs.make_job(noisy_sphere(f"B{mode}"), props)]
        progress = list(jobs.run(chunked, props, chunk=2))
        assert np.array_equal(chunked[0].result, whole[0].result)
        assert chunked[0].iterations_run == 9
        assert len(progress) == 5 and progress == sorted(progress) and progress[-1] == 1.0


def test_leaving_between_chunks_writes_nothing(scene):
    jobs = jobs_module()
    obj = noisy_sphere()
    before = positions_of(obj.data)
    props = settings()
    runner = jobs.run([jobs.make_job(obj, props)], props, chunk=2)
    assert 0.0 < next(runner) < 1.0
    runner.close()  # Esc: the modal handler stops stepping and never calls finish()
    assert np.array_equal(positions_of(obj.data).view(np.uint32), before.view(np.uint32))
    assert obj.data.shape_keys is None
