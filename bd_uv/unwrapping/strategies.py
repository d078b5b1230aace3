"""The smallest certified bound of an island's map (``bound="auto"``, Lipman 2012, Algorithm 1's
goal): ``minimise`` by ADMM onto F_C with frames (one factorisation, no conic solve); Dinkelbach
steps (one always-feasible conic program each) only under a time budget or where no flip-free map
is at hand. A map within a given bound (keep, bend, raise) and BD-ARAP are ``bounded``'s.
Returns a map in the normalised geometry and the C it is meant to be certified at; the caller
certifies it from its final UVs.
"""
import time

import numpy as np

from ..errors import InfeasibleError
from ..frames import frames_from_map
from . import energy_within, mean_relax
from .along import golden
from .bounded import bend, formulate, guaranteed_bound, start_for_solve
from .energy_within import lowered
from .searched import search
from .initial import Start
from .margins import solve_bound

# Minimising C stops after a Dinkelbach step that lowers C - 1 by less than this share of it.
# Measured against C* = where 24 steps end: mushroom 1.12375 -> 1.10996 (11 %, C* 1.10980),
# nefertiti 1.3075 -> 1.2693 (12 %, C* 1.2661), then lion-head 21 % and 7 % (1.5830, C* 1.5703),
# three_peaks 22 % and 8 % (2.005, C* 1.993), hemisphere 36 % and 3 % (1.03477, C* 1.03474).
AUTO_STEP = 0.15
# Weight of the energy (scaled to 1 at the anchor map) next to the max ratio in a Dinkelbach step:
# it keeps the faces below the max near the energy's optimum. Times the current ratio k, since the
# gains in t scale with k (mannequin-devil, k 0.6: mean 1.186 at a flat 0.01, 1.080 at 0.3 k;
# hemisphere, k 0.03: a flat 0.1 held C at 1.0372, 0.3 k reaches 1.0348).
AUTO_ENERGY = 0.3
AUTO_MAX_SOLVES = 24
# One energy solve at the certified C follows the steps when they raised the mean distortion by
# more than this share (mannequin-devil: 1.071 -> 1.150 after two steps).
AUTO_MEAN_RISE = 0.02
LINE_SEARCH = 14        # distortion evaluations along each Dinkelbach step (``best_along``)
# ``least_one_to_one`` ends the search at a target whose best map's boundary folds (does not
# turn once: ``IslandProblem.may_be_one_to_one``), asked of each target's first best and its
# last: the search's later maps are lower still and the maps that unfold are behind it (cow's
# 1,251-face strip: after its 1.5931 map, five targets, 61 iterations, reached 1.5598 turning
# twice; 133 -> 85 iterations, the same C. Camel's 1,324-face patch: its last target's first
# best, now kept, is its least one-to-one map, C 1.1919 -> 1.1878)
FOLDED_ENDS = True
# ... and at a target's map that lies over itself without folding (every
# ``target_watch.CHECK_EVERY``-th new best tested): camel's 1,324-face patch, whose last target
# ran 55 iterations over maps that overlap from its 13th on (its least one-to-one map is that
# target's first best, 1.1878): 92 -> 58 iterations, the same map
OVERLAP_ENDS = True


