"""Running the pipeline off Blender's main thread, so Blender stays usable while it works.

A Job runs one function on a worker thread with a progress callback and a cancel event (the
sketchbody package's own: `run_pipeline(progress=..., cancel=...)` stops within one fit
iteration). Blender's main thread polls it (a bpy.app.timers callback in the add-on) and builds
the scene once it is done: the worker never touches bpy, whose data is not thread-safe. This
module does not import bpy.
"""

import threading


class Job:
    """One computation `work(progress, cancel)` on a daemon worker thread.

    `progress(fraction)` (0..1) records the fraction done and returns False once cancelled;
    `cancel` is a threading.Event the work passes on to the library. After the thread ends,
    `result` holds what `work` returned, or `error` the exception it raised (a cancelled run
    raises the package's Cancelled)."""

    def __init__(self, work, label):
        self.label = label
        self.cancel_event = threading.Event()
        self.fraction = 0.0
        self.result = None
        self.error = None
        self._work = work
        self._thread = threading.Thread(target=self._main, name=f"sketchbody: {label}", daemon=True)

    def start(self):
        """Starts the worker thread; returns the job."""
        self._thread.start()
        return self

    def _progress(self, fraction):
        """The progress callback the work gets: keeps the largest fraction seen; False once
        cancelled (the package then stops the library's call)."""
        self.fraction = max(self.fraction, min(1.0, float(fraction)))
        return not self.cancel_event.is_set()

    def _main(self):
        """The worker thread's body: every exception is kept for the main thread, never raised
        on the worker (where nobody would see it)."""
        try:
            self.result = self._work(self._progress, self.cancel_event)
        except BaseException as e:  # noqa: BLE001 - handed to the main thread
            self.error = e

    @property
    def done(self):
        """True once the worker thread has ended (result or error set)."""
        return self._thread.ident is not None and not self._thread.is_alive()

    def cancel(self):
        """Asks the work to stop (it stops within one fit iteration)."""
        self.cancel_event.set()

    @property
    def cancelled(self):
        """True once cancel() was called."""
        return self.cancel_event.is_set()

    def wait(self, timeout=None):
        """Blocks until the worker ends or `timeout` seconds pass; returns `done`."""
        self._thread.join(timeout)
        return self.done
