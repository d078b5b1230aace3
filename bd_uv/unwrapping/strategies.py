"""How an island's map is found for a bound: keep, bend, raise, minimise (Lipman 2012, section 6).

- ``bounded``: a start map within C is returned as it is; otherwise one solve over F_C from the
  start's frames, anchored at the start (``IslandProblem.anchor_to``); when F_C is empty, C is
  raised towards the bound the flip-free start is known to meet.
- ``minimise`` (``bound="auto"``): the smallest certified C (Algorithm 1's goal) by ADMM onto F_C
  with frames (one factorisation, no conic solve); Dinkelbach steps (one always-feasible conic
  program each) only under a time budget or where no flip-free map is at hand.
- ``arap``: BD-ARAP iterations with frames from the previous map.
Each returns a map in the normalised geometry and the C it is meant to be certified at; the caller
certifies it from its final UVs.
"""
import time

import numpy as np

from ..errors import InfeasibleError
from ..frames import frames_from_map
from ..solvers.flip_free import flip_free_map
from ..solvers.bound_search import BoundSearch
from ..spaces import stretch_conformal_bound
from .initial import Start, start_map
from .problem import (SOLVE_MARGIN, STORE_HEADROOM, STRETCH_MARGIN_SOLVE, Cancelled,
                      solve_bound)

RAISE_FACTOR = 1.5      # C grows by this factor when infeasible
MAX_RESETS = 3          # frame resets after the first feasible solve (BD-Dirichlet, BD-ARAP)
IMPROVEMENT = 0.01      # keep resetting frames while the energy drops by more than this fraction
# Reset frames only when a solution turns faces away from their frames by more than this (radians,
# 99th percentile, after removing the common rotation).
FRAME_TOLERANCE = 0.1
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
# Minimising C within a stretch bound (``stretch.minimise_stretch``) first tries
# 1 + (D - 1)(1 - DESCENT) below the best bound D.
DESCENT = 0.15
# Polish a projected map with one conic solve when the projection changed more than this share of
# the island's area (measured: three_peaks 10 % at C = 5, mannequin-devil 0.3 %, lion-head at C = 2
# 0.2 %: a local bend leaves the conformal map's distortion elsewhere, which a solve cannot lower).
POLISH_AREA = 0.05
# The polish is one conic solve cut short: any iterate that certifies will do, and an early one
# sits inside F_C rather than on its boundary, where the energy's optimum pushes the faces
# (three_peaks at C = 5: 20 iterations to tolerance 1e-6 give max 4.98, mean 1.346; 8 at 1e-3
# give max 3.29, mean 1.297, in 0.2x the solve's time; 5 did not certify).
POLISH_SETTINGS = dict(max_iter=8, tol_gap=1e-3, tol_feas=1e-4)
# Energies whose result is always the solve's optimum: no start is kept as it is, no projection.
ALWAYS_SOLVED = ("dirichlet", "stretch-l1")

_WHY = {"infeasible": "the space is empty for these frames",
        "inexact": "the solver did not converge", "error": "the solver failed",
        "solved": "the solver's map did not pass certification"}


def fits(start, C):
    """Whether a start map is within C with room for how its UVs will be stored."""
    return start.u is not None and start.D * (1.0 + STORE_HEADROOM) <= C


def guaranteed_bound(D0):
    """The requested C whose solve bound still contains a flip-free map of max distortion D0."""
    return max(1.0 + (D0 - 1.0) / (1.0 - SOLVE_MARGIN), D0 * (1.0 + STORE_HEADROOM)) \
        * (1 + 1e-9) + 1e-12


def formulate(prob, start):
    """Set up the island's formulation from its start map (see ``IslandProblem.anchor_to``)."""
    u = start.u if start.u is not None else prob.fallback_map()
    if prob.method == "stretch-l1":
        prob.hold_scale(u)  # the L1 stretch energy shrinks the map to a point unless held
    elif prob.method == "dirichlet":
        prob.floor_scale(u, start.frames)
    else:
        prob.anchor_to(u)


