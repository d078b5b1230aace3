"""Headroom for storage: re-solve an island whose certified map fails once packed and rounded.

A conformal map can shrink faces by orders of magnitude near a cone-like point of the surface
(the Utah teapot's handle meets its body at one vertex: there the plain conformal map makes
faces about 4e-5 as large as the island's median face). Certified in float64, such a face is a
few float32 steps wide once the island is packed into the unit square: rounding its corners
moves its distortion by whole units (4.96 -> 5.36 against C = 5 on the teapot's handle).

The bound ``rounding.rounding_distortion`` says, for every face, how far its distortion can go
when each stored coordinate moves by at most ``h``. The repair :func:`with_storage_headroom`
re-solves the islands that failed as stored with a stretch limit S (every face's singular
values within [1/S, S] at the island's own scale, Lipman 2012 section 6.3; the loosest S of
:data:`STRETCH_LADDER` that certifies the island whole), so no face can collapse below 1/S of
its 3D size; :func:`stored_layout_with_headroom` wraps ``layout.stored_layout``: store, and when an
island fails as stored, re-solve it so, then pack and certify again from the stored UVs.
"""
import dataclasses

import numpy as np

from ..errors import InfeasibleError
from ..layout import stored_layout
from ..geometry import face_areas
from ..metrics import conformal_distortion, signed_uv_areas
from .margins import certified_bound
from .rounding import predicted_to_fail

#: stretch limits tried in turn, loosest first (each must be >= sqrt(C))
STRETCH_LADDER = (64.0, 16.0, 8.0, 4.0)


def solve_with_stretch(V, F, island, bound, method="lscm", ladder=STRETCH_LADDER):
    """Re-solve one certified island (its own cut topology) with the loosest stretch limit of
    ``ladder`` that certifies it whole within ``bound``.

    Returns
    -------
    (IslandResult of the sub-solve, S) or (None, None) when no S of the ladder certifies it
    """
    from .unwrap import unwrap   # unwrapping.unwrap imports nothing of this module
    Vs = np.asarray(V, dtype=np.float64)[island.vertices]
    for S in ladder:
        if S * S < bound:
            continue
        sub = unwrap(Vs, island.tris, bound=float(bound), stretch=float(S), method=method,
                     seams_mode="marked")
        if len(sub.islands) == 1 and sub.islands[0].status == "certified":
            return sub, S
        if any(isinstance(r.error, InfeasibleError) for r in sub.islands):
            break   # no map within S at this bound: none within a tighter S either
    return None, None


def with_storage_headroom(V, F, res, islands, ladder=STRETCH_LADDER):
    """``res`` with the unwrap islands ``islands`` re-solved under a stretch limit.

    Parameters
    ----------
    V : (n,3) float, F : (m,3) int
    res : UnwrapResult
    islands : iterable of int, unwrap islands (certified) that failed as stored
    ladder : stretch limits tried, loosest first

    Returns
    -------
    (UnwrapResult, dict {island: S} of the islands re-solved); islands no S certifies are left
    as they were (the caller's certificate as stored still decides what is written)
    """
    corner_uv = np.array(res.corner_uv, dtype=np.float64, copy=True)
    new_islands, done = list(res.islands), {}
    for i in sorted(set(int(i) for i in islands)):
        r = res.islands[i]
        if r.status != "certified":
            continue
        sub, S = solve_with_stretch(V, F, r, r.bound_certified, method=res.method, ladder=ladder)
        if sub is None:
            continue
        s = sub.islands[0]
        corner_uv[r.faces] = sub.corner_uv
        D = conformal_distortion(V, np.asarray(F)[r.faces], sub.corner_uv)
        new_islands[i] = dataclasses.replace(
            r, uv=s.uv, max_distortion=float(D.max()), mean_distortion=s.mean_distortion,
            distortion=D, min_singular=s.min_singular, max_singular=s.max_singular,
            solves=r.solves + s.solves, iterations=r.iterations + s.iterations,
            seconds=r.seconds + s.seconds, flags=tuple(r.flags) + (f"storage_stretch_{S:g}",),
            message=f"{r.message}; re-solved with stretch <= {S:g} so that it stays certified "
                    f"as stored")
        done[i] = S
    if not done:
        return res, done
    return dataclasses.replace(res, corner_uv=corner_uv, islands=new_islands,
                               certificates=None), done


