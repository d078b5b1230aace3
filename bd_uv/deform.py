"""Planar deformation with handles within a conformal bound (Lipman 2012, section 6.1).

A planar triangle mesh (or a UV layout) is deformed so that its handle vertices reach their target
positions exactly, minimising BD-LSCM (ASAP), BD-ARAP, BD-Dirichlet, BD-Biharmonic (eq. 6.1) or
the L1 stretch energy over F_C (eqs. 4.15-4.18) with a frame field from the rest shape or from a
previous deformation, reset from each solution by eq. 4.21 and re-solved (section 4, "Resetting
the frame-field and iterating"). Every face of the result is certified from the final positions:
not flipped and conformal distortion <= C. With fixed handles all around the boundary and the
boundary mapped onto a simple polygon, the result is a bijection (Theorem 5.1).
"""
import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .energies import energy, jacobian_operators, stretch_l1_program
from .errors import CancelledError, InfeasibleError
from .live.drag import mend_overlap
from .overlap import island_overlaps
from .frames import _solve_fixed, frames_from_map
from .geometry import local_coordinates
from .metrics import conformal_distortion, flipped_faces
from .solvers import conic
from .spaces import bounded_distortion_space, check_stretch, mean_scale_row, stretch_space

METHODS = ("lscm", "arap", "dirichlet", "biharmonic", "stretch-l1")
SOLVE_MARGIN = 2e-3     # solve at a C slightly below the bound so certification has headroom
MAX_RESETS = 4          # frame resets after the first feasible solve
MAX_RETRIES = 4         # frame resets from an infeasible solve's last iterate
IMPROVEMENT = 0.01      # keep resetting frames while the energy drops by more than this fraction
# Faces marked ``loose`` (the triangles filling an island's holes, ``boundary.fixed_boundary_map``)
# are held in F_C at this C only: they need only stay orientation-preserving (Theorem 5.1).
LOOSE_BOUND = 1e4


@dataclass(frozen=True)
class DeformResult:
    """A certified planar deformation.

    Attributes
    ----------
    uv : (n,2) float64, deformed positions; handles exactly at their targets
    distortion : (m,) float64, conformal distortion of each face against the rest shape
    max_distortion : float
    flipped : int, always 0 for a returned result
    bound : float, the bound C that every face was certified within
    energy : float, the energy at the result (normalised geometry: unit total area)
    solves, iterations : int
    seconds : float
    overlap_free : bool, the overlap test (``overlap.island_overlaps``) on ``uv``: always True
        for a returned result
    mended : bool, the direct solve overlapped itself and this map was found by dragging the
        handles there in steps with every step certified (``live.drag``)
    """
    uv: np.ndarray
    distortion: np.ndarray
    max_distortion: float
    flipped: int
    bound: float
    energy: float
    solves: int
    iterations: int
    seconds: float
    overlap_free: bool = True
    mended: bool = False


def planar_operators(Z, tris, nv):
    """Jacobian operators of a planar mesh given by per-face local coordinates (eq. 4.19)."""
    return jacobian_operators(Z, np.asarray(tris, dtype=np.int64), nv)


