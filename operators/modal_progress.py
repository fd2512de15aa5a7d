"""Long interactive runs as a modal timer: progress in the status bar, Esc cancels, nothing written early.

Shared by the mesh and point-cloud operators. An operator calls ``start_modal(context, steps)`` with a
generator that does a slice of the work per ``next()`` and yields the fraction done, and provides
``modal_finish(context)`` (write the results, report, return {"FINISHED"}) and, if something must be
undone on cancel, ``modal_abandon(context)``.
"""

import traceback

PROGRESS_TICK = 0.01  # seconds between timer events: each advances the work by one slice


class ModalProgress:
    progress_label = "HC Smooth"

    def start_modal(self, context, steps):
        self._steps = steps
        window_manager = context.window_manager
        self._timer = window_manager.event_timer_add(PROGRESS_TICK, window=context.window)
        window_manager.progress_begin(0, 100)
        window_manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal_finish(self, context):
        raise NotImplementedError

    def modal_abandon(self, context):
        """Undo what preparing the run changed (nothing by default); nothing has been written."""

    def _end_modal(self, context):
        window_manager = context.window_manager
        window_manager.event_timer_remove(self._timer)
        window_manager.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)

    def modal(self, context, event):
        if event.type == "ESC":
            self._end_modal(context)
            self.modal_abandon(context)
            self.report({"WARNING"}, f"{self.progress_label} cancelled: nothing was changed")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"RUNNING_MODAL"}
        try:
            fraction = next(self._steps)
        except StopIteration:
            self._end_modal(context)
            return self.modal_finish(context)
        except Exception as error:  # every exit removes the timer and the progress and writes nothing
            self._end_modal(context)
            self.modal_abandon(context)
            if isinstance(error, ValueError):  # bad settings or a run that blew up: the message says why
                self.report({"ERROR"}, str(error))
            else:  # a bug: keep the traceback for the console
                traceback.print_exc()
                self.report(
                    {"ERROR"}, f"{self.progress_label} failed ({type(error).__name__}: {error}): nothing was changed"
                )
            return {"CANCELLED"}
        context.window_manager.progress_update(int(fraction * 100))
        if context.workspace is not None:
            context.workspace.status_text_set(f"{self.progress_label}: {fraction:.0%} — Esc to cancel")
        return {"RUNNING_MODAL"}
