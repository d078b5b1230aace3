"""Certified bounded-distortion unwrapping of a whole mesh, island by island.

Per island (Lipman 2012, sections 4 and 6):
1. an initial map and its frames (eq. 4.21): the free-boundary conformal map (LSCM) when it has no
   flipped face, else the flip-free harmonic embedding onto a disk;
2. minimise the energy over F_C with those frames; reset the frames from the solution (eq. 4.21)
   and solve again while the energy improves by more than 1 %;
3. when a solve is infeasible or not certified: reset the frames from the solver's last iterate and
   retry, then raise C by a factor up to the limit. A flip-free initial map with maximal distortion
   D0 lies in the space built from its own frames for every C >= D0, so C never has to rise past D0;
4. ``bound="auto"``: Algorithm 1, bisection on C with frame updates, under a time budget;
5. every result is certified from its final UVs: no flipped face and max distortion <= C.
"""
import time
from dataclasses import dataclass, field

import numpy as np

from .energies import energy, jacobian_operators
from .errors import (BDError, CancelledError, InfeasibleError, InvalidMeshError, IslandError,
                     SolverError)
from .frames import frames_from_map, harmonic_map, lscm_map, planar_map
from .geometry import face_areas, local_coordinates
from .mesh import check_arrays, islands as split_islands
from .metrics import certify, face_jacobians, mean_distortion
from .solvers import conic
from .spaces import bounded_distortion_space

METHODS = ("lscm", "arap", "dirichlet")
FRAMES = ("auto", "harmonic", "conformal", "input-uv", "constant")
SOLVE_MARGIN = 2e-3     # solve at a C slightly below the bound so certification has headroom
RAISE_FACTOR = 1.5      # C grows by this factor when infeasible
MAX_RESETS = 3          # frame resets after the first feasible solve
IMPROVEMENT = 0.01      # keep resetting frames while the energy drops by more than this fraction
# Reset frames only when a solution turns faces away from their frames by more than this (radians,
# 99th percentile, after removing the common rotation): below it the next space is nearly the same
# and the re-solve changed the energy by < 0.5 % on nefertiti, hemisphere, mushroom and lion-head.
FRAME_TOLERANCE = 0.1
HIGH_DISTORTION = 50.0  # certified bounds above this get a "high_distortion" flag and a hint
AUTO_TOLERANCE = 0.01   # bisection stops when C_right - C_left <= this * C_right
AUTO_MAX_SOLVES = 24


@dataclass(frozen=True)
class IslandResult:
    """The outcome for one island; see docs/ARCHITECTURE.md for every field."""
    index: int
    faces: np.ndarray
    vertices: np.ndarray
    tris: np.ndarray
    uv: np.ndarray = None
    status: str = "failed"
    error: BDError = None
    message: str = ""
    bound_requested: object = None
    bound_certified: float = None
    max_distortion: float = float("nan")
    mean_distortion: float = float("nan")
    flipped: int = 0
    frames: str = ""
    energy: float = float("nan")
    seconds: float = 0.0
    solves: int = 0
    iterations: int = 0
    distortion: np.ndarray = None
    flags: tuple = ()
    timings: dict = field(default_factory=dict)

    def summary(self):
        """The island's entry in the JSON report."""
        def num(v):
            return None if v is None or not np.isfinite(v) else float(v)
        return {"island": self.index, "faces": int(len(self.faces)),
                "bound_requested": self.bound_requested,
                "bound_certified": num(self.bound_certified),
                "max_distortion": num(self.max_distortion),
                "mean_distortion": num(self.mean_distortion), "flipped": int(self.flipped),
                "frames": self.frames, "seconds": round(self.seconds, 4), "status": self.status,
                "solves": self.solves, "iterations": self.iterations, "flags": list(self.flags),
                "error": type(self.error).__name__ if self.error else None,
                "message": self.message,
                "timings": {k: round(v, 4) for k, v in self.timings.items()}}