def solve_with_handles(ops, idx, val, w, C, method, sigma, stretch=None, cone="soc",
                       cancel=None, fix_scale=False, loose=None):
    """Minimise an energy over F_C (optionally with stretch bounds) with vertices held fixed.

    Parameters
    ----------
    ops : energies.JacobianOperators of the mesh (nv vertices, k faces)
    idx : (h,) int, fixed vertices; val : (h,) complex, their positions (kept exactly)
    w : (k,) complex unit frames
    C : float, the bound used for the space (no margin is added here)
    method : "lscm" | "arap" | "dirichlet" | "biharmonic" | "stretch-l1" | None (feasibility only)
    sigma : float > 0, lower bound on Re(w alpha) (eq. 4.17)
    stretch : (smin, smax) or None, singular-value bounds (section 6.3, ``spaces.stretch_space``)
    cone : "soc" | "linf"
    cancel : object with ``is_set()``, optional
    fix_scale : bool, add ``spaces.mean_scale_row`` (area-weighted mean of Re(w alpha) = 1), for
        free-boundary islands whose stretch is measured after scaling to UV area = 3D area
    loose : (k,) bool, optional, faces held at LOOSE_BOUND instead of C and without stretch
        bounds (triangles that need only stay orientation-preserving)

    Returns
    -------
    u : (nv,) complex or None, sol : solvers.conic.ConicSolution
    """
    nv = ops.Are.shape[1] // 2
    idx = np.asarray(idx, dtype=np.int64)
    val = np.asarray(val, dtype=np.complex128)
    fixed = np.concatenate([idx, idx + nv])
    xfix = np.concatenate([val.real, val.imag])
    free = np.setdiff1d(np.arange(2 * nv), fixed)
    if loose is not None:
        C = np.where(loose, LOOSE_BOUND, C)
    A, b, cones = bounded_distortion_space(ops, w, C, sigma, cone)
    if stretch is not None:
        As, bs, cs = stretch_space(ops, w, C, *stretch,
                                   faces=None if loose is None else ~loose)
        A = sp.vstack([A, As]).tocsc()
        b, cones = np.concatenate([b, bs]), cones + cs
    if fix_scale:
        Az, bz, cz = mean_scale_row(ops, w)
        A = sp.vstack([Az, A]).tocsc()  # Clarabel: zero cones may come first or anywhere
        b, cones = np.concatenate([bz, b]), cz + cones
    if method == "stretch-l1":
        P, q, A, b, cones = stretch_l1_program(ops, A, b, cones)
    elif method is None:
        P, q = None, np.zeros(2 * nv)
    else:
        P, q, _ = energy(method, ops, w)
    n_all = A.shape[1]
    keep = np.concatenate([free, np.arange(2 * nv, n_all)])
    xf_full = np.zeros(n_all)
    xf_full[fixed] = xfix
    if P is None:
        Pk = sp.csc_array((len(keep), len(keep)))
        qk = np.zeros(len(keep))
    else:
        diag = P.diagonal()
        scale = len(diag) / max(float(np.abs(diag).sum()), 1e-300) if np.any(diag) else \
            1.0 / max(float(np.abs(q).sum()), 1e-300)
        P = P * scale
        q = q * scale
        Pk = P[keep][:, keep]
        qk = q[keep] + P[keep] @ xf_full
    A = A.tocsc()
    Ak = A[:, keep]
    bk = b - A @ xf_full
    sol = conic.solve_conic(Pk, qk, Ak, bk, cones, cancel=cancel)
    if sol.x is None:
        return None, sol
    x = xf_full.copy()
    x[keep] = sol.x
    return x[:nv] + 1j * x[nv:2 * nv], sol


def map_distortion(ops, u, loose=None):
    """Max conformal distortion (eq. 4.9) of a map u (nv,) complex; inf if any face flips.
    Faces marked ``loose`` (k,) bool count only for flips."""
    x = np.concatenate([u.real, u.imag])
    a = np.abs(ops.Are @ x + 1j * (ops.Aim @ x))
    b = np.abs(ops.Bre @ x + 1j * (ops.Bim @ x))
    if not np.all(a > b):
        return np.inf
    if loose is not None:
        a, b = a[~loose], b[~loose]
    return float(np.max((a + b) / (a - b)))


def energy_value(method, ops, u, w):
    """The energy of a map: quadratic forms of ``energies.energy``, or the L1 stretch energy."""
    x = np.concatenate([u.real, u.imag])
    if method == "stretch-l1":
        a = np.abs(ops.Are @ x + 1j * (ops.Aim @ x))
        b = np.abs(ops.Bre @ x + 1j * (ops.Bim @ x))
        return float(np.sum((a + b) * ops.area))
    P, q, const = energy(method, ops, w)
    return float(0.5 * x @ (P @ x) + q @ x + const)


