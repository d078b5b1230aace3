"""An island's map made final: scaled and placed, then certified from its final UVs in the input
geometry (no flipped face, max conformal distortion <= C; the stretch limits of section 6.3 when
asked for), whatever strategy found it (``island_solve.solve_island``, ``fixed_boundary``)."""
import math
import time

import numpy as np

from ..errors import SolverError
from ..metrics import certify_measured, mean_distortion
from .bounded import uv_area
from .margins import certified_bound
from .results import IslandResult

HIGH_DISTORTION = 50.0  # certified bounds above this get a "high_distortion" flag and a hint


def area_scale(u, tris, area3d):
    """The factor making the map u (nv,) complex's UV area the island's 3D area ``area3d``; 1
    for a map collapsed to a point or a line (e.g. pinned ~1e159 away, where float64 cannot hold
    the island's shape): it has no area to scale by, is left unscaled, and its certificate
    fails."""
    area = uv_area(u, tris)
    return math.sqrt(area3d / area) if area > 0.0 and math.isfinite(area) else 1.0


def placed(u, tris, area3d):
    """A map of no pin placed as the unwrap places it: UV area = 3D area (``area_scale``),
    bounding box at (0, 0)."""
    u = area_scale(u, tris, area3d) * u
    return u - (np.minimum.reduce(u.real) + 1j * np.minimum.reduce(u.imag))


def finish(prob, u, C, bound, frames_name, flags, t0, stretch=None):
    """Scale and place the island, certify it from its final UVs in the input geometry."""
    isl = prob.island
    npins = len(prob.pin_idx)
    if npins == 1:
        s = area_scale(u, isl.tris, prob.area3d)
        p = prob.pin_val[0]
        u = p + s * (u - p)
        u[prob.pin_idx[0]] = p
    elif npins == 0:
        u = placed(u, isl.tris, prob.area3d)
    uv = np.stack([u.real, u.imag], axis=1)
    if npins:
        uv[prob.pin_idx] = np.stack([prob.pin_val.real, prob.pin_val.imag], axis=1)
    t = time.perf_counter()
    target = C if bound != "auto" else certified_bound(C)
    ok, D, n_flipped, smax, smin = certify_measured(prob.V, isl.tris, uv[isl.tris], target,
                                                    normalize=npins < 2, faces=prob.faces_3d)
    lo_s, hi_s = float(np.min(smin)), float(np.max(smax))
    # section 6.3: 1/S <= gamma <= Gamma <= S, certified from the UVs
    within_stretch = stretch is None or (lo_s >= (1.0 - 1e-6) / stretch
                                         and hi_s <= stretch * (1.0 + 1e-6))
    ok = ok and within_stretch
    prob.timings["certify"] += time.perf_counter() - t
    maxD = float(np.max(D))
    if not ok and bound == "auto" and n_flipped == 0 and np.isfinite(maxD) and within_stretch:
        # the map measured from its UVs over the problem's own max: faces shrunk to the float64
        # step of the map's extent (a long strip's conformal map: cow-strip1500z's faces of
        # 1e-15 of it, 9.263 in the problem, 12.44 stored) are measured in rounding. ``auto``
        # certifies the least C its stored UVs pass, not nothing (C = 10 certified this disk)
        target = certified_bound(maxD)
        ok = bool(np.all(D <= target))
        flags = list(flags) + ["bound_measured"]
    meanD = mean_distortion(prob.V, isl.tris, D,
                            None if prob.faces_3d is None else prob.faces_3d[1])
    seconds = time.perf_counter() - t0
    common = dict(bound_requested=bound, max_distortion=maxD, mean_distortion=meanD,
                  flipped=n_flipped, frames=frames_name, seconds=seconds, solves=prob.solves,
                  iterations=prob.iterations, distortion=D, flags=tuple(flags),
                  min_singular=lo_s, max_singular=hi_s,
                  timings=dict(prob.timings))
    if not ok:
        err = SolverError(f"island {isl.index}: the result could not be certified (max distortion "
                          f"{maxD:.4g}, {n_flipped} flipped, bound {target:.4g}); nothing was "
                          "written", isl.index)
        return IslandResult(isl.index, isl.faces, isl.vertices, isl.tris, status="failed",
                            error=err, message=str(err), **common)
    certified_C = certified_bound(maxD) if bound == "auto" else C
    msg = (f"island {isl.index}: {len(isl.faces)} faces, max distortion {maxD:.3f} <= "
           f"{certified_C:.4g}, 0 flipped")
    if "bound_raised" in flags:
        msg += f" (C raised from {bound:g})"
    if certified_C > HIGH_DISTORTION:
        common["flags"] = tuple(flags) + ("high_distortion",)
        msg += (f"; C above {HIGH_DISTORTION:g} means the island is nearly closed or badly cut: "
                "mark seams for a lower bound")
    return IslandResult(isl.index, isl.faces, isl.vertices, isl.tris, uv=uv, status="certified",
                        message=msg, bound_certified=float(certified_C), **common)
