"""The post-write check every Blender write path runs on what it stored (issue 10).

The operator (``uv.bd_unwrap``, both paths) and ``scripts/bd_uv_batch.py`` write float32 UVs and
may pack them; the certificate of the solve (float64, before packing) says nothing about what is
stored. :func:`check_stored` certifies each written island again from the UVs as read back, with
that island's own bound, through the core's one certificate function
(``bd_uv.certificate.certify_islands``): no flipped face, max conformal distortion <= C (Lipman
2012, eq. 4.9) and an overlap-free UV boundary (Theorems 5.1, 5.2). The callers put back every
island that fails and report these figures, never the solve's.

No ``bpy``: numpy and ``bd_uv`` only, so the same code serves the operator and the batch script.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ..bd_uv.certificate import RTOL, Certificate
from ..bd_uv.certificate import certify_islands as _core_certify
from ..bd_uv.geometry import face_areas
from ..bd_uv.metrics import face_jacobians, signed_uv_areas
from ..bd_uv.overlap import layout_overlaps as _core_layout_overlaps

__all__ = ["STORAGE_RTOL", "certify_islands", "check_stored", "layout_overlaps", "tiles_off",
           "island_singular_values"]

# Minimise only: an island certified at the exact float64 maximum of its solve measures a little
# more once its UVs are rounded to float32 (Suzanne's 100 Smart-UV islands with the core before
# issue 10: 93 islands above their C by up to 1.2e-6 unpacked, 98 by up to 1.6e-5 packed). Up to
# this much above the solve's C the island is kept and certified at what it measures as stored:
# with no C asked for, that IS its certificate. Beyond it the stored UVs truly differ from the
# solved ones and the island is put back. The core certifies a minimised island only as far
# above its max as float32 rounding can take it at a pessimistic packed scale
# (``bd_uv.unwrapping.rounding.tightened``; before, 2e-4 of C above it, with 1e-4 here): 3e-4 keeps
# at least the room an island had before where Blender packs it at a smaller scale still.
STORAGE_RTOL = 3e-4


def certify_islands(V, F, corner_uv, face_island, bounds):
    """Certificates of islands ``0..len(bounds)-1`` of a stored layout: the core's one
    certificate, ``bd_uv.certificate.certify_islands`` (flips, distortion, overlap-free UV
    boundary). Module-level so a test can substitute a failing check.
    """
    return _core_certify(V, F, corner_uv, face_island, np.asarray(bounds, dtype=np.float64))


def _certify_some(V, F, corner_uv, labels, some, bounds):
    """Certificates of the islands ``some`` (list of labels) only, in that order: they are
    relabelled 0..len(some)-1 so the certificate sees no island without faces."""
    new = np.full(len(bounds) + 1, -1, dtype=np.int64)  # the last entry: label -1 stays -1
    new[some] = np.arange(len(some))
    return certify_islands(V, F, corner_uv, new[labels], np.asarray(bounds)[some])


def island_singular_values(V, F, corner_uv, face_island, n, normalized):
    """Smallest and largest singular value of the faces' maps, per island (Lipman 2012, eqs.
    4.7-4.8: ``gamma = |alpha| - |beta|``, ``Gamma = |alpha| + |beta|``).

    Parameters
    ----------
    V : (n_v,3) float, F : (m,3) int, corner_uv : (m,3,2) float
    face_island : (m,) int
        Island of each face, -1 for faces left out.
    n : int
        Number of islands.
    normalized : (n,) bool
        Islands measured at their own scale (UV area scaled to their 3D area, as the core does
        for islands with fewer than two pinned vertices: packing scales them); the others against
        the 3D geometry.

    Returns
    -------
    lo, hi : (n,) float64
        ``min gamma`` and ``max Gamma`` over each island's faces (NaN for an island without
        faces; ``lo`` is negative when a face is flipped).
    """
    face_island = np.asarray(face_island, dtype=np.int64)
    on = face_island >= 0
    lab = face_island[on]
    alpha, beta = face_jacobians(V, F[on], np.asarray(corner_uv, np.float64)[on])
    a, b = np.abs(alpha), np.abs(beta)
    area3d = np.bincount(lab, weights=face_areas(V, F[on]), minlength=n)
    area_uv = np.bincount(lab, weights=np.abs(signed_uv_areas(corner_uv[on])), minlength=n)
    lo = np.full(n, np.inf)
    hi = np.full(n, -np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):  # a collapsed island measures NaN
        scale = np.where(np.asarray(normalized, bool), np.sqrt(area3d / area_uv), 1.0)
        np.minimum.at(lo, lab, (a - b) * scale[lab])
        np.maximum.at(hi, lab, (a + b) * scale[lab])
    empty = np.bincount(lab, minlength=n) == 0
    lo[empty] = hi[empty] = np.nan
    return lo, hi


def check_stored(V, F, corner_uv, face_island, islands, solved_uv=None, stretch=None,
                 normalized=None) -> list[Certificate]:
    """Certify each island of a stored layout with its own bound (float32 UVs, after packing).

    Parameters
    ----------
    V : (n,3) float
        Positions the islands were solved for (object scale applied).
    F : (m,3) int
    corner_uv : (m,3,2) float
        UVs as read back from the UV map.
    face_island : (m,) int
        Island index (into the unwrap result) of each face; -1 for faces not written.
    islands : sequence of IslandResult
        The unwrap result's islands (indexed by island index); each written island is checked
        against its own ``bound_certified``.
    solved_uv : (m,3,2) float, optional
        The UVs as solved (float64, before packing). An island that fails as stored is checked
        on them too, to tell whether storing (float32, packing) broke it or it failed already.
    stretch : float S, optional
        Limit Stretch: an island is certified only with every face's singular values in
        [1/S, S] (Lipman 2012, section 6.3), measured as the core measures them.
    normalized : (len(islands),) bool, optional
        Islands whose singular values are measured at their own scale (see
        :func:`island_singular_values`); all by default.

    Returns
    -------
    list of bd_uv.Certificate
        One per written island, in increasing island index, its ``island`` the index in the
        unwrap result; ``bound`` the C it is certified at as stored (the solve's
        ``bound_certified``, or for a minimised island the stored max when float32 rounding put
        it just above, see ``STORAGE_RTOL``); ``min_singular``, ``max_singular`` measured as the
        core measures them; ``failed_as_solved`` when it fails on ``solved_uv`` already.
    """
    corner_uv = np.asarray(corner_uv, dtype=np.float64)
    face_island = np.asarray(face_island, dtype=np.int64)
    labels, compact = np.unique(face_island, return_inverse=True)
    compact = compact.reshape(-1)
    if len(labels) and labels[0] < 0:
        labels, compact = labels[1:], compact - 1
    if not len(labels):
        return []
    solved = [islands[int(i)] for i in labels]
    bounds = np.array([float(r.bound_certified) for r in solved])
    certs = list(certify_islands(V, F, corner_uv, compact, bounds))
    # Minimise: no C was asked for, so an island a hair above its solve's C, only from storage,
    # is certified at what it measures; anything more is a true failure.
    auto = np.array([r.bound_requested == "auto" for r in solved])
    retry = [j for j, c in enumerate(certs)
             if not c.certified and auto[j] and c.flipped == 0 and c.overlap_free is not False
             and np.isfinite(c.max_distortion)
             and c.max_distortion <= bounds[j] * (1 + STORAGE_RTOL)]
    if retry:
        bounds2 = bounds.copy()
        bounds2[retry] = [np.nextafter(certs[j].max_distortion, np.inf) for j in retry]
        for j, c in zip(retry, _certify_some(V, F, corner_uv, compact, retry, bounds2)):
            certs[j] = c
        bounds = bounds2
    failing = [j for j, c in enumerate(certs) if not c.certified]
    as_solved = set()
    if failing and solved_uv is not None:
        before = _certify_some(V, F, np.asarray(solved_uv, dtype=np.float64), compact, failing,
                               bounds)
        as_solved = {j for j, c in zip(failing, before) if not c.certified}
    norm = np.ones(len(labels), bool) if normalized is None else \
        np.asarray(normalized, bool)[labels]
    lo, hi = island_singular_values(V, F, corner_uv, compact, len(labels), norm)
    out = []
    for j, c in enumerate(certs):
        ok, reason = bool(c.certified), str(c.reason or "")
        if ok and stretch is not None and not (lo[j] >= (1.0 - RTOL) / stretch
                                               and hi[j] <= stretch * (1.0 + RTOL)):
            ok, reason = False, (f"singular values {lo[j]:.6g} to {hi[j]:.6g} outside "
                                 f"[{1.0 / stretch:.6g}, {stretch:g}]")
        out.append(dataclasses.replace(
            c, island=int(labels[j]), certified=ok, bound=float(bounds[j]), reason=reason,
            failed_as_solved=j in as_solved, min_singular=float(lo[j]), max_singular=float(hi[j])))
    return out


def layout_overlaps(corner_uv, face_island, F):
    """Pairs of islands of a stored layout that overlap each other (the core's
    ``bd_uv.overlap.layout_overlaps``).

    Parameters
    ----------
    corner_uv : (m,3,2) float, face_island : (m,) int (-1 = not part), F : (m,3) int

    Returns
    -------
    (k,2) int64 island pairs (a < b), labels as in ``face_island``
    """
    return _core_layout_overlaps(np.asarray(corner_uv, dtype=np.float64),
                                 np.asarray(face_island, np.int64), F=np.asarray(F, np.int64))


def tiles_off(kept_uv, back_uv):
    """Whole UV tiles (int >= 0) to move ``back_uv`` (k,2) right by so that it no longer lies
    over ``kept_uv`` (j,2): 0 when their bounding boxes do not overlap. A shift by whole tiles
    samples a repeating texture exactly as before."""
    if not len(kept_uv) or not len(back_uv):
        return 0
    klo, khi = kept_uv.min(axis=0), kept_uv.max(axis=0)
    blo, bhi = back_uv.min(axis=0), back_uv.max(axis=0)
    if np.any(bhi <= klo) or np.any(khi <= blo):
        return 0
    return max(1, int(np.ceil(khi[0] - blo[0])))
