"""2D mesh improvement: the optimal quasi-conformal map from equilateral triangles (section 6.6).

Each face of a planar mesh is seen as the image of an equilateral triangle (the hypothetical mesh
M* with the same connectivity, a metric rather than an embedding). Frames fitting each face's
closest equilateral in least squares are the frames of that map (the similarity part alpha of an
affine map is its closest similarity in the Frobenius norm, eq. 4.21). Algorithm 1 (bisection on
C with frame updates, section 6.5) then finds the smallest C* for which F_C with the boundary
fixed is feasible; every face of the result is within C* of an equilateral, and with the boundary
fixed and no flip the map is a bijection of the domain (Theorems 5.1, 5.2).
"""
import time
from dataclasses import dataclass

import numpy as np

from .deform import alpha_of, map_distortion, solve_with_handles
from .energies import jacobian_operators
from .frames import frames_from_map

EQUILATERAL = np.array([0.0, 1.0, 0.5 + 0.5j * np.sqrt(3.0)])
TOLERANCE = 0.005       # bisection stops when C_right - C_left <= this * C_right
MAX_SOLVES = 16
SOLVE_MARGIN = 2e-3


@dataclass(frozen=True)
class ImproveResult:
    """An improved planar mesh.

    Attributes
    ----------
    V2 : (n,2) float64, boundary vertices bit for bit those of the input
    distortion_before, distortion_after : (m,) float64, conformal distortion of each face
        against the equilateral triangle
    max_before, max_after : float
    bound : float, the C* every face with a movable (interior) vertex was certified within;
        faces whose three vertices are all on the boundary cannot change and keep their own
        distortion
    movable_before, movable_after : float, max distortion over the faces with an interior vertex
    flipped : int, 0
    solves : int
    seconds : float
    """
    V2: np.ndarray
    distortion_before: np.ndarray
    distortion_after: np.ndarray
    max_before: float
    max_after: float
    bound: float
    movable_before: float
    movable_after: float
    flipped: int
    solves: int
    seconds: float


def equilateral_operators(F, n):
    """Jacobian operators of the map from equilateral faces (side 1) to vertex positions."""
    F = np.asarray(F, dtype=np.int64)
    return jacobian_operators(np.tile(EQUILATERAL, (len(F), 1)), F, n)


def equilateral_distortion(V2, F):
    """Conformal distortion of each face against the equilateral triangle (eq. 4.9).

    Parameters
    ----------
    V2 : (n,2) float, F : (m,3) int

    Returns
    -------
    D : (m,) float64, ``inf`` for clockwise or degenerate faces
    """
    V2 = np.asarray(V2, dtype=np.float64)
    ops = equilateral_operators(F, len(V2))
    x = np.concatenate([V2[:, 0], V2[:, 1]])
    a = np.abs(ops.Are @ x + 1j * (ops.Aim @ x))
    b = np.abs(ops.Bre @ x + 1j * (ops.Bim @ x))
    with np.errstate(divide="ignore", invalid="ignore"):
        D = (a + b) / (a - b)
    D[~(a > b) | ~np.isfinite(D)] = np.inf
    return D


def _boundary_vertices(F):
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    key = np.sort(E, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return np.unique(key[cnt[inv.ravel()] == 1])


def improve(V2, F, tolerance=TOLERANCE, max_solves=MAX_SOLVES, cancel=None):
    """Move a planar mesh's interior vertices so every face is as close to equilateral as possible.

    Lipman 2012, section 6.6 with Algorithm 1 (section 6.5), boundary fixed.

    Parameters
    ----------
    V2 : (n,2) float, vertex positions; every face counter-clockwise
    F : (m,3) int
    tolerance : float, relative gap of the bisection on C
    max_solves : int
    cancel : object with ``is_set()``, optional

    Returns
    -------
    ImproveResult (the input itself, certified at its own distortion, when nothing better is found)

    Raises
    ------
    ValueError for a mesh with clockwise or degenerate faces (no valid start).
    """
    t0 = time.perf_counter()
    V2 = np.asarray(V2, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    n = len(V2)
    D_before = equilateral_distortion(V2, F)
    if not np.all(np.isfinite(D_before)):
        raise ValueError(f"{int((~np.isfinite(D_before)).sum())} face(s) are clockwise or "
                         "degenerate; improve needs a valid counter-clockwise mesh")
    fixed = _boundary_vertices(F)
    # Faces with all three corners on the boundary cannot move: leave them out of the space, or
    # they would hold C* at their own distortion.
    movable = ~np.all(np.isin(F, fixed), axis=1)
    if not movable.any():
        return ImproveResult(V2.copy(), D_before, D_before, float(D_before.max()),
                             float(D_before.max()), float(D_before.max()), float("nan"),
                             float("nan"), 0, 0, time.perf_counter() - t0)
    ops = equilateral_operators(F[movable], n)
    u0 = V2[:, 0] + 1j * V2[:, 1]
    val = u0[fixed]
    w = frames_from_map(alpha_of(ops, u0))
    sigma = 1e-3 * float(np.median(np.abs(alpha_of(ops, u0))))
    lo, hi, best, solves = 1.0, float(D_before[movable].max()), u0, 0
    C = 0.5 * (lo + hi)
    while solves < max_solves and hi - lo > tolerance * hi:
        Csolve = 1.0 + (C - 1.0) * (1.0 - SOLVE_MARGIN)
        u, _ = solve_with_handles(ops, fixed, val, w, Csolve, None, sigma, cancel=cancel)
        solves += 1
        D = map_distortion(ops, u) if u is not None else np.inf
        if D <= C:
            best, hi = u, D  # the map is certified within its own max distortion D <= C
            w = frames_from_map(alpha_of(ops, u))
            if hi <= lo:  # new frames beat an earlier infeasible C: that evidence is stale
                lo = 1.0
        else:
            lo = C
        C = 0.5 * (lo + hi)
    out = V2.copy()
    interior = np.setdiff1d(np.arange(n), fixed)
    out[interior, 0] = best.real[interior]
    out[interior, 1] = best.imag[interior]
    D_after = equilateral_distortion(out, F)
    if not D_after[movable].max() <= D_before[movable].max():  # never worse than the input
        out, D_after = V2.copy(), D_before
    return ImproveResult(out, D_before, D_after, float(D_before.max()), float(D_after.max()),
                         float(D_after[movable].max()), float(D_before[movable].max()),
                         float(D_after[movable].max()), 0, solves, time.perf_counter() - t0)
