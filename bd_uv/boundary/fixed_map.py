"""The fixed-boundary bounded-distortion map (Lipman 2012, section 5, Theorems 5.1 and 5.2):
a solve over F_C with the outer boundary pinned on its targets and every hole filled by a fan of
triangles held orientation-preserving, so the filled disk maps bijectively onto the target polygon.
"""
import dataclasses
from dataclasses import dataclass

import numpy as np

from ..bijectivity import BijectivityPremises, bijectivity_premises, oriented_loop
from ..errors import InfeasibleError
from ..frames import frames_from_map, harmonic_map, hole_fans
from ..geometry import face_areas, local_coordinates
from ..metrics import conformal_distortion

HOMOTOPY_STEPS = (0.25, 0.5, 0.75, 1.0)
# Energy weight of the triangles filling holes during a fixed-boundary solve (relative to their
# area): small, so the island's own faces decide the map; not zero, so every vertex has energy.
FILL_WEIGHT = 1e-3


@dataclass(frozen=True)
class FixedBoundaryMap:
    """A bounded-distortion map with its outer boundary fixed.

    Attributes
    ----------
    uv : (nv,2) float64, pinned vertices exactly at their targets
    max_distortion : float, conformal distortion (eq. 4.9), <= the bound
    premises : BijectivityPremises, checked on ``uv``
    solves : int
    """
    uv: np.ndarray
    max_distortion: float
    premises: BijectivityPremises
    solves: int


def fill_holes(Z, tris, nv, holes):
    """The island with every hole filled by a fan of triangles around a new centre vertex.

    Parameters
    ----------
    Z : (k,3) complex local corner coordinates, tris : (k,3) int, nv : int
    holes : sequence of (b,) int hole loops, faces on their left (``oriented_loop``)

    Returns
    -------
    Z_all : (k+q,3) complex, tris_all : (k+q,3) int64 (the fill after the island's faces,
    oriented like them), nv_all : int (the centre of hole h is vertex nv + h)
    """
    if not len(holes):
        return Z, tris, nv
    Zf, Tf = hole_fans(Z, tris, nv, holes)
    return np.concatenate([Z, Zf]), np.concatenate([tris, Tf]), nv + len(holes)


def fixed_boundary_map(V, tris, loops, idx, uv, method="dirichlet", bound=5.0, stretch=None,
                       cone="soc", cancel=None):
    """Minimise an energy over F_C with the vertices ``idx`` pinned at ``uv`` (section 5).

    Holes stay holes by construction: each is filled by a fan of triangles (``fill_holes``) held
    orientation-preserving only (``deform.LOOSE_BOUND``, energy weight ``FILL_WEIGHT``), so the
    filled disk's map is orientation-preserving with its boundary on the simple target polygon, a
    bijection by Theorem 5.1: the holes' images lie inside the target and apart from every other
    triangle. The fill is removed before the result is checked (``bijectivity_premises``).
    The frames come from the flip-free Tutte embedding onto a circle (``frames.harmonic_map``),
    turned by the rotation that best fits its pinned vertices to their targets (F_C only admits
    rotations within 90 degrees of the frames, so the embedding's arbitrary global rotation must
    go). When that space is empty the pins are reached in steps (``HOMOTOPY_STEPS``) from the
    fitted embedding's own positions, each step's frames from the last (eq. 4.21).

    Parameters
    ----------
    V : (nv,3) float, tris : (k,3) int, loops : sequence of (b,) int (``Island`` fields)
    idx : (p,) int, pinned island vertices (e.g. ``boundary_targets``' outer boundary, plus any
        interior pins); uv : (p,2) float, their targets
    method : an energy of ``deform.METHODS``
    bound : float >= 1
    stretch : (smin, smax) or None, singular-value bounds relative to the 3D geometry (sec. 6.3)
    cone : "soc" | "linf"
    cancel : object with ``is_set()``, optional (``CancelledError`` when set)

    Returns
    -------
    FixedBoundaryMap

    Raises
    ------
    InfeasibleError when no certified map was found.
    """
    from ..deform import alpha_of, bounded_with_resets
    from ..energies import jacobian_operators
    V = np.asarray(V, dtype=np.float64)
    tris = np.asarray(tris, dtype=np.int64)
    idx = np.asarray(idx, dtype=np.int64)
    uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
    nv, k = len(V), len(tris)
    scale = np.sqrt(face_areas(V, tris).sum())
    Z = local_coordinates(V / scale, tris)
    # The outer loop holds the most targets; the holes are filled (``fill_holes``).
    rings = [oriented_loop(tris, lp) for lp in loops]
    outer = int(np.argmax([np.isin(r, idx).sum() for r in rings]))
    holes = [r for i, r in enumerate(rings) if i != outer]
    Z, tris_all, n_all = fill_holes(Z, tris, nv, holes)
    ops = jacobian_operators(Z, tris_all, n_all)
    loose = np.arange(len(tris_all)) >= k
    if holes:  # the fill's energy barely counts: it only keeps the holes' images inside
        ops = dataclasses.replace(ops, area=np.where(loose, FILL_WEIGHT * ops.area, ops.area))
    c = uv.mean(axis=0)
    val = ((uv[:, 0] - c[0]) + 1j * (uv[:, 1] - c[1])) / scale
    ut = harmonic_map(Z, tris_all, n_all, [rings[outer]])
    a = ut[idx] - ut[idx].mean()
    z = np.sum(np.conj(a) * val)  # least-squares similarity: embedding -> targets
    ut = ut * (z / np.sum(np.abs(a) ** 2)) if abs(z) > 0 else ut
    st = None if stretch is None else tuple(np.asarray(stretch, float))
    lo = loose if holes else None
    w = frames_from_map(alpha_of(ops, ut))
    u, solves, _ = bounded_with_resets(ops, idx, val, w, bound, method, 1e-3, st, cone,
                                      cancel, loose=lo)
    if u is None:
        start = ut[idx]
        for t in HOMOTOPY_STEPS:
            u, n, _ = bounded_with_resets(ops, idx, (1 - t) * start + t * val, w, bound, method,
                                          1e-3, st if t == 1.0 else None, cone, cancel, loose=lo)
            solves += n
            if u is None:
                raise InfeasibleError(f"no map within C = {bound:g} reaches the boundary targets "
                                      f"(stuck at {int(100 * t)}% of the way from a circle); "
                                      "raise the bound or choose another boundary")
            w = frames_from_map(alpha_of(ops, u))
    u = u[:nv]  # the fill's centre vertices go
    out = np.column_stack([u.real * scale + c[0], u.imag * scale + c[1]])
    out[idx] = uv
    D = conformal_distortion(V, tris, out[tris])
    premises = bijectivity_premises(out, tris, loops)
    if not (np.all(D <= bound * (1 + 1e-6)) and premises.orientation_preserving):
        raise InfeasibleError(f"the fixed-boundary map did not certify within C = {bound:g} once "
                              "the pins were written back; raise the bound slightly")
    return FixedBoundaryMap(out, float(D.max()), premises, solves)
