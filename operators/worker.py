"""A background unwrap job that never touches Blender.

The modal operator hands a :class:`UnwrapJob` copies of the mesh arrays and a solve function
(``bd_uv.unwrap``); the job runs it in a daemon thread and reports through a queue that the main
thread drains on its timer. Cancelling sets a ``threading.Event`` that the solver's progress
callback checks (the core raises its ``CancelledError``), so Esc stops the work at the next
checkpoint and nothing partial is ever returned. Clarabel releases the GIL while it factorises,
so Blender's UI thread keeps running meanwhile.

Standard library and numpy only: no ``bpy``, no ``bd_uv`` (the solve function is injected), so
this module is tested without Blender.
"""
from __future__ import annotations

import queue
import threading
import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

__all__ = ["Progress", "Finished", "Failed", "UnwrapJob"]


@dataclass(frozen=True)
class Progress:
    """The solver reached ``fraction`` (0..1) of its work; ``message`` says where."""

    fraction: float
    message: str


@dataclass(frozen=True)
class Finished:
    """The solve returned ``result`` after ``seconds``."""

    result: Any
    seconds: float


@dataclass(frozen=True)
class Failed:
    """The solve raised ``error`` (the core's ``CancelledError`` after :meth:`UnwrapJob.cancel`)."""

    error: BaseException
    seconds: float


def _copied(value):
    """A private copy of a numpy array argument; anything else is passed as it is."""
    if isinstance(value, np.ndarray):
        return np.array(value, copy=True)
    return value


class UnwrapJob:
    """``solve(*args, **kwargs, progress=..., cancel=...)`` in a background thread.

    Parameters
    ----------
    solve : callable
        Called once in the worker thread with copies of ``args`` / ``kwargs`` plus
        ``progress=callable(fraction, message)`` and ``cancel=threading.Event``.
    *args, **kwargs
        Its arguments; numpy arrays are copied at construction, so the caller may reuse or free
        its own (e.g. Blender's mesh may change while the job runs).
    """

    def __init__(self, solve: Callable, *args, **kwargs):
        self._solve = solve
        self._args = tuple(_copied(a) for a in args)
        self._kwargs = {k: _copied(v) for k, v in kwargs.items()}
        self.messages: queue.Queue = queue.Queue()
        self.cancel_event = threading.Event()
        self._thread = threading.Thread(target=self._run, name="bd-uv unwrap", daemon=True)
        self._outcome = None
        self.fraction = 0.0
        self.status = ""

    # -- worker thread -------------------------------------------------------------------------
    def _progress(self, fraction, message=""):
        self.messages.put(Progress(float(fraction), str(message)))

    def _run(self):
        start = time.perf_counter()
        try:
            result = self._solve(*self._args, **self._kwargs, progress=self._progress,
                                 cancel=self.cancel_event)
        except BaseException as error:  # handed to the main thread, which decides
            outcome = Failed(error, time.perf_counter() - start)
        else:
            outcome = Finished(result, time.perf_counter() - start)
        self.messages.put(outcome)

    # -- main thread ---------------------------------------------------------------------------
    def start(self):
        self._thread.start()
        return self

    def cancel(self):
        """Ask the solve to stop at its next checkpoint; the job then ends with :class:`Failed`."""
        self.cancel_event.set()

    @property
    def cancelled(self):
        return self.cancel_event.is_set()

    @property
    def running(self):
        return self._thread.is_alive()

    def poll(self):
        """Drain the queue without blocking.

        Returns
        -------
        outcome : Finished, Failed or None
            The end of the job, once it is there (then returned by every later call too).
            ``fraction`` and ``status`` hold the latest progress.
        """
        while True:
            try:
                message = self.messages.get_nowait()
            except queue.Empty:
                return self._outcome
            if isinstance(message, Progress):
                self.fraction, self.status = message.fraction, message.message
            else:
                self._outcome = message

    def wait(self):
        """Block until the job ends and return its outcome (for scripts and tests)."""
        self._thread.join()
        return self.poll()
