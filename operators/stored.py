"""The post-write check every Blender write path runs on what it stored (issue 10).

The operator (``uv.bd_unwrap``, both paths) and ``scripts/bd_uv_batch.py`` write float32 UVs and
may pack them; the certificate of the solve (float64, before packing) says nothing about what is
stored. :func:`check_stored` certifies each written island again from the UVs as read back, with
that island's own bound, through the core's one certificate function
(``bd_uv.certificate.certify_islands``): no flipped face, max conformal distortion <= C (Lipman
2012, eq. 4.9) and, where the core checks it, an overlap-free boundary. The callers put back every
island that fails and report these figures, never the solve's.

No ``bpy``: numpy and ``bd_uv`` only, so the same code serves the operator and the batch script.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import bd_uv

try:  # the core's one certificate (issue 10); absent from cores that predate it
    from ..bd_uv.certificate import certify_islands as _core_certify
except ImportError:  # pragma: no cover - exercised only with an older core
    _core_certify = None

__all__ = ["STORAGE_RTOL", "StoredIsland", "certify_islands", "check_stored"]

# Minimise only: an island certified at the exact float64 maximum of its solve measures up to
# ~1e-5 more once its UVs are rounded to float32 (and up to ~1e-4 after packing scales a small
# island; measured on Suzanne's 100 Smart-UV islands). Below this much above the solve's C the
# island is kept and certified at what it measures as stored: with no C asked for, that IS its
# certificate. Above it the stored UVs truly differ from the solved ones and the island is put back.
STORAGE_RTOL = 1e-4


@dataclass(frozen=True)
class _Figures:
    """What :func:`certify_islands` returns per island when the core has no certificate module
    (the same attribute names as ``bd_uv.certificate.Certificate``)."""

    island: int
    certified: bool
    bound: float
    max_distortion: float
    mean_distortion: float
    flipped: int
    overlap_free: object
    crossings: int
    reason: str


def _measure(V, F, corner_uv, face_island, bounds):
    """Flips, max and area-weighted mean distortion per island (no overlap check).

    Parameters
    ----------
    V : (n,3) float, F : (m,3) int, corner_uv : (m,3,2) float, face_island : (m,) int (-1 = not
    part), bounds : (k,) float

    Returns
    -------
    list of _Figures, one per label 0..k-1
    """
    k = len(bounds)
    part = face_island >= 0
    lab = face_island[part]
    D = bd_uv.conformal_distortion(V, F[part], corner_uv[part])
    flips = bd_uv.flipped_faces(V, F[part], corner_uv[part])
    P = np.asarray(V, np.float64)[F[part]]
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    worst = np.full(k, -np.inf)
    np.maximum.at(worst, lab, np.where(np.isnan(D), np.inf, D))
    n_flip = np.bincount(lab, weights=flips, minlength=k).astype(np.int64)
    finite = np.isfinite(D)
    w = np.bincount(lab[finite], weights=area[finite], minlength=k)
    s = np.bincount(lab[finite], weights=(area * D)[finite], minlength=k)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(w > 0, s / w, np.inf)
    out = []
    for i in range(k):
        ok = n_flip[i] == 0 and worst[i] <= bounds[i]
        reason = "" if ok else (f"{n_flip[i]} flipped faces" if n_flip[i] else
                                f"max distortion {worst[i]:.6g} > C = {bounds[i]:.6g}")
        out.append(_Figures(i, bool(ok), float(bounds[i]), float(worst[i]), float(mean[i]),
                            int(n_flip[i]), None, 0, reason))
    return out


def certify_islands(V, F, corner_uv, face_island, bounds):
    """Certificates of islands ``0..len(bounds)-1`` of a stored layout.

    The core's ``bd_uv.certificate.certify_islands`` (flips, distortion, overlap); with a core
    that predates it, flips and distortion only (``overlap_free`` is None: not checked).
    Module-level so a test can substitute a failing check.
    """
    bounds = np.asarray(bounds, dtype=np.float64)
    if _core_certify is not None:
        return _core_certify(V, F, corner_uv, face_island, bounds)
    return _measure(V, F, corner_uv, face_island, bounds)


@dataclass(frozen=True)
class StoredIsland:
    """The post-write figures of one island, measured from its UVs as stored.

    Attributes
    ----------
    island : int
        Index of the island in the unwrap result.
    certified : bool
        Passes the certificate as stored (else it must be put back).
    bound : float
        The C it is certified at as stored: the solve's ``bound_certified``, or for a minimised
        island the stored max when float32 rounding put it just above (see ``STORAGE_RTOL``).
    max_distortion, mean_distortion : float
        As stored; the mean is area-weighted over the island's 3D faces.
    flipped : int
    overlap_free : bool or None
        None when not checked.
    reason : str
        Why it fails, "" when certified.
    """

    island: int
    certified: bool
    bound: float
    max_distortion: float
    mean_distortion: float
    flipped: int
    overlap_free: object
    reason: str


def check_stored(V, F, corner_uv, face_island, islands):
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

    Returns
    -------
    list of StoredIsland
        One per written island, in increasing island index.
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
        again = certify_islands(V, F, corner_uv, compact, bounds2)
        for j in retry:
            certs[j] = again[j]
        bounds = bounds2
    return [StoredIsland(int(labels[j]), bool(c.certified), float(bounds[j]),
                         float(c.max_distortion), float(c.mean_distortion), int(c.flipped),
                         c.overlap_free, str(c.reason or ""))
            for j, c in enumerate(certs)]


def layout_overlaps(corner_uv, face_island):
    """Pairs of islands whose stored UVs overlap (the core's check), or None when the core
    cannot check it.

    Parameters
    ----------
    corner_uv : (m,3,2) float, face_island : (m,) int (-1 = not part)
    """
    try:
        from ..bd_uv.certificate import layout_overlaps as core
    except ImportError:  # pragma: no cover - older core
        return None
    return core(np.asarray(corner_uv, dtype=np.float64), np.asarray(face_island, np.int64))
