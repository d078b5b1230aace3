"""Pack islands into the unit square: one common scale (relative texel density kept), no rotation.

A shelf packer on the islands' bounding boxes, tallest first; the strip width is chosen among a few
candidates around the square root of the boxes' total area, and the one giving the smallest square
wins. The loop runs over islands (hundreds), never over faces. Packing moves an island by a
translation and the common scale only, so its distortion and overlap certificate are unchanged up
to rounding (conformal distortion is scale-invariant, Lipman 2012 eq. 4.9).
"""
import numpy as np

from .errors import OptionError

MARGIN = 0.005  # gap between islands and to the square's edge, in the unit square's units


def island_boxes(corner_uv, face_island, n_islands=None):
    """Bounding box of each island.

    Parameters
    ----------
    corner_uv : (m,3,2) float array
    face_island : (m,) int array (-1: no island); faces with non-finite UVs are ignored
    n_islands : int, optional

    Returns
    -------
    lo, hi : (k,2) float64 (inf / -inf for islands with no finite face)
    """
    uv = np.asarray(corner_uv, dtype=np.float64).reshape(-1, 3, 2)
    lab = np.asarray(face_island, dtype=np.int64).reshape(-1)
    k = int(lab.max()) + 1 if n_islands is None and len(lab) else int(n_islands or 0)
    use = (lab >= 0) & np.isfinite(uv).all(axis=(1, 2))
    lo = np.full((k, 2), np.inf)
    hi = np.full((k, 2), -np.inf)
    np.minimum.at(lo, lab[use], uv[use].min(axis=1))
    np.maximum.at(hi, lab[use], uv[use].max(axis=1))
    return lo, hi


def _shelves(w, h, width, gap):
    """Shelf positions (k,2) of boxes (w, h) in a strip of ``width``; returns (pos, used w, h)."""
    order = np.argsort(-h, kind="stable")
    pos = np.zeros((len(w), 2))
    x, y, shelf, used = gap, gap, 0.0, 0.0
    for i in order:  # per island
        if x > gap and x + w[i] + gap > width:
            x, y, shelf = gap, y + shelf + gap, 0.0
        pos[i] = (x, y)
        x += w[i] + gap
        used = max(used, x)
        shelf = max(shelf, h[i])
    return pos, used, y + shelf + gap


def _layout(w, h, gap):
    """Best shelf layout over a few strip widths: (pos, side)."""
    area = float(np.sum((w + gap) * (h + gap)))
    widest = float(w.max()) + 2 * gap
    best = None
    for f in (0.9, 1.0, 1.1, 1.25, 1.4, 1.6, 2.0):
        pos, used, height = _shelves(w, h, max(widest, f * np.sqrt(area) + gap), gap)
        side = max(used, height)
        if best is None or side < best[1]:
            best = (pos, side)
    return best


def pack_islands(corner_uv, face_island, margin=MARGIN):
    """Pack every island into [0,1]^2 with one common scale, ``margin`` apart.

    Parameters
    ----------
    corner_uv : (m,3,2) float array
    face_island : (m,) int array, island per face (-1: not packed, left as it is)
    margin : float, gap between islands and to the square's edge (unit-square units), >= 0

    Returns
    -------
    packed : (m,3,2) float64, the packed UVs (faces of no island, or with non-finite UVs, as given)
    """
    uv = np.asarray(corner_uv, dtype=np.float64).reshape(-1, 3, 2)
    lab = np.asarray(face_island, dtype=np.int64).reshape(-1)
    out = uv.copy()
    if not len(lab) or lab.max() < 0:
        return out
    if not 0 <= margin < 0.25:
        raise OptionError("margin", f"margin must be in [0, 0.25), got {margin!r}")
    lo, hi = island_boxes(uv, lab)
    live = np.flatnonzero(np.isfinite(lo).all(axis=1))
    if not len(live):
        return out
    size = np.maximum(hi[live] - lo[live], 0.0)
    ref = float(np.sqrt(np.sum(size[:, 0] * size[:, 1]))) or float(size.max()) or 1.0
    w, h = size[:, 0] / ref, size[:, 1] / ref          # normalised: total box area about 1
    w, h = np.maximum(w, 1e-12), np.maximum(h, 1e-12)
    scale = 1.0
    for _ in range(30):  # the gap in box units depends on the scale it yields: fixed point
        gap = margin / scale
        pos, side = _layout(w, h, gap)
        new = 1.0 / side
        if abs(new - scale) <= 1e-9 * new:
            break
        scale = new
    gap = margin / scale
    pos, side = _layout(w, h, gap)
    s = min(scale, 1.0 / side)  # never spill out of the square (the gap shrinks a hair instead)
    shift = np.full((len(lo), 2), np.nan)
    shift[live] = pos * s - lo[live] / ref * s
    sel = (lab >= 0) & np.isfinite(uv).all(axis=(1, 2)) & np.isin(lab, live)
    out[sel] = uv[sel] / ref * s + shift[lab[sel]][:, None, :]
    return out
