"""Stretch bounds in an island's search (Lipman 2012, section 6.3, eqs. 6.3-6.4).

Every face's singular values within [1/S, S] together with the conformal bound C, as certified
from the final UVs (``IslandProblem.stretch_range``: at the island's own scale, UV area = 3D area,
when fewer than two pins fix it; else relative to the 3D geometry).

- ``bounded_stretch``: the start when it fits; projection iterations with singular-value bounds,
  polished by a conic solve; a conic solve with the stretch rows when the projection stalls;
- ``stretch_solve``: that conic solve (``spaces.stretch_space`` rows with the scale held by
  ``IslandProblem.hold_scale``);
- ``minimise_stretch``: ``bound="auto"`` with S, bisection on C.
"""
import time

import numpy as np

from ..errors import InfeasibleError
from ..frames import frames_from_map
from ..solvers.projection import ProjectionSolver
from ..spaces import stretch_conformal_bound
from .initial import start_map
from .margins import STORE_HEADROOM, STRETCH_MARGIN_SOLVE, solve_bound
from .bounded import ALWAYS_SOLVED, DESCENT, IMPROVEMENT, MAX_RESETS, POLISH_AREA, fits
from .strategies import AUTO_MAX_SOLVES

# Projection iterations bound the singular values by [m/S, S/m] with this m: the result is
# certified at its own final scale, which the iterations move.
STRETCH_MARGIN = 1.03
# A conic solve whose result misses [1/S, S] at its own scale is repeated with the margin grown by
# the miss, at most this many times per frames tried.
STRETCH_RETRIES = 3
# bound="auto" with S: bisection on C stops when C_right - C_left <= AUTO_TOLERANCE (C_right - 1)
# + AUTO_FLOOR (relative to C - 1: near C = 1 a 1 % tolerance on C is most of what is left).
AUTO_TOLERANCE = 0.02
AUTO_FLOOR = 5e-4


def stretch_solve(prob, frames, u_ref, C, S, report):
    """Minimise the island's energy over F_C with the singular-value rows of section 6.3
    (``spaces.stretch_space``: eq. 6.3 as a cone, the lower bound as a cone given the frames).

    The bounds are relative to the scale the certificate measures: with fewer than two pins the
    island's scale is held by ``IslandProblem.hold_scale`` (area-weighted mean of Re(w alpha) = 1
    on the unit-area island) and the bounds are ``[m/S, S/m]``; the UV area that the certificate
    rescales by is not linear in the map, so when the result misses [1/S, S] at its own scale the
    margin m grows by the miss and the solve is repeated (``STRETCH_RETRIES``). With two or more
    pins the bounds are absolute (relative to the 3D geometry), as the certificate measures them.
    The conformal rows use ``spaces.stretch_conformal_bound`` (C lowered when S leaves the scale
    no room); the result is certified at C.
    An inexact solve resets the frames from its last iterate once (eq. 4.21); an infeasible one
    moves on to the next frames.

    Parameters
    ----------
    prob : IslandProblem
    frames : sequence of (k,) complex unit frames to start from, tried in turn
    u_ref : (nv,) complex, a map giving the anchor position and the LSCM weights
    C : float, S : float

    Returns
    -------
    (nv,) complex map certified to be within C and S (``within``), or None
    """
    prob.hold_scale(u_ref)
    k = np.sqrt(prob.area3d) if len(prob.pin_idx) >= 2 else 1.0
    best = None
    for w0 in frames:
        m, w, reset = STRETCH_MARGIN_SOLVE, w0, False
        for _ in range(STRETCH_RETRIES + 2):
            prob.stretch = (k * m / S, k * S / m)
            report(0.5, f"solving at C = {C:.3g} with stretch {S:.3g}")
            u, outcome = prob.solve(w, stretch_conformal_bound(C, m / S, S / m))
            if prob.within(u, C, S):
                best = u
                break
            if outcome == "solved" and prob.check(u, C)[0]:
                # within C but not within S at its own scale: narrow the solve's bounds
                lo, hi = prob.stretch_range(u)
                m *= max(hi * (1 + STORE_HEADROOM) / S, (1 + STORE_HEADROOM) / (S * lo),
                         1.0) * 1.002
                if m >= S:  # [m/S, S/m] is empty
                    break
            elif outcome == "inexact" and u is not None and not reset:
                # an inexact iterate may still give better frames (eq. 4.21); an infeasible not
                reset, w = True, frames_from_map(prob.alpha(u))
            else:
                break
        if best is not None:
            break
    prob.stretch = None
    return best


