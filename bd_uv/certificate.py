"""One certificate per island, measured from its UVs as stored; every write path uses it.

An island is certified when its map has no flipped face, its conformal distortion is at most its
bound C everywhere (Lipman 2012, eq. 4.9), and it is one-to-one: its UV boundary curves are simple,
disjoint and wound the right way (Theorems 5.1 and 5.2, see :mod:`bd_uv.overlap`).
"""
from dataclasses import dataclass

import numpy as np

from .geometry import face_areas
from .metrics import conformal_distortion, flipped_faces
from .overlap import island_overlaps
from .trim import CHUNK, release_memory

# Same relative tolerance as metrics.certify: the bound is met up to rounding.
RTOL = 1e-6
# an island narrower than this (UV units) that fails certification is named too small in its reason:
# measures at that scale fall below what the overlap test and float32 storage resolve
TINY = 2.0 ** -20


@dataclass(frozen=True)
class Certificate:
    """What one island's stored UVs prove.

    Attributes
    ----------
    island : int
    certified : bool, ``flipped == 0 and max_distortion <= bound and overlap_free``
    bound : float, the C it is checked against
    max_distortion : float (inf when a face is flipped, collapsed or has non-finite UVs)
    mean_distortion : float, area-weighted over the island's faces with finite distortion
    flipped : int, faces with signed UV area <= 0 (or non-finite UVs)
    overlap_free : bool, the island is one-to-one in UV (False when a face has non-finite UVs:
        never placed, never proven)
    crossings : int, pairs of crossing boundary edges (0 when overlap_free)
    reason : str, "" when certified, else what failed, in words
    faces : int, number of faces
    area : float, 3D area of the faces with finite distortion (weights the mean across islands)
    min_singular, max_singular : float, the smallest and largest singular value of the faces'
        maps (Lipman 2012, eqs. 4.7-4.8) when a stretch bound was checked too, else NaN
    failed_as_solved : bool, for a certificate of UVs as stored (float32, packed) that fails:
        the UVs as solved (float64, before packing) fail too, so storing did not break them
    """
    island: int
    certified: bool
    bound: float
    max_distortion: float
    mean_distortion: float
    flipped: int
    overlap_free: bool
    crossings: int
    reason: str
    faces: int = 0
    area: float = 0.0
    min_singular: float = float("nan")
    max_singular: float = float("nan")
    failed_as_solved: bool = False

    def summary(self):
        """JSON-ready dict (no NaN or inf: those become None)."""
        def num(v):
            return None if v is None or not np.isfinite(v) else float(v)
        return {"island": int(self.island), "certified": bool(self.certified),
                "bound": num(self.bound), "max_distortion": num(self.max_distortion),
                "mean_distortion": num(self.mean_distortion), "flipped": int(self.flipped),
                "overlap_free": bool(self.overlap_free), "crossings": int(self.crossings),
                "faces": int(self.faces), "reason": self.reason}


def _measure_faces(V, F, uv, faces):
    """Conformal distortion and flipped-or-not of ``faces`` (``D = inf`` where a UV is not
    finite), ``CHUNK`` faces at a time: every face's numbers are its own, and the temporaries
    of a 500k-face layout (local frames, gradients, float64 UV copies: ~150 MB) stay a chunk's."""
    D = np.empty(len(faces))
    flip = np.empty(len(faces), dtype=bool)
    for i in range(0, len(faces), CHUNK):
        f = faces[i:i + CHUNK]
        uv64 = uv.take(f, axis=0).astype(np.float64)    # (rows: ``take``, ~4x cheaper)
        finite = np.isfinite(uv64).all(axis=(1, 2))
        with np.errstate(invalid="ignore", over="ignore"):
            if finite.all():
                D[i:i + CHUNK] = conformal_distortion(V, F[f], uv64)
            else:
                D[i:i + CHUNK] = np.where(finite, conformal_distortion(V, F[f], np.where(
                    finite[:, None, None], uv64, 0.0)), np.inf)
            flip[i:i + CHUNK] = flipped_faces(V, F[f], uv64) | ~finite
    return D, flip