def bounded(prob, start, C, raise_bound, limit, flags, report):
    """A certified-to-be map within C. Returns (u, C, name of the start it came from)."""
    isl = prob.island
    solved = prob.method in ALWAYS_SOLVED
    if not solved and fits(start, C):
        flags.append("initial_map")  # the start already fits: nothing to bend
        return start.u, C, start.name
    if not solved and start.u is not None and solve_bound(C) > 1.0:   # the projection needs C > 1
        bent = bend(prob, start, C, report, flags)
        if bent is not None:
            return bent, C, start.name
    start = start_for_solve(prob, start, report)
    formulate(prob, start)
    w, best, prev_e, retried, resets = start.frames, None, None, False, 0
    D0 = start.D
    while True:
        report(min(0.9, 0.1 + 0.15 * prob.solves), f"solving at C = {C:.3g}")
        u, outcome = prob.solve(w, C)
        ok, D = prob.check(u, C)
        if ok:
            best = (u, C, start.name)
            if not solved:
                # BD-LSCM: frame resets lower the energy but measured higher mean distortion
                # (three_peaks 1.378 -> 1.397 over 5 resets), so one solve is the answer.
                return best
            e = prob.energy_of(u, w)
            if (prev_e is not None and prev_e - e <= IMPROVEMENT * abs(prev_e)
                    or resets >= MAX_RESETS or frame_turn(prob, u, w) <= FRAME_TOLERANCE):
                return best
            prev_e, resets = e, resets + 1
            w = frames_from_map(prob.alpha(u))
            continue
        if best is not None:  # a later frame reset did not certify: keep the last certified map
            return best
        if u is not None and not retried and outcome == "inexact":
            retried = True  # an inexact iterate may still give better frames; an infeasible one not
            w = frames_from_map(prob.alpha(u))
            continue
        if np.isfinite(D0) and prob.check(start.u, C)[0]:
            flags.append("initial_map")  # the solver failed where the start already fits
            return start.u, C, start.name
        failure = prob.solver_failure()
        if failure is not None and (not raise_bound or C * RAISE_FACTOR > limit):
            raise failure
        if not raise_bound:
            raise InfeasibleError(f"island {isl.index}: no map within distortion {C:g} was found "
                                  f"({_WHY.get(outcome, outcome)}); allow raising the bound or "
                                  "use a larger C", isl.index)
        newC = C * RAISE_FACTOR
        if np.isfinite(D0):  # approach the bound known to be feasible geometrically
            newC = max(newC, np.sqrt(C * D0))
            if newC * RAISE_FACTOR >= D0:
                newC = max(guaranteed_bound(D0), C * 1.0001)
        w = start.frames
        if newC > limit:
            raise InfeasibleError(f"island {isl.index}: infeasible up to the bound limit "
                                  f"{limit:g}" + (" (the pins force a flip or a larger distortion)"
                                                  if len(prob.pin_idx) >= 2 else "")
                                  + "; raise the limit, move or remove pins, or add seams",
                                  isl.index)
        if "bound_raised" not in flags:
            flags.append("bound_raised")
        C, retried = newC, False


def bend(prob, start, C, report, flags=None, polish=True):
    """Bend a start that breaks the bound into F_C, only where the bound demands.

    Projection iterations (Kovalsky et al. 2015, ``solvers.flip_free``) move the faces above C and
    their neighbourhood, from the start itself even when it flips, and keep the start's
    distortion elsewhere. When they changed more than POLISH_AREA of the island's area, one conic
    solve from the harmonic map's frames (``IslandProblem.anchor_to``) redistributes the
    distortion; the map with the lower mean is kept (three_peaks at C = 5: projection 1.378, the
    solve 1.297, cut short by POLISH_SETTINGS).
    ``polish=False`` skips that solve (``minimise`` only needs a flip-free map to descend from).
    Returns the map, or None when the projection stalled (the caller solves from a flip-free start).
    """
    if len(prob.pin_idx) >= prob.nv:
        return None  # every vertex pinned: nothing can move
    report(0.1, f"bending into C = {C:.3g}")
    t = time.perf_counter()
    pins = (prob.pin_idx, prob.pin_val) if len(prob.pin_idx) else None
    u, info = flip_free_map(prob.Z, prob.island.tris, prob.nv, prob.island.loops, start.u,
                            solve_bound(C), pins=pins, cancel=prob.cancel)
    prob.timings["project"] = prob.timings.get("project", 0.0) + time.perf_counter() - t
    prob.iterations += info["iterations"]
    if u is None or not prob.check(u, C)[0]:
        return None
    D0 = prob.face_distortion(start.u)
    D = prob.face_distortion(u)
    changed = ~(np.abs(D - D0) <= 0.01 * D0)
    if flags is not None:
        flags.append("projected")
    if (not polish or prob.method != "lscm"
            or np.sum(prob.ops.area[changed]) <= POLISH_AREA * prob.ops.area.sum()):
        return u
    report(0.5, f"solving at C = {C:.3g}")
    # From the harmonic map's frames, anchored at it: on three_peaks they gave a lower mean (1.346)
    # than the projected map's own frames (1.369).
    harmonic = start_map(prob, "harmonic", None, report)
    prob.anchor_to(harmonic.u)
    us, _ = prob.solve(harmonic.frames, C, **POLISH_SETTINGS)
    if prob.check(us, C)[0] and prob.mean_distortion(us) < prob.mean_distortion(u):
        if flags is not None:
            flags.remove("projected")
        return us
    return u


