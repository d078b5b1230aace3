"""The search's rounds on two cores: once the charts still searched fall into two groups of
enough faces, each group's remaining rounds run in a thread of its own.

A round changes only its own charts (their cut graphs, splits and maps), so two disjoint
groups of charts can be searched at once: each thread sees the other group's faces as frozen,
writes only the seams inside its own charts (the seams between the groups are cut already) and
keeps its own copy of the elimination orders (``orders.Orders.copy``, joined after), so what
each group gets does not depend on the threads' timing. Much of a round on a chart of a few
thousand faces runs without the GIL (qdldl's factorisations through ctypes, numpy's loops on
arrays of that size), which is what the second thread overlaps.
"""
import threading

import numpy as np

from ..solvers.threads import beside, workers
from .topology import charts

# Faces each of the two groups must hold (below it a thread costs more than it overlaps).
PARALLEL_FACES = 2000
# The groups are looked for after each of the first ROUNDS rounds only (a chart labelling each
# time), and on meshes of at most MESH_FACES faces: on larger ones two threads' factors at once
# would raise the search's memory peaks, which is where those meshes miss xatlas.
ROUNDS = 3
MESH_FACES = 50_000


def groups(F, E, cut, frozen):
    """Two groups of whole charts of the faces not frozen, of about equal faces (the largest
    chart first, each into the group holding fewer), as (m,) bool masks; None with one worker,
    fewer than ``2 PARALLEL_FACES`` faces or a group under ``PARALLEL_FACES`` faces."""
    sub = np.flatnonzero(~frozen)
    if workers() < 2 or len(sub) < 2 * PARALLEL_FACES:
        return None
    chs = charts(F, E, cut, sub)
    size = [len(c.faces) for c in chs]
    masks, total = [np.zeros(len(F), dtype=bool) for _ in range(2)], [0, 0]
    for j in sorted(range(len(chs)), key=lambda j: (-size[j], j)):
        g = 0 if total[0] <= total[1] else 1
        masks[g][chs[j].faces] = True
        total[g] += size[j]
    return masks if min(total) >= PARALLEL_FACES else None


def search(masks, frozen, orders, done, last, step):
    """Run ``step(round, frozen, orders) -> changed`` for each group of ``masks`` (``groups``)
    from round ``done + 1``, the second group in a new thread, until the round changes nothing,
    round ``last`` is done or fewer than ``PARALLEL_FACES / 2`` of the group's faces are left
    (the small rounds' fixed costs would be paid twice). ``frozen`` (m,) bool and ``orders``
    (or None) are updated as one search would leave them. An exception in either thread is
    raised here after both have stopped.

    Returns
    -------
    (int, the last round either group ran; bool, whether a group has rounds left)
    """
    froz = [frozen | ~mk for mk in masks]
    ords = [None if orders is None else orders.copy() for _ in masks]
    out = [done, done]
    more = [False, False]
    errors = [None, None]

    def run(i):
        beside(True)
        try:
            r = done
            while r < last:
                r += 1
                out[i] = r
                if not step(r, froz[i], ords[i]):
                    return
                if np.count_nonzero(~froz[i]) < PARALLEL_FACES // 2:
                    more[i] = r < last
                    return
        except BaseException as e:          # raised in the caller's thread below
            errors[i] = e
        finally:
            beside(False)
    t = threading.Thread(target=run, args=(1,), name="bd_uv-search")
    t.start()
    try:
        run(0)
    finally:
        t.join()
    for e in errors:
        if e is not None:
            raise e
    frozen[:] = froz[0] & froz[1]
    if orders is not None:
        orders.join(*ords)
    return max(out), any(more)
