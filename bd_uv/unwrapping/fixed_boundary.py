"""One island mapped with its outer boundary fixed on a circle, a rectangle or its pinned polygon.

Lipman 2012, section 5: an orientation-preserving map that takes the boundary one-to-one onto a
simple polygon is a bijection onto it (Theorem 5.1), also with holes once every loop's image is
simple and nested rightly (Theorem 5.2); the solve fills the holes with triangles held
orientation-preserving, so that holds by construction. ``boundary.boundary_targets`` places the
outer boundary, ``boundary.fixed_boundary_map`` minimises the energy over F_C (eqs. 4.15-4.18) with
those targets (and the island's other pins) held fixed; the caller certifies the result from its
final UVs like every island (``finish.finish``), and ``with_premises`` then checks Theorems
5.1/5.2's premises on the certified UVs (``IslandResult.bijective``).
"""
import dataclasses

import numpy as np

from ..bijectivity import bijectivity_premises
from ..boundary import SHAPES, boundary_targets, fixed_boundary_map
from ..errors import CancelledError, InfeasibleError
from ..metrics import conformal_distortion
from ..spaces import stretch_conformal_bound
from .conic_solves import Cancelled
from .margins import STORE_HEADROOM
from .problem import IslandProblem
from .bounded import RAISE_FACTOR, guaranteed_bound

BOUNDARIES = ("free",) + SHAPES
FRAMES_NAME = "harmonic"  # fixed_boundary_map's frames: the Tutte embedding, turned to the targets
# When faces with all three corners pinned force C above the bound, the first C tried is this much
# above the smallest that admits them (a solve with that face exactly on its cone is fragile).
FORCED_HEADROOM = 1.02
STRETCH_HEADROOM = 1.0 + 4 * STORE_HEADROOM


