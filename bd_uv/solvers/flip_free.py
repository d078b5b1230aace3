"""A flip-free initial map close to conformal, for islands whose LSCM map flips.

The harmonic (Tutte) start is flip-free by construction but far from conformal: on meshes with long
protrusions its mean distortion is 1.3-1.5x the LSCM map's. Projection iterations (Kovalsky et al.
2015, see ``projection``) started from the LSCM map itself, flips and all, move only the faces that
break the bound and their neighbourhood, and keep the LSCM map's mean elsewhere. When they stall,
the harmonic map is the start instead.
"""
import time

import numpy as np

from ..energies import jacobian_operators
from ..frames import harmonic_map
from .projection import ProjectionSolver

__all__ = ["flip_free_map"]

# The LSCM start is given up when none of its projection's first WINDOW iterates is flip-free
# (then the harmonic start, projected where ``harmonic``, else None). Where the bend
# works the LSCM start's iterates are flip-free within 1-5 iterations and within C in 3-10
# (three_peaks.off, mannequin-devil.off and its 700-face patch, DamagedHelmet's 1,506-face
# piece), within 1-8 on 8 ring patches of three_peaks.off and cow.off (one flip-free at 16
# failed all the same: 10 would be too tight); on igl decimated-knight's 976-face strip (a
# 6-edge hole) the LSCM start still flipped
# after 109 iterations and no iterate of the harmonic one's 114 bettered its own max (44.5):
# 223 iterations, 140 ms of CPU, for nothing.
WINDOW = 20
# ... and after its first iterate where the LSCM map flips FLIP_LEAST faces or more and that
# iterate flips more than FLIP_RISE times as many. Of 20 LSCM starts flipping 3 or more (issue
# 21's disks, unseen16, auto15, start16's cow patches; ring patches of three_peaks, cow, dino,
# camel, mannequin-devil, ChineseDragon, horse, lion-head, fandisk, holes, nefertiti and
# armadillo at auto and C = 5), the 7 that bend flip fewer or as many at the first iterate
# (30 -> 13, 19 -> 3, 3 -> 3, 5 -> 3, ...); of the 13 that do not, 12 flip 2.1-80 times as
# many (decimated-knight's strip 4 -> 293, cow.off patches 3 -> 10, 33 -> 68, dino's 4 -> 321,
# camel's 49 -> 181: their window given up for nothing, knight ~17 ms of CPU of auto's ~45;
# a three_peaks patch, 16 -> 5, still runs the window). Fewer than 3 flips says little: cow.off's 1578/400 patch bends from 1 to
# 13 flips to none in 67 iterations
FLIP_RISE = 1.5
FLIP_LEAST = 3


def flip_free_map(Z, tris, nv, loops, u_lscm, C=5.0, *, pins=None, margin=0.9, max_iter=300,
                  solver=None, cancel=None, harmonic=True, ops=None):
    """Flip-free map within conformal distortion ``C``, near the LSCM map.

    Parameters
    ----------
    Z : (k,3) complex, local corner coordinates (``geometry.local_coordinates``)
    tris : (k,3) int
    nv : int
    loops : sequence of (b,) int arrays, boundary loops, longest first
    u_lscm : (nv,) complex, the LSCM map (``frames.lscm_map``), possibly with flipped faces
    C : float > 1, the distortion bound the map must meet (Lipman 2012, eq. 4.9)
    pins : tuple (idx (p,) int, uv (p,) complex), optional; held exactly. Without pins the first
        vertex of the outer loop is held where the LSCM map puts it (translation only).
    margin : float, the projection aims at ``margin * C`` (see ``ProjectionSolver.project``)
    max_iter : int, iterations per start
    solver : ProjectionSolver, optional, reused when given (built over the same ``fixed`` set)
    cancel : object with ``is_set()``; ``CancelledError`` when set
    harmonic : bool, project the harmonic map where the LSCM start fails (False: None then,
        the caller has a better use for the harmonic map: ``bound="auto"`` searches from it)
    ops : energies.JacobianOperators of (Z, tris, nv), optional: the island problem's, not
        made again (~0.7 ms of a 1k-face island)

    Returns
    -------
    u : (nv,) complex128 or None when neither start reached the bound
    info : dict with "start" ("lscm" | "harmonic" | None), "iterations" (total), "seconds",
        "factor_seconds", "max_distortion" (of u, or of the last attempt)
    """
    t0 = time.perf_counter()
    if pins is not None and len(pins[0]):
        fixed, values = np.asarray(pins[0], np.int64), np.asarray(pins[1], np.complex128)
        order = np.argsort(fixed)
        fixed, values = fixed[order], values[order]
    else:
        fixed = np.array([loops[0][0]], dtype=np.int64)
        values = np.asarray(u_lscm, np.complex128)[fixed]
    if solver is None:
        solver = ProjectionSolver(jacobian_operators(Z, tris, nv) if ops is None else ops, nv,
                                  fixed, tris=tris)
    info = {"start": None, "iterations": 0, "seconds": 0.0,
            "factor_seconds": 0.0, "max_distortion": np.inf}
    scale = solver.component_scale(np.asarray(u_lscm, np.complex128))

    # the LSCM start's first WINDOW iterations; run again in full (the same iterates as one run)
    # where one of them was flip-free but they did not converge
    res = solver.project(u_lscm, C, values, margin=margin, scale=scale,
                         max_iter=min(WINDOW, max_iter), cancel=cancel, flip_rise=(FLIP_RISE, FLIP_LEAST))
    info["iterations"] += res.iterations
    if (not res.all_converged and res.iterations >= WINDOW and max_iter > WINDOW
            and np.isfinite(np.max(res.max_distortion))):
        res = solver.project(u_lscm, C, values, margin=margin, scale=scale, max_iter=max_iter,
                             cancel=cancel)
        info["iterations"] += res.iterations
    info["max_distortion"] = float(np.max(res.max_distortion))
    info["factor_seconds"] = solver.factor_seconds
    if res.all_converged:
        info.update(start="lscm", seconds=time.perf_counter() - t0)
        return res.u, info
    if not harmonic:
        info["seconds"] = time.perf_counter() - t0
        return None, info
    # Fallback: the harmonic map, moved to the LSCM map's scale and anchor.
    uh = harmonic_map(Z, tris, nv, loops)
    sh = solver.component_scale(uh)
    uh = (uh - uh[fixed[0]]) * (scale[0] / sh[0]) + values[0]
    res = solver.project(uh, C, values, margin=margin, scale=scale, max_iter=max_iter,
                         cancel=cancel)
    info["iterations"] += res.iterations
    info["max_distortion"] = float(np.max(res.max_distortion))
    info["seconds"] = time.perf_counter() - t0
    info["factor_seconds"] = solver.factor_seconds
    if res.all_converged:
        info["start"] = "harmonic"
        return res.u, info
    return None, info