def bounded_stretch(prob, start, C, S, report, flags=None):
    """A map within C whose singular values lie in [1/S, S] (section 6.3) as certified: the start
    when it already does; else projection iterations with the singular-value bounds (Kovalsky et
    al. 2015 with Lipman 2012, section 6.3), polished by a conic solve with the stretch rows
    (``stretch_solve``) when they changed more than POLISH_AREA of the island, and a conic solve
    when they stall (from the start's, the stalled iterate's and the harmonic map's frames).
    BD-Dirichlet and the L1 stretch energy are always solved (their result is the energy's
    optimum). Returns (u, C, name)."""
    solved = prob.method in ALWAYS_SOLVED
    if not solved and start.u is not None and np.isfinite(start.D) and fits(start, C):
        if prob.within(start.u, C, S):
            if flags is not None:
                flags.append("initial_map")
            return start.u, C, start.name
    if len(prob.pin_idx) >= prob.nv:
        raise InfeasibleError(f"island {prob.island.index}: every vertex is pinned and the pins "
                              f"break the bounds C = {C:g}, S = {S:g}", prob.island.index)
    k = np.sqrt(prob.area3d) if len(prob.pin_idx) >= 2 else 1.0
    fixed = prob.pin_idx if len(prob.pin_idx) else prob.island.loops[0][:1]
    solver = ProjectionSolver(prob.ops, prob.nv, fixed, tris=prob.island.tris)
    starts = [start] if start.u is not None else []
    harmonic = start_map(prob, "harmonic", None, report)
    starts.append(harmonic)
    projected, tried = None, []
    t = time.perf_counter()
    # S close to 1 leaves the projection's own margins (1 % each side) no room, and C = 1 (maps
    # conformal on every face) leaves the projection no set to project onto: conic solve only
    pm = min(STRETCH_MARGIN, S ** 0.25)
    project = not solved and solve_bound(C) > 1.0 and (pm / S) * 1.011 <= (S / pm) * 0.989
    try:
        for st in starts if project else []:
            report(0.2, f"bending into C = {C:.3g}, stretch {S:.3g}")
            values = prob.pin_val if len(prob.pin_idx) else st.u[fixed]
            # margins: the result is measured again at its own scale, which the iterations move
            res = solver.project(st.u, solve_bound(C), values, smin=k * pm / S, smax=k * S / pm,
                                 max_iter=400, cancel=prob.cancel)
            prob.iterations += res.iterations
            if res.all_converged and prob.within(res.u, C, S):
                projected = (res.u, st)
                break
            if res.u is not None and np.all(np.isfinite(res.u)):
                tried.append(frames_from_map(prob.alpha(res.u)))
    finally:
        prob.timings["project"] = prob.timings.get("project", 0.0) + time.perf_counter() - t
    if projected is not None:
        u, st = projected
        D0, D = prob.face_distortion(st.u), prob.face_distortion(u)
        changed = ~(np.abs(D - D0) <= 0.01 * D0)
        if prob.method != "lscm" or \
                np.sum(prob.ops.area[changed]) <= POLISH_AREA * prob.ops.area.sum():
            if flags is not None:
                flags.append("projected")
            return u, C, st.name
        us = stretch_solve(prob, [harmonic.frames], harmonic.u, C, S, report)
        if us is not None and prob.mean_distortion(us) < prob.mean_distortion(u):
            return us, C, st.name
        if flags is not None:
            flags.append("projected")
        return u, C, st.name
    frames = ([start.frames] if start.u is None else []) + [st.frames for st in starts] + tried
    ref = start.u if start.u is not None and np.isfinite(start.D) else harmonic.u
    us = stretch_solve(prob, frames, ref, C, S, report)
    if us is not None:
        if solved:
            us = reset_frames(prob, us, C, S, report)
        return us, C, start.name if start.u is not None else harmonic.name
    raise InfeasibleError(f"island {prob.island.index}: no map found within C = {C:g} and stretch "
                          f"S = {S:g}; raise S or C, or let bd-uv add seams (seams='auto')",
                          prob.island.index)


def reset_frames(prob, u, C, S, report):
    """Frame resets (eq. 4.21) after a certified stretch solve, while the energy drops by more
    than IMPROVEMENT (at most MAX_RESETS), as BD-Dirichlet does without S: the last solve's
    frames are only the start's. Returns the map of lowest energy within C and S."""
    e = prob.energy_of(u, frames_from_map(prob.alpha(u)))
    for i in range(MAX_RESETS):
        report(0.8, f"resetting frames ({i + 1})")
        un = stretch_solve(prob, [frames_from_map(prob.alpha(u))], u, C, S, report)
        if un is None:
            break
        en = prob.energy_of(un, frames_from_map(prob.alpha(un)))
        if en < e:
            u, improved = un, e - en > IMPROVEMENT * abs(e)
            e = en
            if not improved:
                break
        else:
            break
    return u


def minimise_stretch(prob, start, S, budget, flags, report, t0):
    """``bound="auto"`` with a stretch bound: the smallest C (bisection, Algorithm 1's outer loop)
    for which a map with singular values in [1/S, S] (section 6.3) is found.

    The first map is ``bounded_stretch`` at C = S^2 (the largest distortion singular values in
    [1/S, S] allow); then ``stretch_solve`` at C between 1 and the best certified distortion,
    frames from the best map, until the interval is within AUTO_TOLERANCE, AUTO_MAX_SOLVES solves
    or the time budget. Returns (u, its max distortion, name of the start)."""
    u, _, name = bounded_stretch(prob, start, S * S, S, report, flags)
    best, hi, lo = u, prob.distortion(u), 1.0
    while prob.solves < AUTO_MAX_SOLVES and hi - lo > AUTO_TOLERANCE * (hi - 1.0) + AUTO_FLOOR:
        if prob.solves and budget is not None and time.perf_counter() - t0 > budget:
            flags.append("time_budget_exhausted")
            break
        C = 0.5 * (lo + hi) if lo > 1.0 else 1.0 + (hi - 1.0) * (1.0 - DESCENT)
        report(0.1 + 0.8 * prob.solves / AUTO_MAX_SOLVES,
               f"minimising C with stretch {S:.3g}: {lo:.3g} < C* <= {hi:.4g}")
        un = stretch_solve(prob, [frames_from_map(prob.alpha(best))], best, C, S, report)
        D = prob.distortion(un) if un is not None else np.inf
        if un is not None and D < hi:
            best, hi = un, D
        else:
            lo = C
    return best, hi, name
