"""The map an island starts from, and its frames (Lipman 2012, section 4, "Framing of M").

The result inherits the start: a start that already fits the bound is returned as it is, and a
start that does not is bent only where the bound demands. So the start is the best map we can get
cheaply: the free-boundary conformal map (LSCM), flipped faces and all (projection iterations
untangle them, see ``bounded.bend``); the harmonic map when asked for, or when bending stalls.
"""
from dataclasses import dataclass

import numpy as np

from ..errors import InfeasibleError
from ..frames import frames_from_map, harmonic_map, lscm_map, planar_map
from ..metrics import face_jacobians


@dataclass(frozen=True)
class Start:
    """An island's start map.

    Attributes
    ----------
    u : (nv,) complex128 or None, the start map (None when only frames are known)
    frames : (k,) complex128 unit frames (eq. 4.21)
    name : str, where the frames come from ("conformal", "harmonic", "input-uv", "constant")
    D : float, max distortion of ``u``; finite only when ``u`` is flip-free and honours the pins,
        so that F_C with these frames holds ``u`` for every C >= D
    """
    u: np.ndarray
    frames: np.ndarray
    name: str
    D: float


def start_map(prob, frames, initial_uv, report, lscm=None):
    """The start map of an island for a frames option.

    Parameters
    ----------
    prob : problem.IslandProblem
    frames : "auto" | "conformal" | "harmonic" | "input-uv" | "constant"
    initial_uv : (m,3,2) float64 or None, the whole mesh's corner UVs (for "input-uv")
    report : callable(fraction, message)
    lscm : (nv,) complex128, optional, the island's conformal map when already computed

    Returns
    -------
    Start
    """
    isl = prob.island
    npins = len(prob.pin_idx)

    def guaranteed(u):
        return prob.distortion(u) if npins < 2 else _pinned_distortion(prob, u)

    def place(u):  # one pin: translate the free map onto it
        return u - u[prob.pin_idx[0]] + prob.pin_val[0] if npins == 1 else u

    if frames == "input-uv":
        uvc = initial_uv[isl.faces]
        if not np.all(np.isfinite(uvc)):
            raise InfeasibleError(f"island {isl.index}: frames from the current UVs need UVs on "
                                  "every face; unwrap it first or use frames='auto'", isl.index)
        alpha, _ = face_jacobians(prob.Vn, isl.tris, uvc)
        u = _vertex_uv(isl.tris, prob.nv, uvc)
        if u is None:  # the current UVs are cut inside the island: frames only
            return Start(None, frames_from_map(alpha), "input-uv", np.inf)
        u = place(u)
        return Start(u, frames_from_map(prob.alpha(u)), "input-uv", guaranteed(u))
    if frames == "constant":
        u = planar_map(prob.Vn)
        if np.mean(np.abs(prob.alpha(u)) > np.abs(prob.beta(u))) < 0.5:
            u = np.conj(u)
        u = place(u)
        return Start(u, frames_from_map(prob.alpha(u)), "constant", guaranteed(u))
    if frames in ("auto", "conformal"):
        if lscm is None:
            report(0.02, "conformal initial map")
            pins = (prob.pin_idx, prob.pin_val) if npins >= 2 else None
            lscm = lscm_map(prob.Z, isl.tris, prob.nv, isl.loops, pins, ops=prob.ops)
        u = place(lscm)  # when it flips (D = inf), the strategies bend it or replace it
        return Start(u, frames_from_map(prob.alpha(u)), "conformal", guaranteed(u))
    report(0.04, "harmonic initial map")
    u = place(harmonic_map(prob.Z, isl.tris, prob.nv, isl.loops))
    return Start(u, frames_from_map(prob.alpha(u)), "harmonic", guaranteed(u))


def _pinned_distortion(prob, u):
    """Max distortion of a map that must honour two or more pins; inf when it does not."""
    if np.any(np.abs(u[prob.pin_idx] - prob.pin_val) > 1e-12 * (1 + np.abs(prob.pin_val))):
        return np.inf
    return prob.distortion(u)


def _vertex_uv(tris, nv, corner_uv):
    """One UV per island vertex from per-corner UVs, or None when corners of a vertex disagree.

    Parameters
    ----------
    tris : (k,3) int, corner_uv : (k,3,2) float

    Returns
    -------
    (nv,) complex128 or None
    """
    c = (corner_uv[..., 0] + 1j * corner_uv[..., 1]).ravel()
    u = np.zeros(nv, dtype=np.complex128)
    u[tris.ravel()] = c
    if np.any(np.abs(u[tris.ravel()] - c) > 1e-9 * (1 + np.abs(c))):
        return None
    return u