def start_for_solve(prob, start, report):
    """A flip-free start for the conic solve when projection stalled: the start itself when it is
    flip-free (or frames only), else the harmonic map."""
    if start.u is None or np.isfinite(start.D):
        return start
    return start_map(prob, "harmonic", None, report)


def minimise(prob, start, limit, budget, flags, report, t0):
    """Algorithm 1's goal, the smallest certified C, without a conic solve where a flip-free map
    is at hand (issue 21).

    A flip-free map bounds C* from above: the start, bent into C = 5 when it flips. From it
    ``search`` lowers the bound by ADMM onto F_C with frames (``solvers.bound_search``: one
    factorisation for every C). Conic programs run only where they are the only way or were
    asked for:
    - no flip-free map at hand: ``first_certified`` searches C upwards by energy solves, then
      Dinkelbach steps lower it (``ratio_step``);
    - with a time budget (``time_budget``, the command line's ``--time-budget``): Dinkelbach steps
      from the searched map while the budget lasts, each one always-feasible program whose map's
      max distortion is the next bound (Crouzeix, Ferland & Schaible 1985), the best map along
      the step kept (``best_along``), until a step lowers C - 1 by less than AUTO_STEP of itself;
      when they raised the mean distortion by more than AUTO_MEAN_RISE, one energy solve at the
      certified C lowers it (``lower_mean``).
    The budget also bounds the search (no new target after it; at least one is tried).
    Returns (u, smallest certified C, name of the start).
    """
    if not np.isfinite(start.D):  # a flip-free start bounds C* from above
        bent = (bend(prob, start, min(5.0, limit), report, polish=False) if start.u is not None
                else None)
        start = (Start(bent, frames_from_map(prob.alpha(bent)), start.name, prob.distortion(bent))
                 if bent is not None else start_for_solve(prob, start, report))
    best, projected, steps = None, None, budget is not None
    if np.isfinite(start.D) and start.D <= limit:
        best = (start.u, start.D)   # the start is certified at its own distortion
        u, D = search(prob, start.u, report, budget, flags, t0)
        if D < best[1] and prob.check(u, D)[0]:
            best = projected = (u, prob.distortion(u))
    if best is None or steps:  # the conic programs' anchors, weights and scale, at the map
        formulate(prob, start if projected is None else  # the steps start from
                  Start(projected[0], frames_from_map(prob.alpha(projected[0])), start.name,
                        projected[1]))
    if best is None:
        best = first_certified(prob, start, limit, budget, flags, report, t0)
        steps = True
    mean0 = prob.mean_distortion(best[0]) if best is not None else np.inf
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
        if not ok or D >= best[1]:
            break
        gain = (best[1] - D) / (best[1] - 1.0)
        best = (u, D)
        if gain < AUTO_STEP:
            break
    if (prob.solves and best is not None
            and prob.mean_distortion(best[0]) > mean0 * (1.0 + AUTO_MEAN_RISE)):
        best = lower_mean(prob, best, budget, flags, report, t0)
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


def search(prob, u, report, budget, flags, t0):
    """Lower the bound of a flip-free map ``u`` by ADMM onto F_C with frames
    (``solvers.bound_search``), holding the pins (or one boundary vertex, where ``u`` has it).
    Returns (the best map, its max distortion); flags "time_budget_exhausted" when the budget
    stopped it."""
    if len(prob.pin_idx) >= prob.nv:
        return u, prob.distortion(u)
    t = time.perf_counter()
    fixed = prob.pin_idx if len(prob.pin_idx) else prob.island.loops[0][:1]
    u = u.copy()
    if len(prob.pin_idx):
        u[prob.pin_idx] = prob.pin_val
    bs = BoundSearch(prob.ops, prob.nv, prob.island.tris, fixed)

    def progress(D, C):
        report(0.1, f"minimising C: C* <= {D:.4g}, aiming at {C:.4g}")

    deadline = None if budget is None else t0 + budget
    u, D, out_of_time = bs.search(u, lambda v: frames_from_map(prob.alpha(v)), progress,
                                  deadline, prob.cancel)
    if prob.cancel is not None and prob.cancel.is_set():
        raise Cancelled
    if out_of_time:
        flags.append("time_budget_exhausted")
    prob.iterations += bs.iterations
    prob.timings["project"] = prob.timings.get("project", 0.0) + time.perf_counter() - t
    return u, D


