"""An island's map within a given bound: keep, bend, raise (Lipman 2012, section 6), and BD-ARAP.

- ``bounded``: a start map within C is returned as it is; otherwise it is bent into F_C where the
  bound demands (``bend``: projection iterations, then the bound search where they moved much of
  the island), or one solve over F_C from the start's frames, anchored at the start
  (``IslandProblem.anchor_to``); when F_C is empty, C is raised towards the bound the flip-free
  start is known to meet. A flip-free start over C is first lowered by the bound search
  (``searched.over_bound``): C out of its reach is raised to its map at once, and its map stands
  in for the raise's solves.
- ``arap``: BD-ARAP iterations with frames from the previous map.
Each returns a map in the normalised geometry and the C it is meant to be certified at; the caller
certifies it from its final UVs. Minimising C (``bound="auto"``) is ``strategies.minimise``'s.
"""
import time

import numpy as np

from ..errors import InfeasibleError
from ..frames import frames_from_map
from ..solvers.flip_free import flip_free_map
from ..spaces import stretch_conformal_bound
from .along import least_mean_within
from .energy_within import from_harmonic
from .initial import start_map
from .margins import (SOLVE_MARGIN, STORE_HEADROOM, STRETCH_MARGIN_SOLVE, certified_bound,
                      solve_bound)
from .searched import over_bound, search, searched_fallback

RAISE_FACTOR = 1.5      # C grows by this factor when infeasible
MAX_RESETS = 3          # frame resets after the first feasible solve (BD-Dirichlet, BD-ARAP)
IMPROVEMENT = 0.01      # keep resetting frames while the energy drops by more than this fraction
# Reset frames only when a solution turns faces away from their frames by more than this (radians,
# 99th percentile, after removing the common rotation).
FRAME_TOLERANCE = 0.1
# Minimising C within a stretch bound (``stretch.minimise_stretch``) first tries
# 1 + (D - 1)(1 - DESCENT) below the best bound D.
DESCENT = 0.15
# Lower a projected map's bound by the bound search when the projection changed more than this
# share of the island's area (measured: three_peaks 10 % at C = 5, mannequin-devil 0.3 %, lion-head
# at C = 2 0.2 %: a local bend leaves the conformal map's distortion elsewhere, which no solve
# lowers).
POLISH_AREA = 0.05
# Distortion evaluations between the projected map and the searched one (``along``): three_peaks at
# C = 5 mean 1.3098 (searched) -> 1.3032.
MEAN_SEARCH = 12
# The searched map is kept when it lowered the projected map's mean excess over 1 by at least this
# share (three_peaks at C = 5: 20 %, 1.378 -> 1.303; the conic polish would reach 1.297 in twice
# the time); else the polish runs (a torus cut into a disk with holes: 1 %, 3.196 -> 3.177, and
# its UVs overlapped, the polish gives 2.366 and none).
SEARCH_GAIN = 0.1
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
    if (not solved and prob.method == "lscm" and start.u is not None and np.isfinite(start.D)
            and solve_bound(C) > 1.0):
        # a flip-free start over C: the bound search rather than projection iterations
        found, searched = over_bound(prob, start, C, raise_bound, limit, report)
        if found is not None:
            flags += ["projected", "bound_raised"]
            return found + (start.name,)
    else:
        searched = None
    if not solved and start.u is not None and solve_bound(C) > 1.0:   # the projection needs C > 1
        # an unpinned BD-LSCM island whose conformal start flips and whose projection from it
        # stalls: its harmonic map searched into C and its energy lowered there
        # (``energy_within``) before its projection (up to 300 iterations) and a conic solve
        quick = not np.isfinite(start.D) and prob.method == "lscm" and not len(prob.pin_idx)
        bent = bend(prob, start, C, report, flags, harmonic=not quick)
        found, far = from_harmonic(prob, C, report) if quick and bent is None else (None, 0)
        if found is not None:
            flags.append("projected")
            return found[0], C, found[1].name
        if far and raise_bound and certified_bound(far[0][1]) <= limit:
            # C out of the search's reach: the bound raised to its map at once, as
            # ``over_bound`` raises a flip-free start's (cow's 1,651-face strip at C = 5: 9.19
            # in ~0.07 s, where the raise's conic solves reached 60.5 in 0.5 s)
            flags += ["projected", "bound_raised"]
            return far[0][0], certified_bound(far[0][1]), far[1].name
        if quick and bent is None and not far:  # as before: the harmonic map projected
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
        fallback = (searched_fallback(prob, start, searched, C, raise_bound, limit)
                    if searched is not None else None)
        if fallback is not None:
            # the searched map (a sphere with a hole at C = 2.4: certified at 2.52, where the
            # raise's conic solves reached 3.72)
            flags += [f for f in fallback[1] if f not in flags]
            return fallback[0] + (start.name,)
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


