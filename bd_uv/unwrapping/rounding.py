"""How far float32 storage moves a certified map: the rounding step of a coordinate
(:func:`float_step`), a per-face bound on the distortion once every coordinate moved by it
(:func:`rounding_distortion`) and the islands whose certificate is not expected to survive
packing and rounding (:func:`predicted_to_fail`). Imports nothing that solves, so the unwrap
itself can ask (``unwrap.unwrap``'s angle start) and ``storage`` re-solves what it flags.
"""
import dataclasses

import numpy as np

from ..geometry import face_areas, gradient_operators, local_coordinates
from ..metrics import conformal_distortion, face_jacobians, signed_uv_areas, singular_values
from .margins import certified_bound


def float_step(dtype, magnitude=1.0):
    """Half the spacing of ``dtype`` numbers at ``magnitude``: the most one rounding moves a
    coordinate of that size."""
    return float(np.spacing(np.asarray(magnitude, dtype=dtype))) / 2.0


def rounding_distortion(V, F, corner_uv, h, G=None, edges=None):
    """Per-face upper bound on the conformal distortion after each UV coordinate moves by <= h.

    The Jacobian is J = U X^-1 (U: the UV edge vectors, X: the face's own 2D edge vectors). Each
    entry of U moves by at most 2h, so ||dJ||_2 <= ||dU||_F ||X^-1||_2 <= 4h / s_min(X) = e, and
    the singular values of J move by at most e (Weyl): distortion <= (s1 + e) / (s2 - e).

    Parameters
    ----------
    V : (n,3) float, F : (m,3) int, corner_uv : (m,3,2) float, h : float
    G : (m,2,3) float64, optional, the faces' ``gradient_operators(local_coordinates(V, F))``
        when known (the same bits)
    edges : ((m,3), (m,3)) float64, optional, each face's edges from its first corner when
        known (``one_disk.Disk.e01``, ``e02``: the same bits)

    Returns
    -------
    (m,) float64, inf where s2 <= e (the face may flip or collapse when rounded)
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    if G is None:
        smax, smin = singular_values(V, F, corner_uv, normalize=False)
    else:       # ``singular_values``' unnormalised answer, the same arithmetic
        alpha, beta = face_jacobians(V, F, corner_uv, G)
        a, b = np.abs(alpha), np.abs(beta)
        smax, smin = a + b, a - b
    if edges is None:
        P = V[F]
        e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    else:
        e1, e2 = edges
    # s_min of the 2x2 edge matrix X from its Gram matrix (no face loop)
    a, b, c = (e1 * e1).sum(1), (e1 * e2).sum(1), (e2 * e2).sum(1)
    root = np.sqrt(np.maximum((a - c) ** 2 + 4 * b * b, 0.0))
    smin_x = np.sqrt(np.maximum((a + c - root) / 2.0, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        e = 4.0 * h / smin_x
        low = smin - e
        out = np.where(low > 0, (smax + e) / low, np.inf)
    return out


# ``predicted_to_fail`` measures the rounded map only where ``rounding_distortion``'s bound on it
# is not this far below its certified C (the bound's own rounding is ~1e-15 of it)
WITHIN = 1e-6


def predicted_to_fail(V, F, res, dtype=np.float32, coverage=0.25, disk=None):
    """Unwrap islands whose certificate is not expected to survive packing and rounding to
    ``dtype``.

    Used where the packed scale is not known before writing (the Blender operator packs after
    it writes). Each island is placed as a packer would at one texel density, UV area =
    ``coverage`` x its 3D area / the total 3D area (``coverage`` low: a small scale, the
    pessimistic side), centred in the unit square's upper half of coordinates (where float
    steps are largest), rounded to ``dtype`` and measured; it is flagged when that exceeds its
    certified bound, or when :func:`rounding_distortion` says a face may collapse or flip
    (s_min within one rounding). Where that bound is below the certified bound (by WITHIN) and
    the placed coordinates lie in [0, 1) (each rounded by at most ``float_step(dtype, 1.0)``),
    the rounded map, within it, is not measured (the same flags; ~0.3 ms of a 1,595-face
    disk's ~1.2). The certificate of the UVs as really stored still decides what is written:
    this only chooses what to re-solve before writing.

    disk : ``one_disk.Disk`` of the mesh V, F, optional: an island of all its faces in order
        is measured with the disk's frames, areas and edges (the same bits as made here; on a
        1,112-face disk ~0.3 of the call's ~1.1 ms)

    Returns
    -------
    list of int, certified unwrap islands flagged
    """
    out = []
    for i, r, f, u, G, bound, extent in _placements(V, F, res, dtype, coverage, disk):
        if not np.logical_and.reduce(np.isfinite(bound)):
            out.append(i)
        elif not (extent < 1.0 and np.maximum.reduce(bound)
                  <= r.bound_certified * (1.0 - WITHIN)):
            # (else the stored map's distortion is within ``bound``, below its C: its
            # coordinates in [0, 1), each rounded by at most h; not measured)
            stored = u.astype(dtype).astype(np.float64)
            if conformal_distortion(V, f, stored, G).max() > r.bound_certified:
                out.append(i)
    return out


def _placements(V, F, res, dtype, coverage, disk):
    """Each certified island of ``res`` placed as :func:`predicted_to_fail` describes: yields
    (island index, IslandResult, its faces (k,3), its placed corner UVs (k,3,2), its faces'
    gradient operators, :func:`rounding_distortion`'s bound per face, its largest extent)."""
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    uv = np.asarray(res.corner_uv, dtype=np.float64)
    ok = [i for i, r in enumerate(res.islands) if r.status == "certified"]
    faces = np.concatenate([res.islands[i].faces for i in ok]) if ok else np.zeros(0, np.int64)
    whole = disk is not None and len(faces) == len(F) == len(disk.area) and np.array_equal(
        faces, disk.island.faces)
    # each face's area once (face by face: the same bits as the islands' own calls made)
    A = disk.area if whole else face_areas(V, F[faces]) if len(faces) else np.zeros(0)
    total = float(A.sum()) if len(faces) else 0.0
    if total <= 0:
        return
    h = float_step(dtype, 1.0)
    at = 0
    for i in ok:   # per island (its own UV scale), vectorised over its faces
        r = res.islands[i]
        f, u = F[r.faces], uv[r.faces]
        Af, at = A[at:at + len(f)], at + len(f)
        uv_area = float(np.abs(signed_uv_areas(u)).sum())
        if not uv_area > 0:
            continue
        u = u * (np.sqrt(Af.sum() / uv_area) * np.sqrt(coverage / total))
        lo, hi = _extent(u)
        u = u - lo + np.maximum(0.5 * (1.0 - (hi - lo)), 0.0)
        # the faces' frames, once for both (the disk's where the island is all of it)
        G, edges = ((disk.G, (disk.e01, disk.e02)) if whole else
                    (gradient_operators(local_coordinates(V, f)), None))
        yield i, r, f, u, G, rounding_distortion(V, f, u, h, G, edges), np.maximum.reduce(hi - lo)


# What a tightened ``auto`` bound keeps above the larger of its map's max and the bound on its
# distortion once placed and rounded (that bound's own arithmetic is ~1e-15 of it)
TIGHT_HEADROOM = 1e-6


def tightened(V, F, res, dtype=np.float32, coverage=0.25, disk=None):
    """``res`` with the C of each certified ``bound="auto"`` island lowered, where that is
    lower, to ``certified_bound`` of the larger of its max distortion and the most float32
    rounding can make it at :func:`predicted_to_fail`'s placement (``rounding_distortion``),
    with TIGHT_HEADROOM instead of STORE_HEADROOM: the least C its UVs as stored are expected to
    pass. STORE_HEADROOM (2e-4 of C) covers the smallest faces of large atlases; on a small,
    near-isometric disk it was more than the whole gap to the peers' maps (a 600-face patch of
    a knight: max 1.003116, C 1.003318, ABF's and LSCM's max 1.00324). Where the UVs as really
    stored measure more (a smaller packed scale), the layout raises C to what they measure
    (``storage._auto_bounds_as_stored``, the operator's ``stored.STORAGE_RTOL``). Islands placed
    wider than the unit square (rounded by more than one step), or whose bound is not finite,
    keep their C."""
    lower = {}
    for i, r, _, _, _, bound, extent in _placements(V, F, res, dtype, coverage, disk):
        if r.bound_requested != "auto" or not extent < 1.0:
            continue
        worst = float(np.maximum.reduce(bound))
        if not np.isfinite(worst):
            continue
        C = certified_bound(max(worst, float(r.max_distortion)), TIGHT_HEADROOM)
        if C < r.bound_certified:
            lower[i] = C
    if not lower:
        return res
    islands, certs = list(res.islands), res.certificates
    certs = None if certs is None else list(certs)
    for i, C in lower.items():
        r = islands[i]
        old = f"<= {r.bound_certified:.4g}"
        msg = r.message.replace(old, f"<= {C:.4g}", 1) if old in (r.message or "") else r.message
        islands[i] = dataclasses.replace(r, bound_certified=C, message=msg)
        if certs is not None and i < len(certs) and certs[i] is not None:
            certs[i] = dataclasses.replace(certs[i], bound=C)
    if certs is not None:
        certs = type(res.certificates)(certs)
    return dataclasses.replace(res, islands=islands, certificates=certs)


def _extent(corner_uv):
    """(lowest (2,), highest (2,)) of the corner UVs (m,3,2) column by column: ``min`` and
    ``max`` over the axes (0, 1), whose reduction over two axes of a (m,3,2) array cost ~0.3 ms
    of a 1,595-face disk's ~1.2 ms call, each column's reduced as one strided row (the same
    values: a min or max is exact, NaN propagated alike)."""
    flat = corner_uv.reshape(-1, 2)
    x, y = flat[:, 0], flat[:, 1]
    return (np.array([np.minimum.reduce(x), np.minimum.reduce(y)]),
            np.array([np.maximum.reduce(x), np.maximum.reduce(y)]))