def alpha_of(ops, u):
    """Similarity part alpha (k,) complex of a map u (nv,) complex (eq. 4.19)."""
    x = np.concatenate([u.real, u.imag])
    return ops.Are @ x + 1j * (ops.Aim @ x)


def bounded_with_resets(ops, idx, val, w, C, method, sigma, stretch=None, cone="soc",
                        cancel=None, max_resets=MAX_RESETS, fix_scale=False, loose=None):
    """Solve over F_C, resetting frames (eq. 4.21) after infeasible solves and after solutions.

    Lipman 2012, section 4 ("Resetting the frame-field and iterating") and section 6, step 4.

    Parameters are those of ``solve_with_handles``; ``max_resets`` caps the resets after the
    first certified solve.

    Returns
    -------
    u : (nv,) complex or None (no certified map found), solves : int, iterations : int
    """
    Csolve = 1.0 + (C - 1.0) * (1.0 - SOLVE_MARGIN)
    best, best_e, solves, iterations, retries, resets = None, np.inf, 0, 0, 0, 0
    while True:
        u, sol = solve_with_handles(ops, idx, val, w, Csolve, method, sigma, stretch, cone, cancel,
                                    fix_scale, loose)
        solves += 1
        iterations += sol.iterations
        if sol.outcome == "cancelled":
            raise CancelledError("deformation cancelled")
        ok = u is not None and map_distortion(ops, u, loose) <= C
        if ok and stretch is not None:
            x = np.concatenate([u.real, u.imag])
            a = np.abs(ops.Are @ x + 1j * (ops.Aim @ x))
            b = np.abs(ops.Bre @ x + 1j * (ops.Bim @ x))
            if loose is not None:
                a, b = a[~loose], b[~loose]
            ok = bool(np.all(a - b >= stretch[0] * (1 - 1e-9)) and
                      np.all(a + b <= stretch[1] * (1 + 1e-9)))
        if ok:
            wu = frames_from_map(alpha_of(ops, u))
            e = energy_value(method, ops, u, wu)
            improved = e < best_e * (1.0 - IMPROVEMENT)
            if e < best_e:
                best, best_e = u, e
            if not improved or resets >= max_resets:
                return best, solves, iterations
            resets += 1
            w = wu
        else:
            if best is not None or u is None or retries >= MAX_RETRIES:
                return best, solves, iterations
            retries += 1
            w = frames_from_map(alpha_of(ops, u))


