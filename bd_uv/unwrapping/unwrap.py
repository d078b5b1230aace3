"""Certified bounded-distortion unwrapping of a whole mesh, island by island.

Per island (Lipman 2012, sections 4 and 6; issue 9's "never worse than its start"):
1. a start map (``initial.start_map``): the free-boundary conformal map when it has no flipped
   face, else a flip-free map;
2. a start within the bound is returned as it is; otherwise it is bent only where the bound demands
   (``strategies.bounded``), or C is minimised (``strategies.minimise``);
3. every result is certified from its final UVs: no flipped face and max distortion <= C.
With ``boundary`` other than "free", steps 1-2 are replaced by a solve with the island's outer
boundary fixed on a circle, a rectangle or its pinned polygon (``fixed_boundary``, section 5),
certified the same way and checked for Theorems 5.1/5.2's premises (``bijective``).
"""
import math
import time

import numpy as np

from ..errors import (BDError, CancelledError, InvalidMeshError, IslandError, OptionError,
                      SolverError)
from ..mesh import check_arrays, islands as split_islands
from ..metrics import certify, mean_distortion, singular_values
from ..spaces import check_stretch
from . import strategies
from . import stretch as stretch_search
from .batched import conformal_islands
from .fixed_boundary import BOUNDARIES, FRAMES_NAME, fixed_boundary_island, with_premises
from .initial import start_map
from .overlap_certificate import overlap_certificate
from .problem import STORE_HEADROOM, Cancelled, IslandProblem
from .results import IslandResult, UnwrapResult

METHODS = ("lscm", "arap", "dirichlet", "biharmonic", "stretch-l1")
FRAMES = ("auto", "harmonic", "conformal", "input-uv", "constant")
HIGH_DISTORTION = 50.0  # certified bounds above this get a "high_distortion" flag and a hint