@dataclass(frozen=True)
class UnwrapResult:
    """UVs of a whole mesh; ``corner_uv`` is NaN on faces of failed islands."""
    corner_uv: np.ndarray
    face_island: np.ndarray
    islands: list
    seconds: float
    method: str

    @property
    def certified(self):
        return all(r.status == "certified" for r in self.islands)

    def vertex_uv(self):
        """UVs as one table per island vertex, for OBJ output.

        Returns
        -------
        uv : (K,2) float64, the certified islands' vertices in island order
        F_uv : (m,3) int64, index into uv of each face corner; -1 on faces of failed islands
        """
        uvs, F_uv, offset = [], np.full((len(self.face_island), 3), -1, dtype=np.int64), 0
        for r in self.islands:
            if r.status == "certified":
                uvs.append(r.uv)
                F_uv[r.faces] = r.tris + offset
                offset += len(r.uv)
        return (np.concatenate(uvs) if uvs else np.zeros((0, 2))), F_uv

    def report(self):
        """JSON-ready report: method, seconds and one entry per island."""
        return {"method": self.method, "seconds": round(self.seconds, 4),
                "islands": [r.summary() for r in self.islands]}


class _Cancelled(Exception):
    pass


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
    initial_uv : (m,3,2) float array, optional, per-corner UVs (needed for frames="input-uv")
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
        share = len(island.faces) / total

        def report(frac, msg, _done=done, _share=share, _i=island.index):
            if progress is not None:
                progress(min(1.0, _done + _share * frac), f"island {_i + 1}/{len(isl)}: {msg}")
        try:
            res = _solve_island(island, V, pins, method, bound, frames, initial_uv, raise_bound,
                                bound_limit, cone, time_budget, report, cancel)
        except _Cancelled:
            raise CancelledError("unwrap cancelled; nothing was changed") from None
        if res.status == "certified":
            corner_uv[island.faces] = res.uv[island.tris]
        results.append(res)
        done += share
    if progress is not None:
        progress(1.0, "done")
    return UnwrapResult(corner_uv, face_island, results, time.perf_counter() - t0, method)


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