def minimise(prob, start, limit, budget, flags, report, t0, one_to_one=False):
    """Algorithm 1's goal, the smallest certified C, without a conic solve where a flip-free map
    is at hand (issue 21).

    A flip-free map bounds C* from above: the start, bent into C = 5 when it flips. From it
    ``searched.search`` lowers the bound by ADMM onto F_C with frames (``solvers.bound_search``:
    one factorisation for every C); without a time budget, where that raised the mean distortion
    well over the start's, its faces below the max are given back to the conformal map
    (``mean_relax.relax_island``: the same max, a lower mean). Conic programs run only where they
    are the only way or were asked for:
    - no flip-free map at hand: ``first_certified`` searches C upwards by energy solves, then
      Dinkelbach steps lower it (``ratio_step``);
    - with a time budget (``time_budget``, the command line's ``--time-budget``): Dinkelbach steps
      from the searched map while the budget lasts, each one always-feasible program whose map's
      max distortion is the next bound (Crouzeix, Ferland & Schaible 1985), the best map along
      the step kept (``best_along``), until a step lowers C - 1 by less than AUTO_STEP of itself;
      when they raised the mean distortion by more than AUTO_MEAN_RISE, one energy solve at the
      certified C lowers it (``lower_mean``).
    The budget also bounds the search (no new target after it; at least one is tried).
    ``one_to_one``: the least C among the maps that do not lie over themselves
    (``least_one_to_one``: an angle start, ``angle_start``, whose search's map may), searched
    from even where the start is over ``limit``.
    Returns (u, smallest certified C, name of the start).
    """
    flipped = not np.isfinite(start.D)
    if flipped:  # a flip-free start bounds C* from above
        # (a limit at 1 leaves no room to bend into: the projection needs C > 1, as ``bounded``)
        bent = (bend(prob, start, min(5.0, limit), report, polish=False)
                if start.u is not None and solve_bound(min(5.0, limit)) > 1.0 else None)
        start = (Start(bent, frames_from_map(prob.alpha(bent)), start.name, prob.distortion(bent))
                 if bent is not None else start_for_solve(prob, start, report))
    best, projected, steps = None, None, budget is not None
    # an angle start over the limit is searched from too: its search's map must be within it
    # (``angle_start.ANGLE_LIMIT``), the alternative being conic steps, then a cut
    if np.isfinite(start.D) and (start.D <= limit or one_to_one):
        # the start is certified at its own distortion (within the limit)
        best = (start.u, start.D) if start.D <= limit else None
        # the least C of an unpinned island with no time budget: ``one_disk``'s, bounded alike
        least = not steps and not len(prob.pin_idx) and prob.enough is None
        iterations = prob.iterations
        u, D = (least_one_to_one(prob, start, report, budget, flags, t0, least) if one_to_one
                else search(prob, start.u, report, budget, flags, t0, least=least))
        if prob.iterations == iterations and best is not None:
            # no iteration ran (a flat map's round-off, ``bound_search.FLAT``): its map is the
            # start, whose max the search measured in its own arithmetic, maybe a rounding lower
            u, D = start.u, best[1]
        if (D < best[1]) if best is not None else (D <= limit):
            ok, D = prob.check(u, D)    # the map's max distortion, measured anew
            # the search measured D in its frames, the check from the map: where they differ
            # past the check's 1e-9 (decimated-knight's 984-face strip: 4.280943621 against
            # 4.280943657), the map measured anew still betters the start
            ok = ok or (D <= limit and (best is None or D < best[1]))
            if ok:
                best = projected = (u, D)
                # its faces below the max given back to the conformal map where the search
                # raised the mean (``mean_relax``; not for a number asked whose map unfolds)
                relaxed = (mean_relax.relax_island(prob, start.u, u, D)
                           if not steps and prob.enough is None else None)
                if relaxed is not None:
                    best = projected = relaxed
                    flags.append("mean_relaxed")
                elif flipped and not steps and prob.enough is None:
                    # a start that flipped, bent and searched to its least max: the search
                    # left the mean where the bend put it (data25's cow strip: C 9.187, mean
                    # 3.17, where a solve at 9.187 gives 1.49): the energy lowered within its
                    # max by ADMM (``energy_within``, as the C = 5 path's raised bound)
                    low = _mean_lowered(prob, best)
                    if low is not None:
                        best = projected = low
                        flags.append("mean_lowered")
                # an angle start's map whose mean stays over the start's: lowered within its
                # max (``disk_angle._lowered``'s, on the island problem)
                low = (_weighted_lowered(prob, start.u, best)
                       if one_to_one and not steps and prob.enough is None else None)
                if low is not None:
                    best = projected = low
                    flags.append("mean_lowered")
                # a mean still far over the conformal start's: C given back for it
                capped = (mean_relax.capped_island(prob, start.u, best[0], start.D)
                          if not steps and prob.enough is None and not one_to_one
                          and start.name == "conformal" else None)
                if capped is not None:
                    best = projected = capped
                    flags.append("mean_capped")
    if best is None or steps:  # the conic programs' anchors, weights and scale, at the map
        formulate(prob, start if projected is None else  # the steps start from
                  Start(projected[0], frames_from_map(prob.alpha(projected[0])), start.name,
                        projected[1]))
    if best is None:
        best = first_certified(prob, start, limit, budget, flags, report, t0)
        steps = True
    # the mean before any conic step (measured only where a step ran or may run)
    mean0 = (prob.mean_distortion(best[0]) if best is not None and (steps or prob.solves)
             else np.inf)
    # a searched map that lays the island out stays so through the conic steps: a step's map
    # lying over itself would be cut by the overlap repair (camel-patch1200 under the command
    # line's time budget: 20 pieces at C 2.74 where its search gave one island at 1.19)
    laid = steps and projected is not None and lays_out(prob, projected[0])
    while steps and best is not None and prob.solves < AUTO_MAX_SOLVES:
        if budget is not None and time.perf_counter() - t0 > budget and (
                prob.solves or projected is not None):
            if "time_budget_exhausted" not in flags:
                flags.append("time_budget_exhausted")
            break
        report(0.1 + 0.8 * prob.solves / AUTO_MAX_SOLVES, f"minimising C: C* <= {best[1]:.4g}")
        u, _, _ = prob.ratio_step(best[0], AUTO_ENERGY)
        if u is not None:
            u = best_along(prob, best[0], u)
        ok, D = prob.check(u, best[1])
        if not ok or D >= best[1] or (laid and not lays_out(prob, u)):
            break
        gain = (best[1] - D) / (best[1] - 1.0)
        best = (u, D)
        if gain < AUTO_STEP:
            break
    if (prob.solves and best is not None
            and prob.mean_distortion(best[0]) > mean0 * (1.0 + AUTO_MEAN_RISE)):
        best = lower_mean(prob, best, budget, flags, report, t0, laid)
    if best is None:
        failure = prob.solver_failure()
        if failure is not None:
            raise failure
        spent = ("; the time budget ran out after "
                 f"{prob.solves} solve(s): allow more time" if "time_budget_exhausted" in flags
                 else "")
        raise InfeasibleError(f"island {prob.island.index}: no certified map found up to C = "
                              f"{limit:g}{spent}; add seams, move pins, or raise the limit",
                              prob.island.index)
    if best[0] is start.u:
        flags.append("initial_map")  # nothing bettered the start
    elif projected is not None and best[0] is projected[0]:
        flags.append("projected")    # no conic solve bettered the search
    return best + (start.name,)


