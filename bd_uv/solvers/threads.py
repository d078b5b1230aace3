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


def map_blocks(fn, items):
    """``[fn(x) for x in items]``, the items run side by side when there are several workers.

    Results come back in the order of ``items``, and each is what ``fn`` returns for it alone,
    so the outcome does not depend on the number of threads. An exception in any call is
    raised here (after every call has finished).
    """
    items = list(items)
    if len(items) < 2 or workers() < 2:
        return [fn(x) for x in items]
    global _pool
    with _lock:
        if _pool is None:
            _pool = cf.ThreadPoolExecutor(max_workers=workers(), thread_name_prefix="bd_uv")
    futures = [_pool.submit(fn, x) for x in items[1:]]
    try:
        first = fn(items[0])                # the caller's thread takes the first block
    finally:
        cf.wait(futures)
    return [first] + [f.result() for f in futures]


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
