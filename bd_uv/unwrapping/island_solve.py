"""One island solved on its own (the general path): its problem, start and strategy by the
options (``strategies.minimise`` for "auto", ``bounded.bounded`` for a number, the stretch
search with S, a fixed boundary), ``finish``'s certificate; and the unfold of an island whose map
within a number lies over itself (``unfolder``, for ``overlap_certificate``). Split from
``unwrap`` (which splits the mesh, runs the batched conformal maps and the one-disk pass, and
gathers the islands)."""
import dataclasses
import time

import numpy as np

from ..errors import BDError, CancelledError, IslandError, SolverError
from . import bounded as within, strategies
from . import stretch as stretch_search
from .conic_solves import Cancelled
from .finish import finish
from .fixed_boundary import FRAMES_NAME, fixed_boundary_island, with_premises
from .angle_start import ANGLE_LIMIT, angle_start, max_distortion
from .disk_certificate import turning
from .one_disk import fitted
from .initial import start_map
from .problem import IslandProblem
from .results import IslandResult

__all__ = ["angle_unfolder", "batched_options", "failed_result", "quiet", "solve_island",
           "unfold_first", "unfolder"]


def solve_island(island, V, pins, options, initial_uv, report, cancel, lscm=None,
                  faces_3d=None, ranks=None, unfolding=False, one_to_one=False):
    """One island's certified map (see the module's docstring). ``one_to_one``: with
    ``bound="auto"``, the least C among the search's maps that do not lie over themselves
    (``strategies.least_one_to_one``: ``lscm`` is an angle start, ``angle_start``)."""
    t0 = time.perf_counter()
    o = options
    method, bound, boundary, stretch = o.method, o.bound, o.boundary, o.stretch
    if island.error is not None:
        res = failed_result(island, island.error, t0, bound)
        return res if boundary == "free" else with_premises(res, island)
    if boundary != "free":
        try:
            prob, u, C, flags = fixed_boundary_island(island, V, pins, boundary, method, bound,
                                                      o.raise_bound, o.bound_limit, o.cone, cancel,
                                                      report, stretch)
        except IslandError as exc:
            exc.renumber(island.index)
            return with_premises(failed_result(island, exc, t0, bound, FRAMES_NAME), island)
        except BDError as exc:
            err = SolverError(f"island {island.index}: {exc}", island.index)
            return with_premises(failed_result(island, err, t0, bound, FRAMES_NAME), island)
        return with_premises(finish(prob, u, C, bound, FRAMES_NAME, flags, t0, stretch), island)
    try:
        prob = IslandProblem(island, V, pins, method, o.cone, cancel, faces_3d, ranks)
        if unfolding:       # ``unfolder``: the first map that does not lie over itself will do
            prob.enough, prob.ready = prob.one_to_one, prob.may_be_one_to_one
        start = start_map(prob, o.frames, initial_uv, report, lscm=lscm)
    except IslandError as exc:
        exc.renumber(island.index)
        return failed_result(island, exc, t0, bound)
    except BDError as exc:
        return failed_result(island, SolverError(f"island {island.index}: {exc}", island.index), t0,
                       bound)
    flags = ["angle_start"] if one_to_one else []
    try:
        if bound == "auto" and stretch is not None:
            u, C, name = stretch_search.minimise_stretch(prob, start, stretch, o.time_budget,
                                                         flags, report, t0)
        elif bound == "auto":
            u, C, name = strategies.minimise(prob, start, o.bound_limit, o.time_budget, flags,
                                             report, t0, one_to_one)
        elif stretch is not None:
            u, C, name = stretch_search.bounded_stretch(prob, start, float(bound), stretch,
                                                        report, flags)
        else:
            u, C, name = within.bounded(prob, start, float(bound), o.raise_bound,
                                            o.bound_limit, flags, report)
        if method == "arap" and u is not None:
            u = within.arap(prob, u, C, report, stretch)
    except IslandError as exc:
        return failed_result(island, exc, t0, bound, start.name, flags, prob.timings)
    return finish(prob, u, C, bound, name, flags, t0, stretch)


def failed_result(island, error, t0, bound, frames_name="", flags=(), timings=None):
    return IslandResult(island.index, island.faces, island.vertices, island.tris, status="failed",
                        error=error, message=str(error), bound_requested=bound,
                        frames=frames_name, seconds=time.perf_counter() - t0, flags=tuple(flags),
                        timings=timings or {})


