"""The bound search on an island's problem (``solvers.bound_search``: ADMM onto F_C with frames,
one factorisation for every C, no conic solve): ``search``, which ``bound="auto"`` minimises C
with and ``bounded.bend`` polishes a projected map with; and ``over_bound``, a flip-free start
whose max distortion is over the bound asked, lowered by that search rather than bent by
projection iterations.
"""
import threading
import time

import numpy as np

from ..solvers.bound_search import BoundSearch
from ..solvers.ordered_ldl import vertex_ranks
from .along import least_mean_within
from .conic_solves import Cancelled
from .margins import certified_bound, solve_bound

# A numeric C asked of a flip-free map over it: when the search's least max D is this far above
# C (D - 1 > FAR (C - 1)), C is out of reach and the bound is raised to the search's map at
# once. The search ends within a few percent of C* - 1 (three_peaks 2.075 against the conic
# optimum's 1.993, lion-head 1.59 against 1.5703), so FAR leaves room for a C it did not reach.
FAR = 1.25
MEAN_SEARCH = 12   # distortion evaluations between the start and the searched map (``along``)
# ``bound="auto"``'s least-C search (``least``) on an island of up to this many faces iterates on
# the free unknowns (``BoundSearch(free=True)``), as ``disk_auto`` does up to its AUTO_FACES (the
# angle starts' disks of 1,000-2,000 faces: the same iterations and C, the maps to rounding, the
# search 3-17 % less CPU on 9 of 9 disks, issue21-auto25-2026-11-28.md); the whole map's
# products above (``bound_search.ONE_PRODUCT_FACES``)
FREE_FACES = 2000
# A search already run on an island by ``disk_auto`` whose map its certificate did not clear
# (the map lies over itself): handed to the general path's search of the same island from the
# same start, which would run the same iterations again (``hand_over``)
_handed = threading.local()


def hand_over(island, u, searched, D, iterations):
    """Keep ``bound="auto"``'s search of ``island`` (``mesh.Island``) from the map u (nv,)
    complex: its map ``searched`` of max distortion D after ``iterations``, for the next
    ``search`` of this very island from this very start on this thread (the least C, no time
    budget): its answer without the iterations (the same map, to rounding: ``disk_auto`` runs
    them on the same normalised geometry and start)."""
    _handed.entry = (island, u, searched, D, iterations)


def drop_handed():
    """Forget the search ``hand_over`` kept on this thread: a search of the island from another
    start ran first (``disk_angle``'s, from the angle start), as ``search`` forgets it when
    asked from another start."""
    _handed.entry = None


def _handed_over(prob, u, least):
    """The search ``hand_over`` kept for this island and start u, or None (then forgotten)."""
    entry = getattr(_handed, "entry", None)
    _handed.entry = None
    if entry is None or not least or entry[0] is not prob.island or len(prob.pin_idx) \
            or not np.array_equal(entry[1], u):
        return None
    return entry[2:]


def search(prob, u, report, budget, flags, t0, enough=None, least=False, ready=None,
           check=None):
    """Lower the bound of a flip-free map ``u`` by ADMM onto F_C with frames
    (``solvers.bound_search``), holding the pins (or one boundary vertex, where ``u`` has it),
    ending at the first best map ``enough`` (else ``prob.enough``) accepts where it is set.
    ``least``: the search for ``bound="auto"``'s least C on an unpinned island with no time budget,
    bounded as ``BoundSearch.limit_effort`` bounds it. ``ready``: with ``enough``, its gate
    (``BoundSearch.search``'s; the search does not aim deeper for it).
    Returns (the best map, its max distortion); flags "time_budget_exhausted" when the budget
    stopped it."""
    if len(prob.pin_idx) >= prob.nv:
        return u, prob.distortion(u)
    handed = _handed_over(prob, u, least and budget is None)
    if handed is not None:
        us, D, iterations = handed
        prob.iterations += iterations
        return us.copy(), D
    t = time.perf_counter()
    fixed = prob.pin_idx if len(prob.pin_idx) else prob.island.loops[0][:1]
    u = u.copy()
    if len(prob.pin_idx):
        u[prob.pin_idx] = prob.pin_val
    # one elimination order of the island's vertices (the conformal map's, where the one-disk
    # path solved it: no second AMD)
    ranks = prob.ranks if prob.ranks is not None else vertex_ranks(prob.island.tris, prob.nv)
    bs = BoundSearch(prob.ops, prob.nv, prob.island.tris, fixed, connected=True, ranks=ranks,
                     free=True if least and len(prob.island.tris) <= FREE_FACES else None)
    if least:
        bs.limit_effort()
    bs.check = check

    def progress(D, C):
        report(0.1, f"minimising C: C* <= {D:.4g}, aiming at {C:.4g}")

    deadline = None if budget is None else t0 + budget
    # the problem's own test (the unfold's one-to-one) comes with its cheap gate and aims deep;
    # one given here (``over_bound``'s: within C, else the least C) has neither
    deep = enough is None and prob.ready is not None
    enough, ready = (enough, ready) if enough is not None else (prob.enough, prob.ready)
    u, D, out_of_time = bs.search(u, None, progress, deadline, prob.cancel, enough, ready,
                                  deep=deep)
    if prob.cancel is not None and prob.cancel.is_set():
        raise Cancelled
    if out_of_time:
        flags.append("time_budget_exhausted")
    prob.iterations += bs.iterations
    prob.timings["project"] = prob.timings.get("project", 0.0) + time.perf_counter() - t
    return u, D


def over_bound(prob, start, C, raise_bound, limit, report):
    """A flip-free start (``start.D`` finite) over the bound C asked: the bound search from it,
    stopping at its first map within C (``solve_bound``). Where it stays FAR above C (C is out
    of reach), raising is allowed and its bound is within ``limit``: the searched map at the
    bound it certifies (``margins.certified_bound``; flags "projected": no conic solve made it,
    and "bound_raised"). Else None: ``bounded`` goes on (bend,
    conic solve at C) and falls back on the searched map (``searched_fallback``) where those
    fail, instead of raising C by conic solves.

    Before, the projection iterations bent such a start towards C until their iteration limit
    (elephant's 2k-face disk at C = 5, conformal max 81: 560 iterations in 0.79 s, failed), then
    two conic solves raised C to 20.15; the search reaches 8.93 in 0.03 s.
    Returns ((u, C) or None, (the searched map, its max distortion))."""
    target = solve_bound(C)
    us, D = search(prob, start.u, report, None, [], time.perf_counter(),
                   enough=lambda u: prob.distortion(u) <= target)
    D = prob.distortion(us)
    raised = certified_bound(D)
    if D > target and raise_bound and D - 1.0 > FAR * (C - 1.0) and raised <= limit:
        return (us, raised), (us, D)
    return None, (us, D)


def searched_fallback(prob, start, searched, C, raise_bound, limit):
    """Where the solve at C failed for a flip-free start: its searched map (``over_bound``'s)
    within C, as the map of least mean on the segment from the start to it within C
    (``along.least_mean_within``), flag "projected"; else, where raising is allowed, that map
    at the bound it certifies when within ``limit``, flags "projected" and "bound_raised"; else
    None. Returns ((u, C), flags) or None."""
    us, D = searched
    target = solve_bound(C)
    if D <= target:
        return (least_mean_within(prob, start.u, us, target, MEAN_SEARCH), C), ("projected",)
    if raise_bound and certified_bound(D) <= limit:
        return (us, certified_bound(D)), ("projected", "bound_raised")
    return None