def _mean_lowered(prob, best):
    """``energy_within.lowered``'s map from the searched map ``best`` = (u, D), within D: (map,
    its max measured anew) where it certifies at D or lower with a lower mean and lays the
    island out where u does, else None."""
    u, D = best
    y = lowered(prob, u, D)
    if y is None or not np.all(np.isfinite(y)):
        return None
    ok, Dy = prob.check(y, D)
    if not (ok and Dy <= D) or prob.mean_distortion(y) >= prob.mean_distortion(u):
        return None
    if not lays_out(prob, y) and lays_out(prob, u):
        return None           # it would be cut where the searched map was one piece
    return y, Dy


def _weighted_lowered(prob, v, best):
    """``energy_within.weighted_lowered`` of the searched (or relaxed) map ``best`` = (u, D)
    of an angle start v (where ``energy_within.LOWER``): (map, its max measured anew) where it
    certifies at D or lower and lays the island out, else None."""
    u, D = best
    if not energy_within.LOWER or not lays_out(prob, u):
        return None
    low = energy_within.weighted_lowered(prob, v, u, D, prob.lays_out)
    if low is None:
        return None
    ok, Dy = prob.check(low[0], D)
    return (low[0], Dy) if ok and Dy <= D else None


def least_one_to_one(prob, start, report, budget, flags, t0, least):
    """``search`` from a flip-free start, ending at the least max distortion among the start
    and the search's targets' best maps that lays the island out without overlapping itself
    (``IslandProblem.one_to_one``). Each target's best is kept at its end (``enough``, never
    accepting); after the search they are asked from the least up (a map whose boundary does
    not turn once refused at once, ``may_be_one_to_one``), so a search whose own map does not
    overlap costs one test. Within a target, every ``target_watch.CHECK_EVERY``-th new best is
    tested (``lays_out``, ``check``) where OVERLAP_ENDS, and so is the first of a target after
    one that found nothing (``bound_search.CHECK_AFTER_FRUITLESS``): kept where it lays the
    island out, and the search ended at the first that does not (its later maps are lower
    still and lie over themselves too, as the folded ones, FOLDED_ENDS). The search's own map
    where none passes (the overlap repair cuts it then). Returns (u, its max distortion)."""
    kept = [(start.u, start.D, None)]       # (map, its max distortion, lays out: None unknown)

    def record(v):                  # ends the search at a map whose boundary folded
        if not np.array_equal(kept[-1][0], v):      # (``check`` kept it just before)
            kept.append((v, prob.distortion(v), None))
        return FOLDED_ENDS and not prob.may_be_one_to_one(v)

    def check(v):                   # ends the search at a map that lies over itself
        laid = lays_out(prob, v)
        kept.append((v, prob.distortion(v), laid))
        return not laid
    u, D = search(prob, start.u, report, budget, flags, t0, enough=record, least=least,
                  ready=_always if FOLDED_ENDS else None,
                  check=check if OVERLAP_ENDS else None)
    if np.array_equal(kept[-1][0], u):     # the search's map is its last target's best
        kept[-1] = (u, D, kept[-1][2])
    else:
        kept.append((u, D, None))
    for v, Dv, laid in sorted(kept, key=lambda c: c[1]):
        if np.isfinite(Dv) and (laid if laid is not None else lays_out(prob, v)):
            return v, Dv
    return u, D