class _Problem:
    """One island's normalised geometry, operators and pins; solves F_C for given frames."""

    def __init__(self, island, V, pins, method, cone, cancel):
        self.island = island
        self.method, self.cone, self.cancel = method, cone, cancel
        Vi = V[island.vertices]
        self.V = Vi
        self.area3d = float(face_areas(Vi, island.tris).sum())
        # Normalise: centre and unit total area (huge or tiny coordinates solve alike).
        self.Vn = (Vi - Vi.mean(axis=0)) / np.sqrt(self.area3d)
        self.nv = nv = len(Vi)
        self.Z = local_coordinates(self.Vn, island.tris)
        self.ops = jacobian_operators(self.Z, island.tris, nv)
        self.pin_idx, self.pin_val = self._island_pins(pins)
        anchor_idx = self.pin_idx if len(self.pin_idx) else np.array([0])
        anchor_val = self.pin_val if len(self.pin_idx) else np.array([0j])
        self.fixed = np.concatenate([anchor_idx, anchor_idx + nv])
        self.xfix = np.concatenate([anchor_val.real, anchor_val.imag])
        self.free = np.setdiff1d(np.arange(2 * nv), self.fixed)
        self.sigma = 1.0
        self.scale = 1.0
        self.solves = 0
        self.iterations = 0
        self.outcomes = []
        self.last_status = None
        self.timings = {"setup": 0.0, "solve": 0.0, "certify": 0.0}

    def _island_pins(self, pins):
        corners, uv = pins
        isl = self.island
        if not len(corners):
            return np.zeros(0, np.int64), np.zeros(0, np.complex128)
        face, k = corners // 3, corners % 3
        pos = np.full(isl.faces.max() + 1, -1, dtype=np.int64)
        pos[isl.faces] = np.arange(len(isl.faces))
        inside = face <= isl.faces.max()
        inside[inside] = pos[face[inside]] >= 0
        if not inside.any():
            return np.zeros(0, np.int64), np.zeros(0, np.complex128)
        vid = isl.tris[pos[face[inside]], k[inside]]
        val = uv[inside, 0] + 1j * uv[inside, 1]
        ids, first = np.unique(vid, return_index=True)
        clash = np.abs(val - val[first][np.searchsorted(ids, vid)]) > 0
        if clash.any():
            raise InfeasibleError(f"island {isl.index}: corners of one vertex are pinned to "
                                  "different UVs; unpin one of them or mark a seam there",
                                  isl.index)
        return ids, val[first]

    def alpha(self, u):
        x = np.concatenate([u.real, u.imag])
        return self.ops.Are @ x + 1j * (self.ops.Aim @ x)

    def beta(self, u):
        x = np.concatenate([u.real, u.imag])
        return self.ops.Bre @ x + 1j * (self.ops.Bim @ x)

    def frame_turn(self, u, w):
        """How far a map turns faces away from frames w, beyond their common rotation (radians,
        99th percentile)."""
        wa = w * self.alpha(u)
        common = np.sum(self.ops.area * wa / np.maximum(np.abs(wa), 1e-300))
        turn = np.abs(np.angle(wa * np.conj(common)))
        return float(np.percentile(turn, 99))

    def distortion(self, u):
        """Max distortion of a map (inf when any face flips)."""
        a, b = np.abs(self.alpha(u)), np.abs(self.beta(u))
        if not np.all(a > b):
            return np.inf
        return float(np.max((a + b) / (a - b)))

    def set_scale(self, u0, w0):
        """sigma (eq. 4.17) and the objective scaling, from the initial map."""
        ra = np.real(w0 * self.alpha(u0))
        if len(self.pin_idx) >= 2:
            typical = np.median(np.abs(self.alpha(u0)))
            self.sigma = 1e-3 * typical if typical > 0 else 1e-8
            us = u0
        else:
            self.sigma = 1.0
            lo = ra.min()
            us = u0 / lo if lo > 0 else u0
        P, q, const = energy(self.method, self.ops, w0)
        x = np.concatenate([us.real, us.imag])
        e0 = 0.5 * x @ (P @ x) + q @ x + const
        self.scale = 1.0 / max(abs(e0), 1e-6)

    def solver_failure(self):
        """A SolverError when no solve ever gave an answer (no certificate either way)."""
        if self.outcomes and not ({"solved", "infeasible"} & set(self.outcomes)):
            return SolverError(f"island {self.island.index}: the solver failed on every attempt "
                               f"(last status: {self.last_status}); try other frames or the "
                               "L-infinity space, or report the mesh", self.island.index)
        return None

    def solve(self, w, C):
        """Minimise the energy over F_C with frames w. Returns (u or None, outcome)."""
        if self.cancel is not None and self.cancel.is_set():
            raise _Cancelled
        t = time.perf_counter()
        nv = self.nv
        if len(self.free) == 0:
            x = np.zeros(2 * nv)
            x[self.fixed] = self.xfix
            return x[:nv] + 1j * x[nv:], "solved"
        Csolve = 1.0 + (C - 1.0) * (1.0 - SOLVE_MARGIN)
        P, q, _ = energy(self.method, self.ops, w)
        P, q = P * self.scale, q * self.scale
        A, b, cones = bounded_distortion_space(self.ops, w, Csolve, self.sigma, self.cone)
        fr, fx = self.free, self.fixed
        Pc = P[:, fr]
        Pff = Pc[fr]
        qf = q[fr] + P[fr][:, fx] @ self.xfix
        Af = A[:, fr]
        bf = b - A[:, fx] @ self.xfix
        self.timings["setup"] += time.perf_counter() - t
        sol = conic.solve_conic(Pff, qf, Af, bf, cones, cancel=self.cancel)
        self.timings["solve"] += sol.seconds
        self.solves += 1
        self.iterations += sol.iterations
        self.outcomes.append(sol.outcome)
        self.last_status = sol.status
        if sol.outcome == "cancelled" and self.cancel is not None and self.cancel.is_set():
            raise _Cancelled
        if sol.x is None:
            return None, sol.outcome
        x = np.zeros(2 * nv)
        x[fx] = self.xfix
        x[fr] = sol.x
        return x[:nv] + 1j * x[nv:], sol.outcome

    def check(self, u, C):
        """Certify a map in the normalised geometry: (ok, max distortion)."""
        t = time.perf_counter()
        D = self.distortion(u)
        self.timings["certify"] += time.perf_counter() - t
        return D <= C * (1 + 1e-9), D

    def energy_of(self, u, w):
        P, q, const = energy(self.method, self.ops, w)
        x = np.concatenate([u.real, u.imag])
        return float(0.5 * x @ (P @ x) + q @ x + const)


