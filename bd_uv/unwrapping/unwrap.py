"""Certified bounded-distortion unwrapping of a whole mesh, island by island.

Per island (Lipman 2012, sections 4 and 6; issue 9's "never worse than its start"):
1. a start map (``initial.start_map``): the free-boundary conformal map when it has no flipped
   face, else a flip-free map;
2. a start within the bound is returned as it is; otherwise it is bent only where the bound demands
   (``strategies.bounded``), or C is minimised (``strategies.minimise``);
3. every result is certified from its final UVs: no flipped face and max distortion <= C.
"""
import math
import time

import numpy as np

from ..errors import BDError, CancelledError, InvalidMeshError, IslandError, SolverError
from ..mesh import check_arrays, islands as split_islands
from ..metrics import certify, mean_distortion
from . import strategies
from .batched import conformal_islands
from .initial import start_map
from .problem import STORE_HEADROOM, Cancelled, IslandProblem
from .results import IslandResult, UnwrapResult

METHODS = ("lscm", "arap", "dirichlet")
FRAMES = ("auto", "harmonic", "conformal", "input-uv", "constant")
HIGH_DISTORTION = 50.0  # certified bounds above this get a "high_distortion" flag and a hint


def unwrap(V, F, seams=None, pin_corners=None, pin_uv=None, method="lscm", bound=5.0,
           frames="auto", initial_uv=None, raise_bound=True, bound_limit=1000.0, cone="soc",
           time_budget=None, progress=None, cancel=None):
    """Map a triangle mesh to the plane with no flipped face and conformal distortion <= C.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array
    seams : (s,2) int array, optional, vertex pairs of the edges to cut along
    pin_corners : (p,) int array, optional, flat corner indices (face * 3 + corner)
    pin_uv : (p,2) float array, optional, the UV of each pinned corner (kept exactly)
    method : "lscm" | "arap" | "dirichlet"
    bound : float >= 1 or "auto"
    frames : "auto" | "harmonic" | "conformal" | "input-uv" | "constant"
    initial_uv : (m,3,2) float array, optional, per-corner UVs (needed for frames="input-uv":
        they are the start map, returned as they are when within the bound)
    raise_bound : bool, raise C when infeasible (up to ``bound_limit``)
    bound_limit : float
    cone : "soc" (F_C, eq. 4.15) or "linf" (F_C^inf, eq. 4.22)
    time_budget : float seconds per island for ``bound="auto"``, optional
    progress : callable(fraction, message), optional
    cancel : object with ``is_set()``, optional

    Returns
    -------
    UnwrapResult

    Raises
    ------
    InvalidMeshError for a mesh that cannot be read, ValueError for bad options,
    CancelledError when cancelled.
    """
    t0 = time.perf_counter()
    _check_options(method, frames, bound, bound_limit, cone)
    V, F = check_arrays(V, F)
    m = len(F)
    if frames == "input-uv":
        if initial_uv is None:
            raise ValueError("frames='input-uv' needs initial_uv (m,3,2)")
        initial_uv = np.asarray(initial_uv, dtype=np.float64).reshape(m, 3, 2)
    pins = _pins(pin_corners, pin_uv, m)
    isl = split_islands(V, F, seams)
    total = float(m)
    done = 0.0
    results = []
    corner_uv = np.full((m, 3, 2), np.nan)
    face_island = np.empty(m, dtype=np.int64)
    for island in isl:
        face_island[island.faces] = island.index
    batch, starts = _batched(V, isl, pins, face_island, method, bound, frames, progress, cancel)
    for island in isl:
        share = len(island.faces) / total

        def report(frac, msg, _done=done, _share=share, _i=island.index):
            if progress is not None:
                progress(min(1.0, _done + _share * frac), f"island {_i + 1}/{len(isl)}: {msg}")
            if cancel is not None and cancel.is_set():
                raise Cancelled
        try:
            if cancel is not None and cancel.is_set():
                raise Cancelled
            if island.index in batch:
                res = batch[island.index]
                report(1.0, "the conformal map fits the bound")
            else:
                res = _solve_island(island, V, pins, method, bound, frames, initial_uv, raise_bound,
                                    bound_limit, cone, time_budget, report, cancel,
                                    starts.get(island.index))
        except Cancelled:
            raise CancelledError("unwrap cancelled; nothing was changed") from None
        if res.status == "certified":
            corner_uv[island.faces] = res.uv[island.tris]
        results.append(res)
        done += share
    if progress is not None:
        progress(1.0, "done")
    return UnwrapResult(corner_uv, face_island, results, time.perf_counter() - t0, method)


def _check_options(method, frames, bound, bound_limit, cone):
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if frames not in FRAMES:
        raise ValueError(f"frames must be one of {FRAMES}, got {frames!r}")
    if bound != "auto" and not (isinstance(bound, (int, float)) and 1.0 <= bound < np.inf):
        raise ValueError(f"bound must be a finite number >= 1 or 'auto', got {bound!r}")
    if not 1.0 <= bound_limit < np.inf:
        raise ValueError(f"bound_limit must be a finite number >= 1, got {bound_limit!r}")
    if cone not in ("soc", "linf"):
        raise ValueError(f"cone must be 'soc' or 'linf', got {cone!r}")