def unfolder(isl, V, pins, options, cancel, start=None, again=True, disk=None):
    """For ``overlap_certificate``: for an island whose map within the numeric bound asked lies
    over itself, the search for the smallest C within it (``strategies.minimise``, as
    ``bound="auto"`` with ``bound_limit`` that C) up to its first map that does not (a map of
    lower distortion often unfolds it): it stays one island (flag "unfolded"), certified at
    that C. None where that does not apply: a fixed boundary, a stretch bound, a time budget
    (conic steps), a method or frames other than the default's.

    ``start``: (index, u) the angle start (``angle_start``) of that island's disk, over C, where
    its conformal start was bad (or a callable making it, or None, when first asked:
    ``angle_start.bent_first``): first ``bound="auto"``'s search from it, ending at its least
    map that does not lie over itself (``strategies.least_one_to_one``), taken when within C
    (flags "angle_start", "unfolded"); else as above, unless ``again`` is False (that search
    from the conformal start was made: ``disk_auto``)."""
    o = options
    if (o.bound == "auto" or o.boundary != "free" or o.stretch is not None
            or o.time_budget is not None or not batched_options(o)):
        return None
    C = float(o.bound)
    auto = dataclasses.replace(o, bound="auto", bound_limit=C)
    by_index = {island.index: island for island in isl}

    def unfold(index):
        try:
            res, u = None, None
            if start is not None and start[0] == index:
                u = start[1]() if callable(start[1]) else start[1]
            if u is not None:
                res = solve_island(by_index[index], V, pins, dataclasses.replace(o, bound="auto"),
                                   None, quiet(cancel), cancel, u,
                                   None if disk is None else (disk.G, disk.area),
                                   None if disk is None else disk.ranks, one_to_one=True)
                if res.status != "certified" or not res.bound_certified <= C:
                    res = None
            if res is None and not again:
                return None
            if res is None:
                res = solve_island(by_index[index], V, pins, auto, None, quiet(cancel), cancel,
                                   unfolding=True)
        except Cancelled:
            raise CancelledError("unwrap cancelled; nothing was changed") from None
        if res.status != "certified" or not res.bound_certified <= C:
            return None
        # certified at the C asked, as the island's other maps would be (its max distortion
        # says how far below; the search's own bound, 0.02 % above that max, leaves little room
        # for float32: a 1.0002 failed usd-wg's sedan as stored)
        return dataclasses.replace(res, bound_requested=o.bound, bound_certified=C,
                                   flags=res.flags + ("unfolded",),
                                   message=f"{res.message} (unfolded: certified at C = {C:.4g})")
    return unfold


def unfold_first(V, F, disk, u, angle, pins, options, cancel, t0):
    """At a numeric C, a ``one_disk.Disk`` whose conformal map u (nv,) complex lies over itself
    (flip-free, its boundary does not turn once) and whose angle start ``angle`` is over C:
    ``unfolder``'s search from the angle start at once, certified as a one-disk map
    (``one_disk.fitted``), not after the general path bent the conformal map into C and found
    it lying over itself (cow's
    1,251-face strip and four 400-1,240-face cow disks: every one unfolded so, the same map).
    Returns (UnwrapResult or None, whether the unfold found no map: then the unfold before a
    cut is not tried again from the angle start; a map the one-disk certificate did not clear
    is left to the general path's, as before)."""
    if turning(u.take(disk.island.loops[0])) == 1 or not np.isfinite(max_distortion(disk, u)):
        # (a conformal map that flips may turn more than once and bend into one that does not:
        # three_peaks.off, turning twice, bent in 7 projection iterations, its unfold 4x that)
        return None, False
    index = disk.island.index
    unfold = unfolder([disk.island], V, pins, options, cancel, (index, angle), again=False,
                      disk=disk)
    res = unfold(index) if unfold is not None else None
    if res is None:
        return None, unfold is not None
    return fitted(F, disk, res.uv[:, 0] + 1j * res.uv[:, 1], float(options.bound), t0, res.flags,
                  " (unfolded from its angle start)")[0], False


def angle_unfolder(disk, V, pins, options, cancel, start=None):
    """For ``overlap_certificate``: for a ``one_disk.Disk`` whose ``bound="auto"`` map from its
    conformal start lies over itself, the same search from its angle start
    (``angle_start.angle_start``), ending at its least map that does not
    (``strategies.least_one_to_one``); None where there is no angle start, its max distortion
    is over ``angle_start.ANGLE_LIMIT`` or it does not certify (the island is cut then).
    ``start``: the angle start where it is known. Not under a time budget."""
    if options.time_budget is not None or options.stretch is not None:
        return None

    def unfold(index):
        u = angle_start(V, disk) if start is None else start
        if u is None or not max_distortion(disk, u) <= ANGLE_LIMIT:
            return None
        try:
            res = solve_island(disk.island, V, pins, options, None, quiet(cancel), cancel, u,
                               (disk.G, disk.area), disk.ranks, one_to_one=True)
        except Cancelled:
            raise CancelledError("unwrap cancelled; nothing was changed") from None
        return res if res.status == "certified" else None
    return unfold


def quiet(cancel):
    """A progress report that only checks ``cancel``."""
    def report(frac, msg):
        if cancel is not None and cancel.is_set():
            raise Cancelled
    return report


def batched_options(options):
    """Do these options solve unpinned islands by the batched conformal map first?"""
    return options.method == "lscm" and options.frames in ("auto", "conformal")