def lower_mean(prob, best, budget, flags, report, t0):
    """One energy solve over F_C at the bound the map ``best`` = (u, D) certifies, from its own
    frames (where it is feasible, eq. 4.21): the min-max steps leave faces below the max wherever
    that helped the max, the energy brings them back (issue 9, "a final energy solve at the
    certified C"). Returns the solve's map when it certifies with a lower mean, else ``best``."""
    if budget is not None and time.perf_counter() - t0 > budget:
        flags.append("time_budget_exhausted")
        return best
    C = guaranteed_bound(best[1])
    report(0.9, f"lowering the mean distortion at C = {C:.4g}")
    u, _ = prob.solve(frames_from_map(prob.alpha(best[0])), C)
    ok, D = prob.check(u, C)
    if ok and prob.mean_distortion(u) < prob.mean_distortion(best[0]):
        return u, D
    return best


def best_along(prob, u0, u1, evaluations=LINE_SEARCH):
    """The map of lowest max distortion on the segment from u0 to u1 (u1 included), by golden
    section on s in [0, 1] of ``u0 + s (u1 - u0)``.

    With the frames fixed each face's ratio ``|beta_j| / Re(w_j alpha_j)`` is convex over linear
    along the segment, so their max is quasi-convex; the conformal distortion (eq. 4.9) follows it
    closely. A Dinkelbach step can overshoot where faces grew (lion-head: 1.650 at s = 1, 1.626 at
    s = 0.82). Vectorised distortion evaluations only, no solve.
    """
    d = u1 - u0
    D = lambda s: prob.distortion(u0 + s * d)
    g = 0.5 * (np.sqrt(5.0) - 1.0)
    a, b = 0.0, 1.0
    c, e = b - g * (b - a), a + g * (b - a)
    fc, fe = D(c), D(e)
    for _ in range(evaluations - 2):
        if fc < fe:
            b, e, fe = e, c, fc
            c = b - g * (b - a)
            fc = D(c)
        else:
            a, c, fc = c, e, fe
            e = a + g * (b - a)
            fe = D(e)
    s, Ds = (c, fc) if fc < fe else (e, fe)
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


def arap(prob, u, C, report, S=None):
    """BD-ARAP: minimise the ARAP energy over F_C with frames from the previous map, resetting
    the frames while the energy improves (section 6.1, "As-rigid-as-possible"). With a stretch
    bound S the rows of section 6.3 are added (``stretch.stretch_solve``'s scale and margins) and
    each iterate must pass them as certified (``IslandProblem.within``)."""
    if len(prob.pin_idx) < 2:
        # ARAP has an absolute scale: start from the map scaled to the 3D area, one anchor.
        scale = np.sqrt(1.0 / uv_area(u, prob.island.tris))
        if len(prob.pin_idx):
            p = prob.pin_val[0]
            u = p + (u - p) * scale
            prob.set_anchors(prob.pin_idx, prob.pin_val)
        else:
            u = (u - u[0]) * scale
            prob.set_anchors(np.array([0]), u[:1])
    else:
        prob.set_anchors(prob.pin_idx, prob.pin_val)
    prob.weights = None
    prob.sigma = 1e-3 * float(np.median(np.abs(prob.alpha(u))))
    Cs = C
    if S is not None:
        k = np.sqrt(prob.area3d) if len(prob.pin_idx) >= 2 else 1.0
        prob.fix_scale = len(prob.pin_idx) < 2
        prob.stretch = (k * STRETCH_MARGIN_SOLVE / S, k * S / STRETCH_MARGIN_SOLVE)
        Cs = stretch_conformal_bound(C, STRETCH_MARGIN_SOLVE / S, S / STRETCH_MARGIN_SOLVE)
    prev = None
    for i in range(MAX_RESETS + 1):
        w = frames_from_map(prob.alpha(u))
        prob.scale = 1.0 / max(prob.energy_of(u, w), 1e-6)
        report(0.9, f"BD-ARAP iteration {i + 1}")
        un, _ = prob.solve(w, Cs)
        if not prob.within(un, C, S):
            break
        e = prob.energy_of(un, w)
        u = un
        if prev is not None and prev - e <= IMPROVEMENT * abs(prev):
            break
        prev = e
    prob.stretch, prob.fix_scale = None, False
    return u


def frame_turn(prob, u, w):
    """How far a map turns faces away from frames w, beyond their common rotation (radians,
    99th percentile)."""
    wa = w * prob.alpha(u)
    common = np.sum(prob.ops.area * wa / np.maximum(np.abs(wa), 1e-300))
    turn = np.abs(np.angle(wa * np.conj(common)))
    return float(np.percentile(turn, 99))


def uv_area(u, tris):
    """Signed UV area of a map."""
    p = u[tris]
    return float(np.sum(0.5 * ((p[:, 1] - p[:, 0]).conj() * (p[:, 2] - p[:, 0])).imag))