def _initial(prob, frames, initial_uv, report):
    """Initial map, its frames, the frames' name and the map's max distortion D0.

    D0 is finite only when the map is flip-free and honours the pins, so that F_C with these frames
    is guaranteed non-empty for C >= D0.
    """
    isl = prob.island
    npins = len(prob.pin_idx)
    pins = (prob.pin_idx, prob.pin_val) if npins >= 2 else None

    def guaranteed(u):
        return prob.distortion(u) if npins < 2 else np.inf

    def place(u):  # one pin: translate the free map onto it
        return u - u[prob.pin_idx[0]] + prob.pin_val[0] if npins == 1 else u

    if frames == "input-uv":
        uvc = initial_uv[isl.faces]
        if not np.all(np.isfinite(uvc)):
            raise InfeasibleError(f"island {isl.index}: frames from the current UVs need UVs on "
                                  "every face; unwrap it first or use frames='auto'", isl.index)
        alpha, _ = face_jacobians(prob.Vn, isl.tris, uvc)
        w = frames_from_map(alpha)
        return w, "input-uv", np.inf, None
    if frames == "constant":
        u = planar_map(prob.Vn)
        if np.mean(np.abs(prob.alpha(u)) > np.abs(prob.beta(u))) < 0.5:
            u = np.conj(u)
        u = place(u)
        return frames_from_map(prob.alpha(u)), "constant", guaranteed(u), u
    if frames in ("auto", "conformal"):
        report(0.02, "conformal initial map")
        u = place(lscm_map(prob.Z, isl.tris, prob.nv, isl.loops, pins))
        D0 = prob.distortion(u)
        if frames == "conformal" or np.isfinite(D0):
            g = D0 if npins < 2 else np.inf
            return frames_from_map(prob.alpha(u)), "conformal", g, u
    report(0.04, "harmonic initial map")
    u = place(harmonic_map(prob.Z, isl.tris, prob.nv, isl.loops))
    return frames_from_map(prob.alpha(u)), "harmonic", guaranteed(u), u


def _solve_island(island, V, pins, method, bound, frames, initial_uv, raise_bound, bound_limit,
                  cone, time_budget, report, cancel):
    t0 = time.perf_counter()
    if island.error is not None:
        return _failed(island, island.error, t0, bound)
    try:
        prob = _Problem(island, V, pins, method, cone, cancel)
        w0, frames_name, D0, u0 = _initial(prob, frames, initial_uv, report)
    except IslandError as exc:
        exc.island = island.index
        return _failed(island, exc, t0, bound)
    except BDError as exc:
        return _failed(island, SolverError(f"island {island.index}: {exc}", island.index), t0,
                       bound)
    prob.set_scale(u0 if u0 is not None else _any_map(prob, w0), w0)
    flags = []
    try:
        if bound == "auto":
            u, C = _auto(prob, w0, D0, u0, bound_limit, time_budget, flags, report, t0)
        else:
            u, C = _bounded(prob, w0, D0, u0, float(bound), raise_bound, bound_limit, flags,
                            report)
        if method == "arap" and u is not None:
            u = _arap(prob, u, C, report)
    except IslandError as exc:
        return _failed(island, exc, t0, bound, frames_name, flags, prob.timings)
    return _finish(prob, u, C, bound, frames_name, flags, t0)


