"""Two sparse factorisations at once: a small shared thread pool.

qdldl (and SuperLU) release the GIL while they factor, so independent blocks of a
block-diagonal system (the charts of one seam-search round) factor side by side on two cores.
Only the factorisations and solves overlap; the numpy around them takes turns. The pool is made
on first use and has ``BD_UV_THREADS`` workers (default: 2, or 1 on a one-core machine; set
``BD_UV_THREADS=1`` where processes already fill the cores, e.g. a batch with ``--jobs``).
"""
import concurrent.futures as cf
import functools
import os
import threading

import numpy as np

_pool = None
_lock = threading.Lock()


def workers():
    """Threads the pool runs (1: everything runs in the caller's thread)."""
    try:
        n = int(os.environ.get("BD_UV_THREADS", ""))
    except ValueError:
        n = min(2, _cpus())
    return max(1, n)


@functools.lru_cache(maxsize=1)
def _cpus():
    """``os.cpu_count()``, read once: glibc reads it from /sys on every call (~50 us), and the
    seam search asks at every solve (~1 % of a 1k-face mesh's search)."""
    return os.cpu_count() or 1


def _the_pool():
    """The shared thread pool, made at its first use."""
    global _pool
    with _lock:
        if _pool is None:
            _pool = cf.ThreadPoolExecutor(max_workers=workers(), thread_name_prefix="bd_uv")
    return _pool


def map_blocks(fn, items):
    """``[fn(x) for x in items]``, the items run side by side when there are several workers.

    Results come back in the order of ``items``, and each is what ``fn`` returns for it alone,
    so the outcome does not depend on the number of threads. An exception in any call is
    raised here (after every call has finished).
    """
    items = list(items)
    if len(items) < 2 or workers() < 2:
        return [fn(x) for x in items]
    pool = _the_pool()
    futures = [pool.submit(fn, x) for x in items[1:]]
    try:
        first = fn(items[0])                # the caller's thread takes the first block
    finally:
        cf.wait(futures)
    return [first] + [f.result() for f in futures]


def map_queue(fn, items, alone):
    """``[fn(x) for x in items]``, at most two at a time, an item with ``alone`` true with no
    other beside it, in the order of ``items``: the caller's thread and one of the pool's take
    the next item as soon as they are free (a queue rather than pairs, which wait for both of a
    pair before the next two start; the same limit on what is held at once, the memory of two
    factors). Results in the order of ``items``, each what ``fn`` returns for it alone; an
    exception is raised here after every started call has finished (no further item starts).
    """
    items = list(items)
    if len(items) < 2 or workers() < 2:
        return [fn(x) for x in items]
    pool = _the_pool()
    out = [None] * len(items)
    state = {"next": 0, "busy": 0, "alone": False, "error": None}
    cond = threading.Condition()

    def lane():
        while True:
            with cond:
                while True:
                    i = state["next"]
                    if state["error"] is not None or i >= len(items):
                        return
                    if (state["busy"] == 0 if alone[i] else
                            state["busy"] < 2 and not state["alone"]):
                        break
                    cond.wait()
                state["next"] = i + 1
                state["busy"] += 1
                state["alone"] = bool(alone[i])
            try:
                out[i] = fn(items[i])
            except BaseException as exc:    # raised by the caller once both lanes stop
                with cond:
                    state["error"] = state["error"] or exc
            finally:
                with cond:
                    state["busy"] -= 1
                    if alone[i]:
                        state["alone"] = False
                    cond.notify_all()
    other = pool.submit(lane)
    try:
        lane()                              # the caller's thread is the other lane
    finally:
        cf.wait([other])
    if state["error"] is not None:
        raise state["error"]
    return out


def halves(sizes, least):
    """Where to cut a sequence of blocks of ``sizes`` into two runs of about equal total work
    (``None`` when the smaller run would be under ``least``, or there is one worker).

    Returns
    -------
    int j: blocks ``[:j]`` and ``[j:]``, or None
    """
    if workers() < 2 or len(sizes) < 2:
        return None
    c = np.cumsum(np.asarray(sizes, dtype=np.float64))
    j = int(np.argmin(np.abs(c[:-1] - c[-1] / 2))) + 1
    return j if min(c[j - 1], c[-1] - c[j - 1]) >= least else None
