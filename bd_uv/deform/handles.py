"""A bounded-distortion solve with vertices held fixed (Lipman 2012, sections 4 and 6).

``solve_with_handles`` minimises an energy over F_C (eqs. 4.15-4.18; optionally with stretch
bounds, section 6.3) with some vertices kept exactly at their positions; ``bounded_with_resets``
repeats it with the frame field reset from each solution by eq. 4.21 (section 4, "Resetting the
frame-field and iterating"). Used by planar deformation (``planar.deform``), the fixed-boundary
map (``boundary.fixed_map``) and mesh improvement (``improve``).
"""
import numpy as np
import scipy.sparse as sp

from ..energies import energy, jacobian_operators, stretch_l1_program
from ..errors import CancelledError
from ..frames import frames_from_map
from ..solvers import conic
from ..spaces import bounded_distortion_space, mean_scale_row, stretch_space

METHODS = ("lscm", "arap", "dirichlet", "biharmonic", "stretch-l1")
SOLVE_MARGIN = 2e-3     # solve at a C slightly below the bound so certification has headroom
MAX_RESETS = 4          # frame resets after the first feasible solve
MAX_RETRIES = 4         # frame resets from an infeasible solve's last iterate
IMPROVEMENT = 0.01      # keep resetting frames while the energy drops by more than this fraction
# Faces marked ``loose`` (the triangles filling an island's holes, ``boundary.fixed_boundary_map``)
# are held in F_C at this C only: they need only stay orientation-preserving (Theorem 5.1).
LOOSE_BOUND = 1e4


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