def stored_layout_with_headroom(V, F, res, stretch=None, ladder=STRETCH_LADDER,
                                **layout_options):
    """``layout.stored_layout``, and when islands the unwrap certified fail as stored, those
    islands re-solved with headroom (:func:`with_storage_headroom`) and the whole layout packed
    and certified again before anything is left unwritten. With the caller's own ``stretch``
    limit (the unwrap already held it) nothing is re-solved: a looser one would break it.

    Returns
    -------
    (Layout, UnwrapResult the layout was made from, dict {island: S} re-solved)
    """
    layout = stored_layout(V, F, res, **layout_options)
    if stretch is not None:
        return layout, res, {}
    ok = [r.status == "certified" for r in res.islands]
    for _ in range(AUTO_TRIES):
        raised = _auto_bounds_as_stored(res, layout, ok)
        if raised is None:
            break
        res = raised
        layout = stored_layout(V, F, res, **layout_options)
    failed = {int(s) for c, s in zip(layout.certificates, layout.source)
              if not c.certified and ok[int(s)]}
    if not failed:
        return layout, res, {}
    fixed, done = with_storage_headroom(V, F, res, failed, ladder=ladder)
    if not done:
        return layout, res, done
    return stored_layout(V, F, fixed, **layout_options), fixed, done


# Layouts made again with raised bounds (``_auto_bounds_as_stored``) before the re-solve
AUTO_TRIES = 2


def _auto_bounds_as_stored(res, layout, ok):
    """``res`` with the bound of each ``bound="auto"`` island whose UVs as stored failed by the
    bound alone (no face flipped, one to one, finite) raised to what they showed, with the float32
    move counted twice over (``certified_bound`` of max + 2 x (stored max - max)), flagged
    "bound_as_stored"; None when there is none. The least C of a near-isometric piece has only
    STORE_HEADROOM (2e-4) above its max, and float32 UVs of its small faces in a large atlas move
    it further (Khronos' 2CylinderEngine: islands of 5 of its 29 meshes certified at 1.0002,
    stored at 1.00022-1.00135, not written; a graded planar disk's faces 1e-5 of it stored at
    1.038). For "auto" the bound is bd-uv's to choose, so it is raised: the next layout is
    certified against it as ever."""
    worst = {}
    for c, s in zip(layout.certificates, layout.source):
        i = int(s)
        if (not c.certified and ok[i] and res.islands[i].bound_requested == "auto"
                and c.flipped == 0 and c.overlap_free and np.isfinite(c.max_distortion)):
            worst[i] = max(worst.get(i, 1.0), float(c.max_distortion))
    if not worst:
        return None
    islands = list(res.islands)
    for i, stored in worst.items():
        r = islands[i]
        C = certified_bound(stored + 2.0 * max(stored - r.max_distortion, 0.0))
        if not C > r.bound_certified:
            return None
        flags = tuple(r.flags) + (() if "bound_as_stored" in r.flags else ("bound_as_stored",))
        islands[i] = dataclasses.replace(r, bound_certified=C, flags=flags)
    return dataclasses.replace(res, islands=islands)


def beyond_headroom(V, F, res, ladder=STRETCH_LADDER):
    """Certified islands whose texel density varies more than the loosest stretch limit could
    hold: the largest to smallest face scale (sqrt of UV over 3D area) above ``ladder[0]``
    squared. Their smallest faces get less than a texel where their largest get thousands, no
    float32 texture may hold them (``rounding.predicted_to_fail`` flags them at some packed scale),
    and a stretch re-solve would have to move the map far from itself and seldom certifies
    (measured: two 3,300-face shells of Khronos' BrainStem, spread 1e10 and 5e13, failed every S
    of the ladder in 16 s); seams serve them (``seams.needed``).

    Returns
    -------
    list of int, island indices
    """
    k = len(res.islands)
    lab = np.asarray(res.face_island, dtype=np.int64)
    ok = np.array([r.status == "certified" for r in res.islands], dtype=bool)
    use = (lab >= 0) & (lab < k)
    use[use] = ok[lab[use]]
    if not use.any():
        return []
    V = np.asarray(V, dtype=np.float64)
    faces = np.flatnonzero(use)
    a3 = face_areas(V, np.asarray(F, dtype=np.int64)[faces])
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.sqrt(np.abs(signed_uv_areas(
            np.asarray(res.corner_uv, dtype=np.float64)[faces])) / a3)
    good = np.isfinite(scale) & (a3 > 0)
    lab, scale = lab[faces][good], scale[good]
    hi = np.full(k, -np.inf)
    lo = np.full(k, np.inf)
    np.maximum.at(hi, lab, scale)
    np.minimum.at(lo, lab, scale)
    return np.flatnonzero(hi > float(ladder[0]) ** 2 * lo).tolist()


def with_predicted_headroom(V, F, res, dtype=np.float32, ladder=STRETCH_LADDER):
    """``res`` with the islands ``rounding.predicted_to_fail`` re-solved under a stretch limit
    (:func:`with_storage_headroom`), before anything is written.

    Returns
    -------
    (UnwrapResult, dict {island: S})
    """
    flagged = predicted_to_fail(V, F, res, dtype=dtype)
    if not flagged:
        return res, {}
    return with_storage_headroom(V, F, res, flagged, ladder=ladder)
