"""The interactive path: chunked runs (progress in the status bar, Esc between chunks).

A window's timer events cannot be sent headless, so this drives the same runner the modal operator
steps through: results must equal the one-call run, progress must rise to 1, and leaving early
(what Esc does) must write nothing.
"""

import importlib
from types import SimpleNamespace

import numpy as np
from blender_scene import ADDON, noisy_sphere, positions_of


def jobs_module():
    return importlib.import_module(f"{ADDON}.jobs.mesh")


def make_job(obj, props):
    return importlib.import_module(f"{ADDON}.operators.mesh_objects").make_job(obj, props)


def core_module():
    return importlib.import_module(f"{ADDON}.core")


def settings(**overrides):
    """The operator's settings as the command line hands them over: the declared defaults, 9 iterations
    (given, so the Automatic Amount is off, as the command line does with --iterations)."""
    settings_class = importlib.import_module(f"{ADDON}.cli.arguments").Settings
    return settings_class(**{"iterations": 9, "auto_amount": False, **overrides})


def test_chunked_run_equals_one_call_and_reports_rising_progress(scene):
    jobs = jobs_module()
    for mode in ("SIMULTANEOUS", "SEQUENTIAL"):
        props = settings(mode=mode)
        whole = [make_job(noisy_sphere(f"A{mode}"), props)]
        list(jobs.run(whole, props))
        chunked = [make_job(noisy_sphere(f"B{mode}"), props)]
        progress = list(jobs.run(chunked, props, chunk=2))
        assert np.array_equal(chunked[0].result, whole[0].result)
        assert chunked[0].report.iterations == 9
        assert progress == sorted(progress) and progress[-1] == 1.0
        assert len([fraction for fraction in progress if fraction > 0.0]) == 5  # after the welding's slices


def test_leaving_between_chunks_writes_nothing(scene):
    jobs = jobs_module()
    obj = noisy_sphere()
    before = positions_of(obj.data)
    props = settings()
    runner = jobs.run([make_job(obj, props)], props, chunk=2)
    fraction = next(runner)
    while fraction == 0.0:  # the welding and the faces' surface: slices of their own, before the iterations
        fraction = next(runner)
    assert 0.0 < fraction < 1.0
    runner.close()  # Esc: the modal handler stops stepping and never calls finish()
    assert np.array_equal(positions_of(obj.data).view(np.uint32), before.view(np.uint32))
    assert obj.data.shape_keys is None


class FakeWindowManager:
    def __init__(self):
        self.calls = []

    def event_timer_add(self, step, window=None):
        self.calls.append("timer_add")
        return "timer"

    def event_timer_remove(self, timer):
        self.calls.append("timer_remove")

    def progress_begin(self, low, high):
        self.calls.append("begin")

    def progress_update(self, value):
        self.calls.append(value)

    def progress_end(self):
        self.calls.append("end")

    def modal_handler_add(self, operator):
        self.calls.append("handler")


def modal_operator():
    """A ModalProgress user with Blender's window manager, workspace and report() stood in for."""
    base = importlib.import_module(f"{ADDON}.operators.modal_progress").ModalProgress

    class Operator(base):
        def __init__(self):
            self.reports, self.finished, self.abandoned = [], False, False

        def report(self, level, message):
            self.reports.append((set(level), message))

        def modal_finish(self, context):
            self.finished = True
            return {"FINISHED"}

        def modal_abandon(self, context):
            self.abandoned = True

    statuses = []
    context = SimpleNamespace(
        window=None, window_manager=FakeWindowManager(), workspace=SimpleNamespace(status_text_set=statuses.append)
    )
    return Operator(), context, statuses


def work(fractions, fail_at=None):
    for index, fraction in enumerate(fractions):
        if index == fail_at:
            raise ValueError("bad settings")
        yield fraction


TIMER, ESC, MOUSE = (SimpleNamespace(type=kind) for kind in ("TIMER", "ESC", "MOUSEMOVE"))


def test_modal_steps_show_progress_then_finish():
    operator, context, statuses = modal_operator()
    assert operator.start_modal(context, work([0.25, 0.5, 1.0])) == {"RUNNING_MODAL"}
    assert operator.modal(context, MOUSE) == {"RUNNING_MODAL"}  # other events pass through
    assert [operator.modal(context, TIMER) for _ in range(3)] == [{"RUNNING_MODAL"}] * 3
    assert not operator.finished
    assert operator.modal(context, TIMER) == {"FINISHED"} and operator.finished
    assert context.window_manager.calls == ["timer_add", "begin", "handler", 25, 50, 100, "timer_remove", "end"]
    assert (
        statuses[:3]
        == ["HC Smooth: 25% — Esc to cancel", "HC Smooth: 50% — Esc to cancel", "HC Smooth: 100% — Esc to cancel"]
        and statuses[-1] is None
    )


def test_modal_escape_abandons_without_finishing():
    operator, context, statuses = modal_operator()
    operator.start_modal(context, work([0.5, 1.0]))
    operator.modal(context, TIMER)
    assert operator.modal(context, ESC) == {"CANCELLED"}
    assert operator.abandoned and not operator.finished
    assert operator.reports == [({"WARNING"}, "HC Smooth cancelled: nothing was changed")]
    assert context.window_manager.calls[-2:] == ["timer_remove", "end"] and statuses[-1] is None


def test_modal_error_is_reported_and_abandons():
    operator, context, _ = modal_operator()
    operator.start_modal(context, work([0.5, 1.0], fail_at=1))
    operator.modal(context, TIMER)
    assert operator.modal(context, TIMER) == {"CANCELLED"}
    assert operator.abandoned and not operator.finished
    assert operator.reports == [({"ERROR"}, "bad settings")]


def test_automatic_amount_reports_progress_while_it_chooses(scene):
    jobs = jobs_module()
    props = settings(auto_amount=True)
    job = make_job(noisy_sphere(), props)
    progress = list(jobs.run([job], props, chunk=5))
    choosing = [f for f in progress if f < core_module().mesh.smooth.CHOOSING_SHARE]
    assert len(choosing) >= 2 and progress == sorted(progress) and progress[-1] == 1.0
    whole = make_job(noisy_sphere("B"), props)
    list(jobs.run([whole], props))
    assert job.report.amount == whole.report.amount and np.array_equal(job.result, whole.result)


def test_a_released_job_keeps_its_report(scene):
    """Edit mode drops a job's arrays before Blender builds its BMesh again: the report stays."""
    jobs = jobs_module()
    props = settings()
    job = make_job(noisy_sphere(), props)
    list(jobs.run([job], props))
    expected = jobs.summary([job], props)
    job.change = None  # measured again by release, from the arrays
    jobs.release(job)
    assert job.positions is None and job.result is None and job.measured_input is None
    assert jobs.summary([job], props) == expected and "volume" in expected