def _pins(pin_corners, pin_uv, m):
    """Validated pins as (corners (p,), uv (p,2))."""
    if pin_corners is None or len(pin_corners) == 0:
        return np.zeros(0, np.int64), np.zeros((0, 2))
    c = np.asarray(pin_corners, dtype=np.int64).ravel()
    uv = np.asarray(pin_uv, dtype=np.float64).reshape(-1, 2)
    if len(c) != len(uv):
        raise ValueError(f"{len(c)} pinned corners but {len(uv)} pin UVs")
    if np.any((c < 0) | (c >= 3 * m)):
        raise InvalidMeshError("pinned corner indices must lie in 0..3m-1 (face * 3 + corner)")
    if not np.all(np.isfinite(uv)):
        raise InvalidMeshError("pinned UVs must be finite numbers")
    return c, uv


def _failed(island, error, t0, bound, frames_name="", flags=(), timings=None):
    return IslandResult(island.index, island.faces, island.vertices, island.tris, status="failed",
                        error=error, message=str(error), bound_requested=bound,
                        frames=frames_name, seconds=time.perf_counter() - t0, flags=tuple(flags),
                        timings=timings or {})


def _batched(V, isl, pins, face_island, method, bound, frames, progress, cancel):
    """Solve every island that can go through ``batched.conformal_islands`` at once: valid,
    unpinned, BD-LSCM at a fixed bound from the conformal start. Returns (results by island index,
    conformal starts of the islands that did not fit)."""
    if method != "lscm" or bound == "auto" or frames not in ("auto", "conformal"):
        return {}, {}
    pinned = np.zeros(len(isl), dtype=bool)
    if len(pins[0]):
        pinned[np.unique(face_island[pins[0] // 3])] = True
    todo = [i for i in isl if i.error is None and not pinned[i.index]]
    if len(todo) < 2:
        return {}, {}
    if progress is not None:
        progress(0.01, f"conformal maps of {len(todo)} islands")
    if cancel is not None and cancel.is_set():
        raise CancelledError("unwrap cancelled; nothing was changed")
    return conformal_islands(V, todo, float(bound))


def _solve_island(island, V, pins, method, bound, frames, initial_uv, raise_bound, bound_limit,
                  cone, time_budget, report, cancel, lscm=None):
    t0 = time.perf_counter()
    if island.error is not None:
        return _failed(island, island.error, t0, bound)
    try:
        prob = IslandProblem(island, V, pins, method, cone, cancel)
        start = start_map(prob, frames, initial_uv, report, lscm=lscm)
    except IslandError as exc:
        exc.island = island.index
        return _failed(island, exc, t0, bound)
    except BDError as exc:
        return _failed(island, SolverError(f"island {island.index}: {exc}", island.index), t0,
                       bound)
    flags = []
    try:
        if bound == "auto":
            u, C, name = strategies.minimise(prob, start, bound_limit, time_budget, flags, report,
                                             t0)
        else:
            u, C, name = strategies.bounded(prob, start, float(bound), raise_bound, bound_limit,
                                            flags, report)
        if method == "arap" and u is not None:
            u = strategies.arap(prob, u, C, report)
    except IslandError as exc:
        return _failed(island, exc, t0, bound, start.name, flags, prob.timings)
    return _finish(prob, u, C, bound, name, flags, t0)


def certified_bound(max_distortion):
    """The bound ``bound="auto"`` reports for a map: its max distortion with STORE_HEADROOM,
    rounded up to 4 significant digits, so the UVs still pass as stored (float32, packed)."""
    c = max_distortion * (1.0 + STORE_HEADROOM)
    digits = 3 - int(math.floor(math.log10(c)))
    return math.ceil(c * 10 ** digits) / 10 ** digits


def _finish(prob, u, C, bound, frames_name, flags, t0):
    """Scale and place the island, certify it from its final UVs in the input geometry."""
    isl = prob.island
    npins = len(prob.pin_idx)
    if npins < 2:
        s = np.sqrt(prob.area3d / strategies.uv_area(u, isl.tris))
        if npins == 1:
            p = prob.pin_val[0]
            u = p + s * (u - p)
            u[prob.pin_idx[0]] = p
        else:
            u = s * u
            u = u - (u.real.min() + 1j * u.imag.min())
    uv = np.stack([u.real, u.imag], axis=1)
    if npins:
        uv[prob.pin_idx] = np.stack([prob.pin_val.real, prob.pin_val.imag], axis=1)
    t = time.perf_counter()
    target = C if bound != "auto" else certified_bound(C)
    ok, D, n_flipped = certify(prob.V, isl.tris, uv[isl.tris], target)
    prob.timings["certify"] += time.perf_counter() - t
    maxD = float(np.max(D))
    meanD = mean_distortion(prob.V, isl.tris, D)
    seconds = time.perf_counter() - t0
    common = dict(bound_requested=bound, max_distortion=maxD, mean_distortion=meanD,
                  flipped=n_flipped, frames=frames_name, seconds=seconds, solves=prob.solves,
                  iterations=prob.iterations, distortion=D, flags=tuple(flags),
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
