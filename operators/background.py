"""The synchronous and background paths of a solving operator, written once.

An operator mixing in :class:`BackgroundSolve` defines

- ``_prepare(context)`` -> ``(state, solve, args, kwargs)``, or None after reporting why not
  (it reads the meshes: Object Mode inside);
- ``_finish(context, state, result, seconds)`` -> the operator's return set (write, check,
  report);
- ``JOB`` (text for the status bar, e.g. "Bounded Distortion deform") and, optionally,
  ``CANCELLED`` (the report when Esc or a cancel stops it; by default "<JOB> cancelled: ...").

``execute()`` solves here and now (scripts, the redo panel, tests); ``invoke()`` runs
``solve(*args, **kwargs, progress=..., cancel=...)`` in a :class:`~.worker.UnwrapJob` thread
polled by a modal timer, shows progress in the status bar, and Esc cancels leaving mesh and UVs
exactly as they were. Core errors become reports: a ``BDError`` is a WARNING (the user's mesh
needs work), a ``ValueError`` an ERROR.
"""
import time

import bpy

from .. import bd_uv
from .editmode import edit_mesh_objects
from .worker import Failed, UnwrapJob


def has_event_loop(context):
    """Whether modal timers will fire (not so in background mode or without a window)."""
    return context.window is not None and not bpy.app.background


class BackgroundSolve:
    JOB = "Bounded Distortion"
    CANCELLED = None

    def _cancelled(self):
        return self.CANCELLED or f"{self.JOB} cancelled: mesh and UVs unchanged"

    def _failed(self, error):
        """Report an exception from the solve; nothing has been written."""
        if isinstance(error, bd_uv.CancelledError):
            self.report({'WARNING'}, self._cancelled())
        elif isinstance(error, ValueError):  # bad options (bd_uv.OptionError is one too)
            self.report({'ERROR'}, str(error))
        elif isinstance(error, bd_uv.BDError):
            self.report({'WARNING'}, str(error))
        else:
            raise error
        return {'CANCELLED'}

    def execute(self, context):
        prepared = self._prepare(context)
        if prepared is None:
            return {'CANCELLED'}
        state, solve, args, kwargs = prepared
        start = time.perf_counter()
        try:
            result = solve(*args, **kwargs)
        except (bd_uv.BDError, ValueError) as error:
            return self._failed(error)
        return self._finish(context, state, result, time.perf_counter() - start)

    def invoke(self, context, event):
        if not has_event_loop(context):  # timers would never fire: solve here and now
            return self.execute(context)
        prepared = self._prepare(context)
        if prepared is None:
            return {'CANCELLED'}
        self._state, solve, args, kwargs = prepared
        self._job = UnwrapJob(solve, *args, **kwargs).start()
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.progress_begin(0, 100)
        self._status(context, "starting")
        wm.modal_handler_add(self)
        return {'RUNNING_MODAL'}

    def _status(self, context, message):
        text = f"{self.JOB}: {self._job.fraction * 100:.0f}% {message}  (Esc to cancel)"
        if context.workspace is not None:
            context.workspace.status_text_set(text)
        context.window_manager.progress_update(int(self._job.fraction * 100))

    def _end_modal(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)

    def modal(self, context, event):
        if event.type == 'ESC' and event.value == 'PRESS':
            self._job.cancel()  # the thread stops at its next checkpoint; its result is dropped
            self._end_modal(context)
            self.report({'WARNING'}, self._cancelled())
            return {'CANCELLED'}
        if event.type != 'TIMER':
            return {'PASS_THROUGH'}
        outcome = self._job.poll()
        if outcome is None:
            self._status(context, self._job.status)
            return {'PASS_THROUGH'}
        self._end_modal(context)
        if isinstance(outcome, Failed):
            return self._failed(outcome.error)
        if not edit_mesh_objects(context):
            self.report({'WARNING'}, "Left Edit Mode while solving: nothing written")
            return {'CANCELLED'}
        return self._finish(context, self._state, outcome.result, outcome.seconds)
