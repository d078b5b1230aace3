"""Charts shaped for the atlas (the atlas cuts): a chart the search made that alone caps the
atlas's coverage is bisected (``bisect``: a short seam along the mesh), where that measurably
pays.

A chart of 3D-area share ``a`` whose map fills ``q`` of the least square around it (over
rotations) leaves any square atlas of the charts at most ``q / a`` covered, whatever the packer
(the chart alone needs that square). Merging by the conformal test alone knows nothing of this:
on fandisk (a CAD mesh) it joined 28 charts into 3, the largest 59 % of the area in a band
filling 33 % of its square, so every packer (ours, Blender's exact shape) stopped near 0.56
while xatlas reached 0.58 on its own 114 charts.

The search's own charts cap it too: it opens Blender's torus into one band by its two handle
cuts (bound 0.33, packed 0.33 against xatlas's 0.55 on 8 charts), a cylinder's side into one
long strip. Only the chart capping the atlas (the lowest ``q / a``) is split, and only while
that bound is below ``TARGET`` (the coverage packers reach on charts of good shape), the chart is
bounded by a seam the search added (the user's islands, bounded by their seams alone, stay
whole), and both pieces pass the search's test by their own conformal maps and raise ``q / a``
by ``GAIN``; where it cannot be, no split pays and the pass stops. So a sphere's hemispheres
(``q / a`` = 1.3) and a dozen even charts stay as they are; the torus's band becomes two
(packed 0.65). Used by ``auto.unwrap_auto`` after merging (unless ``atlas_cuts=False``:
the seams the search's test needs only), so every packer gets the same charts.
"""
import numpy as np
from scipy.spatial import ConvexHull, QhullError

from .bisect import bisect
from .charts import MARGIN, chart_maps
from .topology import charts

# A chart is a candidate while its bound q / a is below this: the coverage our packer and
# Blender's exact shape reach on charts of good shape (0.64-0.71 on cow, dino, camel).
TARGET = 0.70
# A split is kept when the worse piece's bound is at least this times the chart's.
GAIN = 1.15
# Rotations tried for the least square around a chart (over 90 degrees).
ANGLES = 90
# Splits at most (each one bisection of the chart with the lowest bound).
MAX_SPLITS = 16


def square_fill(uv, tris, loop=None):
    """Area of a planar map over the area of the least square holding it (rotations only).

    Parameters
    ----------
    uv : (n,) complex128 chart vertex positions, tris : (k,3) int64
    loop : (b,) int64, optional, the boundary loop of a disk (its hull is the chart's)

    Returns
    -------
    float in (0, 1]
    """
    e1, e2 = uv[tris[:, 1]] - uv[tris[:, 0]], uv[tris[:, 2]] - uv[tris[:, 0]]
    area = 0.5 * abs(float(np.sum((e1.conjugate() * e2).imag)))
    pts = uv[loop] if loop is not None and len(loop) >= 3 else np.unique(uv[tris.ravel()])
    try:
        pts = pts[ConvexHull(np.stack([pts.real, pts.imag], 1)).vertices]
    except (QhullError, ValueError):
        pass
    turns = np.exp(-1j * np.linspace(0.0, np.pi / 2, ANGLES, endpoint=False))
    p = pts[None, :] * turns[:, None]
    side = np.maximum(np.ptp(p.real, axis=1), np.ptp(p.imag, axis=1)).min()
    return area / side ** 2 if side > 0 else 1.0


def _fill_floor(uv, tris):
    """A lower bound of ``square_fill(uv, tris)``: the map's area over the square of its
    bounding box's diagonal (no square around the map, at any rotation, is wider than that
    diagonal), a millionth under it for the rounding of either."""
    e1, e2 = uv[tris[:, 1]] - uv[tris[:, 0]], uv[tris[:, 2]] - uv[tris[:, 0]]
    area = 0.5 * abs(float(np.sum((e1.conjugate() * e2).imag)))
    d2 = float(np.ptp(uv.real)) ** 2 + float(np.ptp(uv.imag)) ** 2
    return (1.0 - 1e-6) * area / d2 if d2 > 0 else 0.0


def _passes(cm, S, cap):
    """Which charts of ``cm`` (ChartMaps) pass the search's test."""
    return (np.isfinite(cm.max_distortion) & (cm.max_stretch <= S * MARGIN)
            & (cm.crossings == 0) & (cm.mean_distortion <= cap))