def fixed_boundary_island(island, V, pins, shape, method, bound, raise_bound, bound_limit, cone,
                          cancel, report, stretch=None):
    """Map one island with its outer boundary on ``shape``; raise C when F_C is empty.

    Parameters
    ----------
    island : mesh.Island (valid: ``island.error is None``)
    V : (n,3) float64, the whole mesh's vertices
    pins : (corners (p,), uv (p,2)), the whole mesh's pinned corners; those on the island's outer
        boundary define the rectangle's corners or the pinned polygon (``boundary_targets``) and
        are otherwise replaced by the targets; the island's other pins are kept exactly
    shape : "circle" | "rectangle" | "pinned"
    method : an energy of ``deform.METHODS`` ("lscm", "arap", "dirichlet", "biharmonic",
        "stretch-l1")
    bound : float >= 1, the conformal bound C
    raise_bound : bool, multiply C by ``bounded.RAISE_FACTOR`` while no map is found
    bound_limit : float, the largest C tried
    cone : "soc" | "linf"
    cancel : object with ``is_set()`` or None
    report : callable(fraction, message)
    stretch : float S, optional: every face's singular values within [1/S, S] relative to the 3D
        geometry (section 6.3; the target gives the scale); C is then raised up to S^2 at most

    Returns
    -------
    prob : IslandProblem whose pins are the targets and kept pins (``pin_idx`` (q,),
        ``pin_val`` (q,) complex), so that ``finish.finish`` writes them back exactly
    u : (nv,) complex, the map in UV coordinates (not normalised)
    C : float, the bound it is to be certified at
    flags : list of str: ``"bound_raised"``; ``"boundary_pins_moved"`` when pins on the outer
        boundary were placed on the circle or rectangle rather than kept at their pinned UVs

    Raises
    ------
    InfeasibleError when the targets cannot be placed or no map is found up to ``bound_limit``;
    Cancelled when cancelled.
    """
    prob = IslandProblem(island, V, pins, method, cone, cancel)
    own = np.column_stack([prob.pin_val.real, prob.pin_val.imag])
    try:
        idx, uv = boundary_targets(prob.V, island.tris, island.loops, shape,
                                   (prob.pin_idx, own) if len(prob.pin_idx) else None)
    except ValueError as exc:
        raise InfeasibleError(f"island {island.index}: boundary {shape!r}: {exc}",
                              island.index) from None
    keep = ~np.isin(prob.pin_idx, idx)  # pins inside the island or on holes stay where they are
    all_idx = np.concatenate([idx, prob.pin_idx[keep]])
    all_uv = np.concatenate([uv, own[keep]])
    C, flags = float(bound), []
    # Section 6.3 relative to the 3D geometry: the target gives the scale (circle and rectangle
    # have the island's 3D area). Solved a little inside [1/S, S] so the stored UVs still pass.
    st = None if stretch is None else (STRETCH_HEADROOM / stretch, stretch / STRETCH_HEADROOM)
    if shape != "pinned" and not keep.all():
        flags.append("boundary_pins_moved")  # on the circle/rectangle, not at their pinned UVs
    forced = forced_distortion(prob.V, island.tris, all_idx, all_uv)
    if forced > C / (1.0 + 1e-6):
        why = (f"island {island.index}: faces with all three corners on the {shape} have "
               f"distortion {forced:.4g} there, above C = {C:g}")
        C = FORCED_HEADROOM * guaranteed_bound(forced)
        if not raise_bound or C > bound_limit:
            raise InfeasibleError(why + ("; allow raising the bound" if not raise_bound else
                                         f", beyond the bound limit {bound_limit:g}")
                                  + ", or choose other corners (pins) or split those faces",
                                  island.index)
        flags.append("bound_raised")  # straight to the C those faces need, not by steps
    while True:
        if cancel is not None and cancel.is_set():
            raise Cancelled
        report(0.2, f"solving with the boundary on a {shape} at C = {C:.3g}")
        try:
            res = fixed_boundary_map(prob.V, island.tris, island.loops, all_idx, all_uv,
                                     method=method, cone=cone, cancel=cancel, stretch=st,
                                     bound=C if st is None else stretch_conformal_bound(C, *st))
            break
        except CancelledError:
            raise Cancelled from None
        except InfeasibleError as exc:
            # with S, a C above what the singular values allow (S^2) cannot help
            top = bound_limit if st is None else \
                min(bound_limit, stretch_conformal_bound(st[1] / st[0], *st))
            if st is not None and raise_bound and C >= top:
                raise InfeasibleError(f"island {island.index}: {exc} with stretch S = "
                                      f"{stretch:g} (C tried up to {C:g}, which S leaves room "
                                      "for); raise S or choose another boundary",
                                      island.index) from None
            if not raise_bound or C * RAISE_FACTOR > bound_limit:
                raise InfeasibleError(f"island {island.index}: {exc}"
                                      + ("" if not raise_bound else
                                         f" (tried up to C = {C:g}, bound limit "
                                         f"{bound_limit:g})"), island.index) from None
            C *= RAISE_FACTOR
            if "bound_raised" not in flags:
                flags.append("bound_raised")
    prob.pin_idx = all_idx
    prob.pin_val = all_uv[:, 0] + 1j * all_uv[:, 1]
    prob.solves += res.solves
    return prob, res.uv[:, 0] + 1j * res.uv[:, 1], C, flags


def forced_distortion(V, tris, idx, uv):
    """The largest conformal distortion (eq. 4.9) of the faces whose three corners are all pinned:
    a lower bound on C for any map with those pins (1 when there is no such face).

    Parameters
    ----------
    V : (nv,3) float, tris : (k,3) int, idx : (p,) int pinned vertices, uv : (p,2) their targets

    Returns
    -------
    float (inf when such a face is flat or flipped on the targets)
    """
    T = np.full((len(V), 2), np.nan)
    T[idx] = uv
    full = ~np.isnan(T[tris][..., 0]).any(axis=1)
    if not full.any():
        return 1.0
    return float(np.max(conformal_distortion(V, tris[full], T[tris[full]])))


def with_premises(result, island):
    """``result`` with ``bijective`` set from Theorems 5.1/5.2's premises on its final UVs.

    Parameters
    ----------
    result : IslandResult, certified or failed
    island : mesh.Island it came from (its ``loops``)

    Returns
    -------
    IslandResult; ``bijective`` is False for a failed island, and a certified island whose
    premises fail says which in its message
    """
    if result.status != "certified":
        return dataclasses.replace(result, bijective=False)
    p = bijectivity_premises(result.uv, result.tris, island.loops)
    msg = result.message + (", bijective onto its boundary polygon (Theorems 5.1, 5.2)"
                            if p.bijective else f"; not shown bijective: {p.message}")
    return dataclasses.replace(result, bijective=bool(p.bijective), message=msg)
