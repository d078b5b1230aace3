"""Planar deformation with handles within a conformal bound (Lipman 2012, section 6.1).

A planar triangle mesh (or a UV layout) is deformed so that its handle vertices reach their target
positions exactly, minimising BD-LSCM (ASAP), BD-ARAP, BD-Dirichlet, BD-Biharmonic (eq. 6.1) or
the L1 stretch energy over F_C (eqs. 4.15-4.18) with a frame field from the rest shape or from a
previous deformation, reset from each solution by eq. 4.21 and re-solved (section 4, "Resetting
the frame-field and iterating"; ``handles.bounded_with_resets``). Every face of the result is
certified from the final positions: not flipped and conformal distortion <= C. With fixed handles
all around the boundary and the boundary mapped onto a simple polygon, the result is a bijection
(Theorem 5.1).
"""
import time
from dataclasses import dataclass

import numpy as np

from ..energies import energy
from ..errors import InfeasibleError
from ..live.drag import mend_overlap
from ..overlap import island_overlaps
from ..frames import _solve_fixed, frames_from_map
from ..geometry import local_coordinates
from ..metrics import conformal_distortion, flipped_faces
from ..spaces import check_stretch
from .handles import METHODS, alpha_of, bounded_with_resets, energy_value, planar_operators


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