def _any_map(prob, w):
    """A map for scaling when the frames came from input UVs: the conformal map."""
    return lscm_map(prob.Z, prob.island.tris, prob.nv, prob.island.loops,
                    (prob.pin_idx, prob.pin_val) if len(prob.pin_idx) >= 2 else None)


def _guaranteed_bound(D0):
    """The requested C whose solve bound (with SOLVE_MARGIN) still contains the D0 map."""
    return 1.0 + (D0 - 1.0) / (1.0 - SOLVE_MARGIN) * (1 + 1e-9) + 1e-12


_WHY = {"infeasible": "the space is empty for these frames",
        "inexact": "the solver did not converge", "error": "the solver failed",
        "solved": "the solver's map did not pass certification"}


def _bounded(prob, w0, D0, u0, C, raise_bound, limit, flags, report):
    """Solve at C with frame resets; raise C when infeasible. Returns (u, certified C)."""
    isl = prob.island
    w, best, prev_e, retried, resets = w0, None, None, False, 0
    while True:
        report(min(0.9, 0.1 + 0.15 * prob.solves), f"solving at C = {C:.3g}")
        u, outcome = prob.solve(w, C)
        ok, D = prob.check(u, C) if u is not None else (False, np.inf)
        if ok:
            e = prob.energy_of(u, w)
            best = (u, C)
            if (prev_e is not None and prev_e - e <= IMPROVEMENT * abs(prev_e)
                    or resets >= MAX_RESETS or prob.frame_turn(u, w) <= FRAME_TOLERANCE):
                return best
            prev_e, resets = e, resets + 1
            w = frames_from_map(prob.alpha(u))
            continue
        if best is not None:  # a later frame reset did not certify: keep the last certified map
            return best
        if u is not None and not retried and outcome == "inexact":  # an infeasible x is a certificate
            retried = True
            w = frames_from_map(prob.alpha(u))
            continue
        if np.isfinite(D0) and prob.check(u0, C)[0]:
            flags.append("initial_map")  # the solver failed where the initial map already fits
            return u0, C
        failure = prob.solver_failure()
        if failure is not None and (not raise_bound or C * RAISE_FACTOR > limit):
            raise failure
        if not raise_bound:
            raise InfeasibleError(f"island {isl.index}: no map within distortion {C:g} was found "
                                  f"({_WHY.get(outcome, outcome)}); allow raising the bound or use a larger C",
                                  isl.index)
        newC = C * RAISE_FACTOR
        if np.isfinite(D0):  # approach the bound known to be feasible geometrically
            newC = max(newC, np.sqrt(C * D0))
            if newC * RAISE_FACTOR >= D0:
                newC = max(_guaranteed_bound(D0), C * 1.0001)
        w = w0
        if newC > limit:
            raise InfeasibleError(f"island {isl.index}: infeasible up to the bound limit "
                                  f"{limit:g}" + (" (the pins force a flip or a larger distortion)"
                                                  if len(prob.pin_idx) >= 2 else "")
                                  + "; raise the limit, move or remove pins, or add seams",
                                  isl.index)
        if "bound_raised" not in flags:
            flags.append("bound_raised")
        C, retried = newC, False


