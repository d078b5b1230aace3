"""The compaction of a square-ending search's best layout, started on a spare core while
spyrrow overruns the search's time.

A square-ending search (:mod:`.square`, ``reach``) that has not reached its square ends by its
clock, but spyrrow looks at its clock only between the strikes of its separator, so it often
returns well after its time (up to 4 s; the early stop's trip lands there too:
issue18-pack30-2026-11-29.md), with no better layout found meanwhile; only then did the
compaction (:mod:`.compact`) start. Here, once the search's time is over (its first report, the
first placement's, plus its exploration's share: :func:`.square._offer`), the best square layout
it reported is handed to a thread that compacts it (spyrrow holds no GIL while it searches,
HiGHS none while it solves); a better one arriving later cancels that compaction, and its own
starts once it has stood for ``QUIET`` seconds. Within the search's time nothing runs beside
it: started there (after ``QUIET`` without a better layout) a compaction took CPU from the
search under load, igl-bunny -0.011 coverage (3 of 3 seeds, load 2-3). When the search returns,
the compaction of the layout it ends with is kept if it is the one compacted here (finished, or
joined); else it is compacted then, as before. The result is the compaction of the same layout
with the same CPU budget (on the thread's clock, ``time.thread_time``), only sooner where a core
is free: by the search's overrun, up to the compaction's length (measured in
issue18-pack31-2026-11-29.md).
"""
import threading
import time

import numpy as np

QUIET = 0.05   # seconds a better layout must stand before its compaction starts


class Ahead:
    """A thread compacting the newest layout offered to it.

    ``compact(best, clock, cancel)`` is the caller's compaction of ``best`` (a (Placement,
    side) pair) on CPU clock ``clock``, ended early once the Event ``cancel`` is set."""

    def __init__(self, compact):
        self._compact = compact
        self._after = None       # perf_counter time before which no compaction starts
        self._lock = threading.Lock()
        self._wake = threading.Condition(self._lock)
        self._offered = None     # (best, time offered)
        self._running = None     # (best, cancel Event)
        self._done = None        # (best, result)
        self._closing = False
        self._failed = False
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def start_after(self, when):
        """No compaction starts before ``when`` (``time.perf_counter``), unless the search has
        ended."""
        with self._lock:
            self._after = when
            self._wake.notify()

    def offer(self, best):
        """A better layout (best, side) than every one offered before."""
        with self._lock:
            if self._closing:
                return
            self._offered = (best, time.perf_counter())
            if self._running is not None:
                self._running[1].set()
            self._wake.notify()

    def _run(self):
        try:
            while True:
                with self._lock:
                    while True:
                        if self._offered is None:
                            if self._closing:
                                return
                            self._wake.wait()
                            continue
                        if self._after is None and not self._closing:
                            self._wake.wait()   # (until the search's time is known, or ends)
                            continue
                        wait = max(self._offered[1] + QUIET, self._after or 0.0) \
                            - time.perf_counter()
                        if wait > 0 and not self._closing:
                            self._wake.wait(wait)   # (a newer one may come meanwhile)
                            continue
                        best, self._offered = self._offered[0], None
                        cancel = threading.Event()
                        self._running = (best, cancel)
                        break
                result = self._compact(best, time.thread_time, cancel)
                with self._lock:
                    self._running = None
                    if not cancel.is_set():
                        self._done = (best, result)
        except Exception:   # (the caller compacts its layout itself, and meets the error there)
            with self._lock:
                self._failed, self._running, self._done = True, None, None

    def finish(self, best):
        """The compaction of ``best``, the layout the search ended with, if it is the one this
        thread compacted (waiting for it to finish); else None (this thread's work stopped; also
        when a compaction failed here: the caller's own compaction then meets its error)."""
        with self._lock:
            self._closing = True
            same = _same(best, self._offered[0]) if self._offered is not None else False
            if not same:
                self._offered = None
            if self._running is not None and not _same(best, self._running[0]):
                self._running[1].set()
            self._wake.notify()
        self._thread.join()
        if self._failed:
            return None
        if self._done is not None and _same(best, self._done[0]):
            return self._done[1]
        return None

    def cancel(self):
        """Stop without a result (no square layout, or an error on the caller's side)."""
        with self._lock:
            self._closing = True
            self._offered = None
            if self._running is not None:
                self._running[1].set()
            self._wake.notify()
        self._thread.join()


def _same(a, b):
    """Whether two (Placement, side) pairs are the same layout."""
    return (a[1] == b[1] and np.array_equal(a[0].angle, b[0].angle)
            and np.array_equal(a[0].shift, b[0].shift))