def split_for_packing(V, F, E, cut, original, A, cen, S, cap, poly=None, geom=None,
                      known=None, invalid=None, chs=None):
    """Bisect the charts of ``cut`` that cap the atlas's coverage, while it pays; marks the new
    seams in ``cut`` (in place).

    Parameters
    ----------
    original : (e,) bool, the given seams: a chart bounded by no other seam is left whole
    A : (m,) face areas, cen : (m,3) face centroids (``bisect``'s)
    S, cap : stretch and mean distortion a piece's conformal map must pass (as every chart)
    poly : (m,) int64 polygon per face, optional (``bisect`` keeps polygons whole)
    known : dict, optional: maps of charts that passed (``ChartMaps.remember``); the pieces'
        maps go in, the split charts' come out
    invalid : (m,) bool, optional, faces of islands left to ``unwrap`` to report (never split)
    chs : list of topology.Chart, optional: the charts of ``cut`` (``merge.merge_charts``'s),
        else found here

    Returns
    -------
    kept : list of (bound before, worse piece's bound after) per kept split
    every : list of topology.Chart, the charts of ``cut`` after the splits (by least face)
    """
    every = charts(F, E, cut) if chs is None else chs
    chs = [c for c in every if c.kind == "disk" and len(c.faces) >= 4
           and not (invalid is not None and invalid[c.faces].any())]
    total = float(A.sum())
    if not chs or total <= 0:
        return [], every
    # Each chart's conformal map: the search's (``known``) or solved here. Only its shape counts.
    maps = [None if known is None else known.get(c.faces.tobytes()) for c in chs]
    miss = [j for j, u in enumerate(maps) if u is None]
    if miss:
        cm = chart_maps(V, [chs[j] for j in miss], geom)
        for k, j in enumerate(miss):
            maps[j] = cm.uv[cm.voff[k]:cm.voff[k + 1]]
    inner = E.faces[:, 1] >= 0

    def bound(c, u):
        return square_fill(u, c.tris, c.loops[0]) / (float(A[c.faces].sum()) / total)

    live = []                               # (bound, chart, may it be split)
    for j, c in enumerate(chs):
        # A chart whose bound is surely at least TARGET is never split and never stops the
        # pass before a chart below TARGET would (the pass takes the lowest bound first and
        # stops at TARGET): left out, without its hull and rotations (``square_fill``).
        if _fill_floor(maps[j], c.tris) / (float(A[c.faces].sum()) / total) >= TARGET:
            continue
        fe = np.unique(E.face_edges[c.faces].ravel())
        fe = fe[inner[fe]]
        # Only a chart bounded by a seam the search added: the user's islands stay as they are.
        free = bool((cut[fe] & ~original[fe]).any())
        live.append((bound(c, maps[j]), c, free))
    kept = []
    while live and len(kept) < MAX_SPLITS:
        # The chart capping the atlas: where it cannot be split, no split pays.
        i = min(range(len(live)), key=lambda k: (round(live[k][0], 9), int(live[k][1].faces[0])))
        b, c, free = live.pop(i)
        if b >= TARGET or not free:
            break
        trial = cut.copy()
        if bisect([c.faces], E, trial, A, cen, poly)[0] is None:
            break
        pieces = charts(F, E, trial, c.faces)
        if len(pieces) != 2 or any(p.kind != "disk" for p in pieces):
            break
        pm = chart_maps(V, pieces, geom, limits=(S * MARGIN, cap))
        if not _passes(pm, S, cap).all():
            break
        after = [bound(p, pm.uv[pm.voff[k]:pm.voff[k + 1]]) for k, p in enumerate(pieces)]
        if min(after) < GAIN * b:
            break
        cut[:] = trial
        every = sorted([x for x in every if x is not c] + pieces, key=lambda x: int(x.faces[0]))
        kept.append((b, min(after)))
        if known is not None:
            known.pop(c.faces.tobytes(), None)
            pm.remember(pieces, np.ones(2, dtype=bool), known)
        live += [(a, p, True) for a, p in zip(after, pieces)]
    return kept, every


def atlas_cuts_of(info, vertices=None):
    """``UnwrapResult.atlas_cuts`` of ``unwrap_auto``'s ``info``: ``cuts``, ``length`` and
    ``seams`` (vertex pairs, renumbered through ``vertices`` when the search ran on a subset)."""
    seams = info["atlas_seams"]
    if vertices is not None and len(seams):
        seams = np.sort(np.asarray(vertices)[seams], axis=1)
    return {"cuts": info["atlas_cuts"], "length": info["atlas_length"],
            "seams": np.asarray(seams, np.int64).reshape(-1, 2)}
