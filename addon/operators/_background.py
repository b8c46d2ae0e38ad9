"""An operator's engine call in a worker thread (job.Job) under a modal handler, for the UI
button: progress in the status bar and on the cursor, Esc to cancel, the UI responsive.

bpy is touched on the main thread only, before the job starts and after it ends, so a cancel
or an error leaves the scene exactly as it was. Scripts and background mode run the same work
synchronously through execute (modal operators need a window).
"""

from __future__ import annotations

from .. import preferences, state
from ..job import Job


class RunsInBackground:
    """A mixin for an Operator whose invoke calls ``start``. The operator provides:

    - ``finished(context, result) -> set``: writes the result (main thread, after the job);
    - ``failed(error) -> str``: the report for an error the job raised;
    - ``cancelled_report``: the report when Esc (or Blender) cancelled it.
    """

    _job = None
    _timer = None
    _busy = ()  # the session_uids the job works on (state.running)
    _what = ""

    def start(self, context, compute, *, what: str, name: str, cancelled_type, busy=()) -> set:
        """Runs ``compute(progress)`` in a worker thread; ``what`` names it in the status bar
        ("decomposing 'Suzanne' (5000 vertices)"). busy: session_uids (an object's and its
        mesh's), marked as running (state.running) until the job ends, so that no other job
        starts on them."""
        self._what = what
        self._job = Job(compute, cancelled_type=cancelled_type, name=name)
        wm = context.window_manager
        self._timer = wm.event_timer_add(preferences.get(context).poll_interval, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0, 100)
        self._busy = tuple(busy)
        state.running.update(self._busy)
        self._job.start()
        self._status(context)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        job = self._job
        if event.type == "ESC" and event.value == "PRESS" and not job.cancelling:
            job.cancel()  # the engine stops at its next progress call
            self._status(context)
            return {"RUNNING_MODAL"}
        if event.type != "TIMER" or event.timer is not self._timer:
            return {"PASS_THROUGH"}  # the UI stays responsive
        if job.running:
            context.window_manager.progress_update(100.0 * job.fraction)
            self._status(context)
            return {"RUNNING_MODAL"}
        self._cleanup(context)
        # Blender keeps the finished operator (redo, the Info log): let it keep no arrays.
        self._job = None
        # Esc after the engine's last progress call still cancels: the artist asked for nothing.
        if job.cancelled or job.cancelling:
            self.report({"WARNING"}, self.cancelled_report)
            return {"CANCELLED"}
        if job.error is not None:
            self.report({"ERROR"}, self.failed(job.error))
            return {"CANCELLED"}
        return self.finished(context, job.result)

    def cancel(self, context):
        # Blender ends the modal itself (file load, quit): stop the worker, drop the result.
        if self._job is not None:
            self._job.cancel()
            self._job.wait()
        self._cleanup(context)

    def _status(self, context):
        job = self._job
        done = "cancelling..." if job.cancelling else f"{100 * job.fraction:.0f}%"
        text = f"Multiscale: {self._what} {done}  {job.elapsed:.0f} s  |  Esc to cancel"
        if context.workspace is not None:
            context.workspace.status_text_set(text)
        if context.area is not None:
            context.area.tag_redraw()

    def _cleanup(self, context):
        state.running.difference_update(self._busy)
        self._busy = ()
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
            wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)