def bend(prob, start, C, report, flags=None, polish=True, harmonic=None):
    """Bend a start that breaks the bound into F_C, only where the bound demands.

    Projection iterations (Kovalsky et al. 2015, ``solvers.flip_free``) move the faces above C and
    their neighbourhood, from the start itself even when it flips, and keep the start's
    distortion elsewhere. When they changed more than POLISH_AREA of the island's area, the
    bound search (``search``: ADMM onto F_C with frames, one factorisation, no conic solve)
    lowers the map's max distortion, and the mean with it, and the map of least mean on the
    segment between the two within C is taken (``along.least_mean_within``; three_peaks at
    C = 5: projection 1.378, searched 1.310 at max 2.07, between 1.303, in 0.1 s; the conic
    polish gave 1.297 in 0.25 s, ABF's whole unwrap taking 0.27 s). Where that lowered the
    mean by less than SEARCH_GAIN of its excess, one conic solve from the harmonic map's frames
    (``IslandProblem.anchor_to``) polishes it, cut short by POLISH_SETTINGS, and the map with
    the lower mean is kept.
    ``polish=False`` skips both (``minimise`` searches the map itself). ``harmonic``: project
    the harmonic map where the projection from the start stalls (by default where ``polish``).
    """
    if len(prob.pin_idx) >= prob.nv:
        return None  # every vertex pinned: nothing can move
    report(0.1, f"bending into C = {C:.3g}")
    t = time.perf_counter()
    pins = (prob.pin_idx, prob.pin_val) if len(prob.pin_idx) else None
    # where the LSCM start fails, ``minimise`` (no polish) searches from the harmonic map
    # instead of projecting it
    u, info = flip_free_map(prob.Z, prob.island.tris, prob.nv, prob.island.loops, start.u,
                            solve_bound(C), pins=pins, cancel=prob.cancel,
                            harmonic=polish if harmonic is None else harmonic, ops=prob.ops)
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
    us, _ = search(prob, u, report, None, [], time.perf_counter())
    # the search lowers the max, and the mean most of the way: the least mean lies between
    um = least_mean_within(prob, u, us, C, MEAN_SEARCH)
    m0, m = prob.mean_distortion(u), prob.mean_distortion(um)
    if not prob.check(um, C)[0]:
        um, m = u, m0
    if m0 - m >= SEARCH_GAIN * (m0 - 1.0):
        return um
    report(0.5, f"solving at C = {C:.3g}")
    # From the harmonic map's frames, anchored at it: on three_peaks they gave a lower mean (1.346)
    # than the projected map's own frames (1.369).
    harmonic = start_map(prob, "harmonic", None, report)
    prob.anchor_to(harmonic.u)
    us, _ = prob.solve(harmonic.frames, C, **POLISH_SETTINGS)
    if prob.check(us, C)[0] and prob.mean_distortion(us) < m:
        if flags is not None:
            flags.remove("projected")
        return us
    return um


def start_for_solve(prob, start, report):
    """A flip-free start for the conic solve when projection stalled: the start itself when it is
    flip-free (or frames only), else the harmonic map."""
    if start.u is None or np.isfinite(start.D):
        return start
    return start_map(prob, "harmonic", None, report)


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
    return float(np.add.reduce(0.5 * ((p[:, 1] - p[:, 0]).conj() * (p[:, 2] - p[:, 0])).imag))