def deform(V2, F, handles, positions, method="lscm", bound=5.0, frames="rest", previous=None,
           stretch=None, cone="soc", cancel=None):
    """Deform a planar mesh so its handles reach their targets, within conformal distortion C.

    Lipman 2012, section 6.1 (BD-LSCM/ASAP, BD-ARAP, BD-Biharmonic eq. 6.1, BD-Dirichlet, L1
    stretch) over F_C (eqs. 4.15-4.18), frames reset by eq. 4.21.

    Parameters
    ----------
    V2 : (n,2) float, rest positions; every face counter-clockwise
    F : (m,3) int
    handles : (h,) int, handle vertices (fixed and moved ones alike)
    positions : (h,2) float, their targets (met exactly)
    method : "lscm" | "arap" | "dirichlet" | "biharmonic" | "stretch-l1"
    bound : float >= 1, the conformal bound C
    frames : "rest" (frames of the rest shape: constant frames) or "previous" (frames of
        ``previous``, e.g. the last deformation; without it, of the plain minimiser of the
        energy with the handles, which may fold; for "arap" and "stretch-l1", the rest frames)
    previous : (n,2) float, optional
    stretch : float S >= sqrt(C), optional: every face's singular values in [1/S, S] (section 6.3)
    cone : "soc" (F_C) | "linf" (F_C^inf, eq. 4.22)
    cancel : object with ``is_set()``, optional

    Returns
    -------
    DeformResult

    Raises
    ------
    ValueError for bad options or a rest shape with clockwise/degenerate faces,
    InfeasibleError when no certified map was found within C.
    """
    t0 = time.perf_counter()
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if frames not in ("rest", "previous"):
        raise ValueError(f"frames must be 'rest' or 'previous', got {frames!r}")
    if not (isinstance(bound, (int, float)) and 1.0 <= bound < np.inf):
        raise ValueError(f"bound must be a finite number >= 1, got {bound!r}")
    if stretch is not None:
        check_stretch(bound, stretch)
    V2 = np.asarray(V2, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    handles = np.asarray(handles, dtype=np.int64).ravel()
    positions = np.asarray(positions, dtype=np.float64).reshape(-1, 2)
    n = len(V2)
    if V2.ndim != 2 or V2.shape[1] != 2 or F.ndim != 2 or F.shape[1] != 3:
        raise ValueError("V2 must be (n,2) and F (m,3)")
    if len(handles) != len(positions) or len(handles) < 2:
        raise ValueError("give at least two handles, each with one target position")
    if np.any((handles < 0) | (handles >= n)) or len(np.unique(handles)) != len(handles):
        raise ValueError("handle indices must be distinct vertex indices in 0..n-1")
    e1, e2 = V2[F[:, 1]] - V2[F[:, 0]], V2[F[:, 2]] - V2[F[:, 0]]
    if not np.all(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] > 0):
        raise ValueError("every rest face must be counter-clockwise with positive area "
                         "(reverse F's corner order for a clockwise mesh)")
    # Normalised geometry: centred, unit total area (results are mapped back exactly).
    c = V2.mean(axis=0)
    s = np.sqrt(0.5 * np.sum(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]))
    Vn = (V2 - c) / s
    un_rest = Vn[:, 0] + 1j * Vn[:, 1]
    val = ((positions[:, 0] - c[0]) + 1j * (positions[:, 1] - c[1])) / s
    ops = planar_operators(local_coordinates(np.column_stack([Vn, np.zeros(n)]), F), F, n)
    w = frames_from_map(alpha_of(ops, un_rest))
    if frames == "previous":
        if previous is not None:
            pv = (np.asarray(previous, dtype=np.float64).reshape(n, 2) - c) / s
            w = frames_from_map(alpha_of(ops, pv[:, 0] + 1j * pv[:, 1]))
        elif method != "stretch-l1":
            P, q, _ = energy(method, ops, w)
            x = _solve_fixed(P, n, handles, val) if method != "arap" else None
            if x is not None:
                w = frames_from_map(alpha_of(ops, x))
    st = None if stretch is None else (1.0 / stretch, float(stretch))
    u, solves, iters = bounded_with_resets(ops, handles, val, w, bound, method, 1e-3, st, cone,
                                           cancel)
    if u is None:
        raise InfeasibleError(f"no deformation within C = {bound:g} and 0 flips was found"
                              + (f" with stretch {stretch:g}" if stretch else "")
                              + " after frame resets; raise the bound, move the handles less, "
                                "or deform in smaller steps with frames='previous'")
    uv = np.column_stack([u.real * s + c[0], u.imag * s + c[1]])
    uv[handles] = positions
    corner = uv[F]
    V3 = np.column_stack([V2, np.zeros(n)])
    D = conformal_distortion(V3, F, corner)
    flipped = int(flipped_faces(V3, F, corner).sum())
    if flipped or not np.all(D <= bound * (1 + 1e-6)):
        raise InfeasibleError(f"the deformation did not certify within C = {bound:g} after "
                              "writing the handles back; raise the bound slightly")
    mended = False
    ov = island_overlaps(F, corner, np.zeros(len(F), dtype=np.int64), 1)
    if not ov.overlap_free[0]:
        uv, D = mend_overlap(V2, F, handles, positions, method, bound, stretch, cone, ov)
        u = ((uv[:, 0] - c[0]) + 1j * (uv[:, 1] - c[1])) / s
        mended = True
    e = energy_value(method, ops, u, frames_from_map(alpha_of(ops, u)))
    return DeformResult(uv, D, float(D.max()), 0, float(bound), e, solves, iters,
                        time.perf_counter() - t0, True, mended)

