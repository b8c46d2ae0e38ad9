"""A background computation with progress and cancel (no bpy).

The modal Decompose polls a Job from a timer on the main thread; the engine
runs in the worker thread with the GIL released, so the UI stays responsive.
"""

from __future__ import annotations

import threading
import time


class Job:
    """Run ``fn(progress)`` in a daemon thread.

    ``fn`` receives a ``progress(fraction) -> bool`` callback to pass to the
    engine; it returns False once :meth:`cancel` was called.  After the thread
    ends, exactly one of ``result`` / ``error`` is set, or ``cancelled`` is True.
    """

    def __init__(self, fn, cancelled_type=None, name="pointscale-job"):
        self._fn = fn
        self._cancelled_type = cancelled_type
        self._cancel = threading.Event()
        self.fraction = 0.0
        self.result = None
        self.error = None
        self.cancelled = False
        self.started = None
        self.finished = None
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)

    def _progress(self, fraction) -> bool:
        self.fraction = float(fraction)
        return not self._cancel.is_set()

    def _run(self):
        try:
            self.result = self._fn(self._progress)
        except BaseException as exc:  # noqa: BLE001 - handed to the main thread
            if self._cancelled_type is not None and isinstance(exc, self._cancelled_type):
                self.cancelled = True
            else:
                self.error = exc
        if self._cancel.is_set() and self.error is None:
            # A cancel that came too late to stop the engine still drops the result.
            self.cancelled = True
            self.result = None
        self.finished = time.perf_counter()

    def start(self) -> "Job":
        self.started = time.perf_counter()
        self._thread.start()
        return self

    def cancel(self) -> None:
        self._cancel.set()

    @property
    def cancelling(self) -> bool:
        return self._cancel.is_set()

    @property
    def running(self) -> bool:
        return self._thread.is_alive()

    @property
    def elapsed(self) -> float:
        if self.started is None:
            return 0.0
        return (self.finished or time.perf_counter()) - self.started

    def wait(self, timeout=None) -> bool:
        self._thread.join(timeout)
        return not self._thread.is_alive()