def _always(v):
    return True


def lays_out(prob, v):
    """Does the flip-free map v lay the island out without overlapping itself
    (``IslandProblem.lays_out``: the boundary loop's test on a disk)?"""
    return prob.lays_out(v)


def lower_mean(prob, best, budget, flags, report, t0, laid=False):
    """One energy solve over F_C at the bound the map ``best`` = (u, D) certifies, from its own
    frames (where it is feasible, eq. 4.21): the min-max steps leave faces below the max wherever
    that helped the max, the energy brings them back (issue 9, "a final energy solve at the
    certified C"). Returns the solve's map when it certifies with a lower mean (and, with
    ``laid``, lays the island out without overlapping itself), else ``best``."""
    if budget is not None and time.perf_counter() - t0 > budget:
        flags.append("time_budget_exhausted")
        return best
    C = guaranteed_bound(best[1])
    report(0.9, f"lowering the mean distortion at C = {C:.4g}")
    u, _ = prob.solve(frames_from_map(prob.alpha(best[0])), C)
    ok, D = prob.check(u, C)
    if ok and prob.mean_distortion(u) < prob.mean_distortion(best[0]) and (
            not laid or lays_out(prob, u)):
        return u, D
    return best


def best_along(prob, u0, u1, evaluations=LINE_SEARCH):
    """The map of lowest max distortion on the segment from u0 to u1 (u1 included), by golden
    section on s in [0, 1] of ``u0 + s (u1 - u0)`` (``along.golden``).

    With the frames fixed each face's ratio ``|beta_j| / Re(w_j alpha_j)`` is convex over linear
    along the segment, so their max is quasi-convex; the conformal distortion (eq. 4.9) follows it
    closely. A Dinkelbach step can overshoot where faces grew (lion-head: 1.650 at s = 1, 1.626 at
    s = 0.82). Vectorised distortion evaluations only, no solve.
    """
    d = u1 - u0
    s, Ds = golden(lambda s: prob.distortion(u0 + s * d), evaluations)
    return u0 + s * d if Ds < prob.distortion(u1) else u1


def first_certified(prob, start, limit, budget, flags, report, t0):
    """A first certified map when no flip-free map is at hand: energy solves over F_C from C = 5
    (or the limit), doubling C (and, past the start's own distortion, the bound it is known to
    meet) until one certifies. Returns (u, its max distortion) or None."""
    C, w = min(5.0, limit), start.frames
    while prob.solves < AUTO_MAX_SOLVES and C <= limit:
        if prob.solves and budget is not None and time.perf_counter() - t0 > budget:
            flags.append("time_budget_exhausted")
            return None
        report(0.1 + 0.8 * prob.solves / AUTO_MAX_SOLVES, f"looking for a map within C = {C:.3g}")
        u, _ = prob.solve(w, C)
        ok, D = prob.check(u, C)
        if ok:
            return u, D
        C *= 2.0
        if np.isfinite(start.D) and C >= start.D:
            C, w = guaranteed_bound(start.D), start.frames
    return None
