"""Room beside pinned charts: the largest empty square of the unit square that keeps a margin to
every pinned chart's bounding box. ``pack_islands`` with ``pinned`` packs the charts that move
into the free space around the pinned charts' shapes (:mod:`.around`), and into this square
instead only when it reaches a higher density; the pinned ones keep their UVs bit for bit."""
import numpy as np


def chart_boxes(corner_uv, face_island, charts):
    """Bounding boxes of the given charts: lo, hi (c,2) float64."""
    lab = np.asarray(face_island, dtype=np.int64)
    lo = np.full((len(charts), 2), np.inf)
    hi = np.full((len(charts), 2), -np.inf)
    where = np.full(int(lab.max()) + 1, -1)
    where[charts] = np.arange(len(charts))
    sel = (lab >= 0) & (where[np.maximum(lab, 0)] >= 0)
    np.minimum.at(lo, where[lab[sel]], corner_uv[sel].min(axis=1))
    np.maximum.at(hi, where[lab[sel]], corner_uv[sel].max(axis=1))
    return lo, hi


def free_square(lo, hi, margin):
    """The largest square in [0,1]^2 at least ``margin`` from every box (lo, hi), its corners
    taken at 0 or ``margin`` past a box's high side.

    Parameters
    ----------
    lo, hi : (b,2) float arrays, the boxes
    margin : float

    Returns
    -------
    corner : (2,) float64, side : float (0 when there is no room)
    """
    blo, bhi = lo - margin, hi + margin
    xs = np.concatenate([[0.0], bhi[:, 0]])
    ys = np.concatenate([[0.0], bhi[:, 1]])
    x, y = (a.ravel() for a in np.meshgrid(xs, ys, indexing="ij"))
    side = np.minimum(1.0 - x, 1.0 - y)
    below = (x[:, None] < bhi[None, :, 0]) & (y[:, None] < bhi[None, :, 1])
    room = np.maximum(blo[None, :, 0] - x[:, None], blo[None, :, 1] - y[:, None])
    side = np.minimum(side, np.where(below, np.maximum(room, 0.0), np.inf).min(axis=1))
    best = int(np.argmax(side))
    return np.array([x[best], y[best]]), float(max(side[best], 0.0))