def certify_islands(V, F, corner_uv, face_island, bounds, rtol=RTOL):
    """Certify every island of a layout from its UVs as stored.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array
    corner_uv : (m,3,2) float array, UVs as stored (float32 allowed; measured in float64)
    face_island : (m,) int array, island per face, -1 for faces of no island
    bounds : (k,) float array, the bound C of each island (k islands, labels 0..k-1)
    rtol : float, relative tolerance on the bound

    Returns
    -------
    list of Certificate, one per island in label order
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    uv = np.asarray(corner_uv).reshape(len(F), 3, 2)
    lab = np.asarray(face_island, dtype=np.int64).reshape(-1)
    bounds = np.asarray(bounds, dtype=np.float64).reshape(-1)
    k = len(bounds)
    lab = np.where(lab < k, lab, -1)
    faces = np.flatnonzero(lab >= 0)
    fl = lab[faces]
    D, flip = _measure_faces(V, F, uv, faces)
    n_faces = np.bincount(fl, minlength=k)
    n_flip = np.bincount(fl, weights=flip, minlength=k).astype(np.int64)
    maxD = np.full(k, -np.inf)
    np.maximum.at(maxD, fl, D)
    maxD[n_faces == 0] = np.nan
    A = np.concatenate([face_areas(V, F[faces[i:i + CHUNK]])
                        for i in range(0, len(faces), CHUNK)]) if len(faces) else np.zeros(0)
    ok_d = np.isfinite(D) & np.isfinite(A)
    wsum = np.bincount(fl[ok_d], weights=A[ok_d], minlength=k)
    dsum = np.bincount(fl[ok_d], weights=(A * D)[ok_d], minlength=k)
    with np.errstate(invalid="ignore", divide="ignore"):
        meanD = np.where(wsum > 0, dsum / wsum, np.inf)
    D = flip = A = ok_d = None              # per face, not held through the overlap test
    # The distortion pass's freed chunks, handed back before the boundary's arrays (on a
    # 500k-face mesh the freed heap stayed resident under the overlap test: the seam search's
    # last memory peak).
    release_memory(len(F))
    ov = island_overlaps(F, uv, lab, k)
    width = None        # measured only to word a failure (``_island_widths``)
    certs = []
    for i in range(k):  # one small record per island, no per-face work
        why = []
        if n_faces[i] == 0:
            why.append("no faces with UVs")
        if n_flip[i]:
            why.append(f"{n_flip[i]} flipped or collapsed face(s)")
        if not n_flip[i] and n_faces[i] and not maxD[i] <= bounds[i] * (1.0 + rtol):
            why.append(f"max distortion {maxD[i]:.6g} > bound {bounds[i]:.6g}")
        if ov.crossings[i]:
            why.append(f"the UV boundary crosses itself ({ov.crossings[i]} crossing(s))")
        elif ov.bad_loops[i]:
            why.append(f"{ov.bad_loops[i]} UV boundary loop(s) wound the wrong way (a hole "
                       "outside its island, or the island lying over itself)")
        if why and width is None:
            width = _island_widths(uv[faces].astype(np.float64), fl, k)
        if why and width[i] < TINY:
            why.append(f"the island is {width[i]:.2g} of the UV square across, too small to "
                       "measure: raise the texel density")
        overlap_free = bool(ov.overlap_free[i] and n_faces[i] > 0)   # a bool, not np.bool_
        certs.append(Certificate(
            island=i, certified=not why, bound=float(bounds[i]), max_distortion=float(maxD[i]),
            mean_distortion=float(meanD[i]), flipped=int(n_flip[i]), overlap_free=overlap_free,
            crossings=int(ov.crossings[i]), reason="; ".join(why), faces=int(n_faces[i]),
            area=float(wsum[i])))
    return certs


def _island_widths(uv64, fl, k):
    """(k,) float64, each island's larger UV extent over its finite corners (0 when none)."""
    P = uv64.reshape(-1, 2)
    own = np.repeat(fl, 3)
    keep = np.isfinite(P).all(axis=1)
    lo = np.full((k, 2), np.inf)
    hi = np.full((k, 2), -np.inf)
    np.minimum.at(lo, own[keep], P[keep])
    np.maximum.at(hi, own[keep], P[keep])
    with np.errstate(invalid="ignore"):
        return np.nan_to_num((hi - lo).max(axis=1), nan=0.0, neginf=0.0, posinf=np.inf)


def certificate_totals(certs):
    """Figures over many islands, for summary lines and captions.

    Returns
    -------
    dict: islands, certified, overlapping (islands not overlap-free), flipped, faces (of certified
    islands), and over the certified islands max_distortion, bound and the area-weighted
    mean_distortion (None when no island is certified)
    """
    ok = [c for c in certs if c.certified]
    area = sum(c.area for c in ok)
    return {"islands": len(certs), "certified": len(ok),
            "overlapping": sum(not c.overlap_free for c in certs),
            "flipped": sum(c.flipped for c in certs), "faces": sum(c.faces for c in ok),
            "max_distortion": max((c.max_distortion for c in ok), default=None),
            "bound": max((c.bound for c in ok), default=None),
            "mean_distortion": (sum(c.area * c.mean_distortion for c in ok) / area
                                if ok and area > 0 else None)}