def _auto(prob, w0, D0, u0, limit, budget, flags, report, t0):
    """Algorithm 1: bisection on C with frame updates. Returns (u, smallest certified C)."""
    isl = prob.island
    lo, hi, best = 1.0, np.inf, None
    w = w0
    C = 5.0 if not np.isfinite(D0) else min(5.0, _guaranteed_bound(D0))
    while prob.solves < AUTO_MAX_SOLVES:
        if prob.solves and budget is not None and time.perf_counter() - t0 > budget:
            flags.append("time_budget_exhausted")
            break
        frac = 0.1 + 0.8 * prob.solves / AUTO_MAX_SOLVES
        report(frac, f"minimising C: {lo:.3g} < C* <= {hi:.4g}")
        u, _ = prob.solve(w, C)
        ok, D = prob.check(u, C) if u is not None else (False, np.inf)
        if ok:
            best = (u, D)
            hi = D
            w = frames_from_map(prob.alpha(u))
        else:
            lo = C
        if np.isfinite(hi) and hi - lo <= AUTO_TOLERANCE * hi:
            break
        if not np.isfinite(hi):
            C = 2.0 * lo
            if np.isfinite(D0) and C >= D0:
                C, w = _guaranteed_bound(D0), w0
            if C > limit:
                break
        else:
            C = 0.5 * (lo + hi)
    if best is None:
        if np.isfinite(D0) and D0 <= limit and prob.check(u0, D0 * (1 + 1e-9))[0]:
            flags.append("initial_map")
            return u0, D0
        failure = prob.solver_failure()
        if failure is not None:
            raise failure
        spent = ("; the time budget ran out after "
                 f"{prob.solves} solve(s): allow more time" if "time_budget_exhausted" in flags
                 else "")
        raise InfeasibleError(f"island {isl.index}: no certified map found up to C = "
                              f"{min(limit, 2 * lo):g}{spent}; add seams, move pins, or raise "
                              "the limit", isl.index)
    return best


def _arap(prob, u, C, report):
    """BD-ARAP: minimise the ARAP energy over F_C with frames from the previous map, resetting
    the frames while the energy improves (section 6.1, "As-rigid-as-possible")."""
    if len(prob.pin_idx) < 2:
        # ARAP has an absolute scale: start from the map scaled to the 3D area, with a small sigma.
        scale = np.sqrt(1.0 / _uv_area(u, prob.island.tris))
        u = (u - u[0]) * scale if not len(prob.pin_idx) else \
            prob.pin_val[0] + (u - prob.pin_val[0]) * scale
        if not len(prob.pin_idx):
            prob.xfix = np.concatenate([[u[0].real], [u[0].imag]])
    prob.sigma = 1e-3 * float(np.median(np.abs(prob.alpha(u))))
    prob.scale = 1.0
    prev = None
    for i in range(MAX_RESETS + 1):
        w = frames_from_map(prob.alpha(u))
        e_now = prob.energy_of(u, w)
        prob.scale = 1.0 / max(e_now, 1e-6)
        report(0.9, f"BD-ARAP iteration {i + 1}")
        un, _ = prob.solve(w, C)
        if un is None or not prob.check(un, C)[0]:
            break
        e = prob.energy_of(un, w)
        u = un
        if prev is not None and prev - e <= IMPROVEMENT * abs(prev):
            break
        prev = e
    return u


def _uv_area(u, tris):
    p = u[tris]
    return float(np.sum(0.5 * ((p[:, 1] - p[:, 0]).conj() * (p[:, 2] - p[:, 0])).imag))


def _finish(prob, u, C, bound, frames_name, flags, t0):
    """Scale and place the island, certify it from its final UVs in the input geometry."""
    isl = prob.island
    npins = len(prob.pin_idx)
    if npins < 2:
        s = np.sqrt(prob.area3d / _uv_area(u, isl.tris))
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
    ok, D, n_flipped = certify(prob.V, isl.tris, uv[isl.tris], C)
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
                          f"{maxD:.4g}, {n_flipped} flipped, bound {C:.4g}); nothing was written",
                          isl.index)
        return IslandResult(isl.index, isl.faces, isl.vertices, isl.tris, status="failed",
                            error=err, message=str(err), **common)
    certified_C = maxD if bound == "auto" else C
    msg = (f"island {isl.index}: {len(isl.faces)} faces, max distortion {maxD:.3f} <= "
           f"{certified_C:.3g}, 0 flipped")
    if certified_C > HIGH_DISTORTION:
        flags = list(flags) + ["high_distortion"]
        common["flags"] = tuple(flags)
        msg += (f"; C above {HIGH_DISTORTION:g} means the island is nearly closed or badly cut: "
                "mark seams for a lower bound")
    return IslandResult(isl.index, isl.faces, isl.vertices, isl.tris, uv=uv, status="certified",
                        message=msg, bound_certified=float(certified_C), energy=prob.energy_of(u, frames_from_map(prob.alpha(u))),
                        **common)