def unwrap(V, F, seams=None, pin_corners=None, pin_uv=None, method="lscm", bound=5.0,
           frames="auto", initial_uv=None, raise_bound=True, bound_limit=1000.0, cone="soc",
           time_budget=None, overlap="cut", face_groups=None, stretch=None, boundary="free",
           progress=None, cancel=None):
    """Map a triangle mesh to the plane with no flipped face and conformal distortion <= C.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array
    seams : (s,2) int array, optional, vertex pairs of the edges to cut along; or "auto": cut
        every island that cannot be certified as it is into certified disk charts
        (``bd_uv.seams.unwrap_auto``, which also takes existing seams to keep)
    pin_corners : (p,) int array, optional, flat corner indices (face * 3 + corner)
    pin_uv : (p,2) float array, optional, the UV of each pinned corner (kept exactly)
    method : "lscm" | "arap" | "dirichlet" | "biharmonic" | "stretch-l1". BD-Biharmonic (eq. 6.1)
        with boundary="free" is held at two boundary vertices of the start map, and its mean
        distortion is higher than BD-LSCM's: it is meant for a fixed boundary. "stretch-l1" is the
        L1 stretch energy sum_j (|alpha_j| + |beta_j|) Area_j (section 6.1, a second-order cone
        objective); with a free boundary it would shrink the island to a point, so the island's
        scale is held (area-weighted mean of Re(w alpha) = 1 on the unit-area island, one anchor
        vertex; ``IslandProblem.hold_scale``); with two or more pins or a fixed boundary they
        give the scale
    bound : float >= 1 or "auto"
    frames : "auto" | "harmonic" | "conformal" | "input-uv" | "constant"
    initial_uv : (m,3,2) float array, optional, per-corner UVs (needed for frames="input-uv":
        they are the start map, returned as they are when within the bound)
    raise_bound : bool, raise C when infeasible (up to ``bound_limit``)
    bound_limit : float
    cone : "soc" (F_C, eq. 4.15) or "linf" (F_C^inf, eq. 4.22)
    time_budget : float seconds per island for ``bound="auto"``, optional
    overlap : "cut" | "fail", an island whose UVs lie over themselves: cut it into overlap-free
        pieces (islands of their own, ``cut_edges`` naming the mesh edges cut), or fail it with
        ``OverlapError``
    face_groups : (m,) int array, optional, a group per face (the polygon each triangle comes
        from): a cut never separates faces of one group (with seams="auto", no seam is added
        inside a group either)
    stretch : float S >= sqrt(C), optional: every face's singular values within [1/S, S]
        (section 6.3, eqs. 6.3-6.4), certified from the final UVs (``min_singular``,
        ``max_singular``): relative to the island's own scale (UV area = 3D area) with a free
        boundary and fewer than two pins, else relative to the 3D geometry (pins or the fixed
        boundary give the scale). Every method; with bound="auto" the smallest C within S is
        sought (free boundary only). With seams="auto": every chart within S; default 2 there
    boundary : "free" | "circle" | "rectangle" | "pinned", where each island's outer boundary
        goes (Lipman 2012, section 5; ``boundary.boundary_targets``): free (the default), on a
        circle or a rectangle of the island's 3D area (rectangle corners at the four boundary
        vertices nearest a right angle, or at four pinned ones), or on the polygon of its pinned
        boundary vertices (at least 3); holes stay holes (filled for the solve with triangles held
        orientation-preserving: a bijection by Theorem 5.1). Needs a numeric bound; frames come
        from a Tutte embedding ("auto" or "harmonic"). Each such island reports ``bijective``.
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
    if isinstance(seams, str):
        if seams != "auto":
            raise OptionError(f"seams must be vertex pairs or 'auto', got {seams!r}")
        if boundary != "free":
            raise OptionError("seams='auto' makes free-boundary charts; boundary= needs "
                             "boundary='free' there")
        if bound == "auto":
            raise OptionError("seams='auto' needs a numeric bound C")
        if (pin_corners is not None and len(pin_corners)) or frames == "input-uv":
            raise OptionError("seams='auto' does not take pins or the current UVs: call "
                             "bd_uv.seams.unwrap_auto for material groups, or mark seams")
        from ..seams import unwrap_auto  # the seams package builds on this module
        # face_groups (polygons) are kept whole by the seams added too: unwrap_auto's polygons.
        return unwrap_auto(V, F, bound=bound, stretch=2.0 if stretch is None else stretch,
                           method=method, frames=frames, cone=cone, progress=progress,
                           cancel=cancel, polygons=face_groups)[0]
    if boundary not in BOUNDARIES:
        raise OptionError(f"boundary must be one of {BOUNDARIES}, got {boundary!r}")
    if boundary != "free" and bound == "auto":
        raise OptionError(f"boundary={boundary!r} needs a numeric bound C (bound='auto' minimises C "
                         "with a free boundary only)")
    if boundary != "free" and frames not in ("auto", "harmonic"):
        raise OptionError(f"boundary={boundary!r} takes its frames from a Tutte embedding onto the "
                         f"boundary (frames 'auto' or 'harmonic'), got frames={frames!r}")
    if stretch is not None:
        check_stretch(1.0 if bound == "auto" else float(bound), stretch)
    t0 = time.perf_counter()
    _check_options(method, frames, bound, bound_limit, cone)
    if overlap not in ("cut", "fail"):
        raise OptionError(f"overlap must be 'cut' or 'fail', got {overlap!r}")
    V, F = check_arrays(V, F)
    m = len(F)
    if frames == "input-uv":
        if initial_uv is None:
            raise OptionError("frames='input-uv' needs initial_uv (m,3,2)")
        initial_uv = np.asarray(initial_uv, dtype=np.float64).reshape(m, 3, 2)
    pins = _pins(pin_corners, pin_uv, m)
    return unwrap_islands(V, F, split_islands(V, F, seams), pins, method, bound, frames,
                          initial_uv, raise_bound, bound_limit, cone, time_budget, overlap,
                          face_groups, stretch, boundary, progress, cancel, t0=t0)


def unwrap_islands(V, F, isl, pins, method, bound, frames, initial_uv, raise_bound, bound_limit,
                   cone, time_budget, overlap, face_groups, stretch, boundary, progress, cancel,
                   conformal=None, t0=None):
    """``unwrap`` on islands already found (``mesh.islands``, or charts of a validated mesh).

    Parameters
    ----------
    V, F : checked arrays; isl : list of mesh.Island numbered 0.. by their smallest face
    pins : (corners (p,), uv (p,2)) as ``_pins`` returns; the other options as ``unwrap``'s,
        already checked
    conformal : dict island index -> (nv,) complex128, optional: the island's free-boundary
        conformal map as ``batched.conformal_islands`` would solve it (unit-area normalisation,
        ``_far_pairs`` pinned at 0 and 1), already known (the seam search's chart maps); only
        used where the batched path would solve it. Everything is certified from the final UVs
        as ever.

    Returns
    -------
    UnwrapResult
    """
    t0 = time.perf_counter() if t0 is None else t0
    m = len(F)
    total = float(m)
    done = 0.0
    results = []
    corner_uv = np.full((m, 3, 2), np.nan)
    face_island = np.empty(m, dtype=np.int64)
    for island in isl:
        face_island[island.faces] = island.index
    batch, starts = ({}, {}) if boundary != "free" or stretch is not None else \
        _batched(V, isl, pins, face_island, method, bound, frames, progress, cancel, conformal)
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
                                    starts.get(island.index), boundary, stretch)
        except Cancelled:
            raise CancelledError("unwrap cancelled; nothing was changed") from None
        if res.status == "certified":
            corner_uv[island.faces] = res.uv[island.tris]
        results.append(res)
        done += share
    pinned = set(face_island[pins[0] // 3].tolist())
    results, face_island, corner_uv = overlap_certificate(V, F, results, face_island, corner_uv,
                                                           pinned, overlap == "cut", face_groups)
    if progress is not None:
        progress(1.0, "done")
    return UnwrapResult(corner_uv, face_island, results, time.perf_counter() - t0, method)


def _check_options(method, frames, bound, bound_limit, cone):
    if method not in METHODS:
        raise OptionError(f"method must be one of {METHODS}, got {method!r}")
    if frames not in FRAMES:
        raise OptionError(f"frames must be one of {FRAMES}, got {frames!r}")
    if bound != "auto" and not (isinstance(bound, (int, float)) and 1.0 <= bound < np.inf):
        raise OptionError(f"bound must be a finite number >= 1 or 'auto', got {bound!r}")
    if not 1.0 <= bound_limit < np.inf:
        raise OptionError(f"bound_limit must be a finite number >= 1, got {bound_limit!r}")
    if cone not in ("soc", "linf"):
        raise OptionError(f"cone must be 'soc' or 'linf', got {cone!r}")


def _pins(pin_corners, pin_uv, m):
    """Validated pins as (corners (p,), uv (p,2))."""
    if pin_corners is None or len(pin_corners) == 0:
        return np.zeros(0, np.int64), np.zeros((0, 2))
    c = np.asarray(pin_corners, dtype=np.int64).ravel()
    uv = np.asarray(pin_uv, dtype=np.float64).reshape(-1, 2)
    if len(c) != len(uv):
        raise OptionError(f"{len(c)} pinned corners but {len(uv)} pin UVs")
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


def _batched(V, isl, pins, face_island, method, bound, frames, progress, cancel, conformal=None):
    """Solve every island that can go through ``batched.conformal_islands`` at once: valid,
    unpinned, BD-LSCM at a fixed bound from the conformal start. Returns (results by island index,
    conformal starts of the islands that did not fit)."""
    if method != "lscm" or bound == "auto" or frames not in ("auto", "conformal"):
        return {}, {}
    pinned = np.zeros(len(isl), dtype=bool)
    if len(pins[0]):
        pinned[np.unique(face_island[pins[0] // 3])] = True
    todo = [i for i in isl if i.error is None and not pinned[i.index]]
    known = conformal is not None and len(todo) > 0 and all(i.index in conformal for i in todo)
    if len(todo) < 2 and not known:
        return {}, {}
    if progress is not None:
        progress(0.01, f"conformal maps of {len(todo)} islands")
    if cancel is not None and cancel.is_set():
        raise CancelledError("unwrap cancelled; nothing was changed")
    return conformal_islands(V, todo, float(bound), conformal)


def _solve_island(island, V, pins, method, bound, frames, initial_uv, raise_bound, bound_limit,
                  cone, time_budget, report, cancel, lscm=None, boundary="free", stretch=None):
    t0 = time.perf_counter()
    if island.error is not None:
        res = _failed(island, island.error, t0, bound)
        return res if boundary == "free" else with_premises(res, island)
    if boundary != "free":
        try:
            prob, u, C, flags = fixed_boundary_island(island, V, pins, boundary, method, bound,
                                                      raise_bound, bound_limit, cone, cancel,
                                                      report, stretch)
        except IslandError as exc:
            exc.island = island.index
            return with_premises(_failed(island, exc, t0, bound, FRAMES_NAME), island)
        except BDError as exc:
            err = SolverError(f"island {island.index}: {exc}", island.index)
            return with_premises(_failed(island, err, t0, bound, FRAMES_NAME), island)
        return with_premises(_finish(prob, u, C, bound, FRAMES_NAME, flags, t0, stretch), island)
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
        if bound == "auto" and stretch is not None:
            u, C, name = stretch_search.minimise_stretch(prob, start, stretch, time_budget,
                                                         flags, report, t0)
        elif bound == "auto":
            u, C, name = strategies.minimise(prob, start, bound_limit, time_budget, flags, report,
                                             t0)
        elif stretch is not None:
            u, C, name = stretch_search.bounded_stretch(prob, start, float(bound), stretch,
                                                        report, flags)
        else:
            u, C, name = strategies.bounded(prob, start, float(bound), raise_bound, bound_limit,
                                            flags, report)
        if method == "arap" and u is not None:
            u = strategies.arap(prob, u, C, report, stretch)
    except IslandError as exc:
        return _failed(island, exc, t0, bound, start.name, flags, prob.timings)
    return _finish(prob, u, C, bound, name, flags, t0, stretch)


def certified_bound(max_distortion):
    """The bound ``bound="auto"`` reports for a map: its max distortion with STORE_HEADROOM,
    with C - 1 rounded up to 4 significant digits (1.03633 for 1.036117, 3.858 for 3.8563), so the
    UVs still pass as stored (float32, packed) and a C close to 1 keeps the precision it was
    minimised to (the search's tolerance is relative to C - 1 too)."""
    c = max_distortion * (1.0 + STORE_HEADROOM)
    excess = c - 1.0
    if not excess > 0.0:
        return c
    digits = 3 - int(math.floor(math.log10(excess)))
    return 1.0 + math.ceil(excess * 10 ** digits) / 10 ** digits


def _finish(prob, u, C, bound, frames_name, flags, t0, stretch=None):
    """Scale and place the island, certify it from its final UVs in the input geometry."""
    isl = prob.island
    npins = len(prob.pin_idx)
    if npins < 2:
        # A map collapsed to a point or a line (e.g. pinned ~1e159 away, where float64 cannot
        # hold the island's shape) has no area to scale by: left unscaled, its certificate fails.
        area = strategies.uv_area(u, isl.tris)
        s = math.sqrt(prob.area3d / area) if area > 0.0 and math.isfinite(area) else 1.0
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
    smax, smin = singular_values(prob.V, isl.tris, uv[isl.tris], normalize=npins < 2)
    lo_s, hi_s = float(np.min(smin)), float(np.max(smax))
    if stretch is not None:  # section 6.3: 1/S <= gamma <= Gamma <= S, certified from the UVs
        ok = ok and lo_s >= (1.0 - 1e-6) / stretch and hi_s <= stretch * (1.0 + 1e-6)
    prob.timings["certify"] += time.perf_counter() - t
    maxD = float(np.max(D))
    meanD = mean_distortion(prob.V, isl.tris, D)
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
