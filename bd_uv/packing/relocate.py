"""Small charts that bound a compacted square moved into the free space deepest inside it.

The compaction (:mod:`.compact`) stops at a local optimum: every chart it could move is pressed
against its neighbours, and the square's side is held by the charts against its edges. Some of
those are small, while holes and pockets of the large charts' concave sides stay empty inside
the square. Moving such a chart into the free spot farthest from the square's edges frees that
edge, and the compaction then goes on from the new layout (measured on cow's compacted layouts,
seeds 0-2: 0.690 / 0.698 / 0.699 -> 0.700 / 0.704 / 0.710 after one move and compaction).

The free space is a raster of the square made conservative as in :mod:`.around`: a chart
occupies every cell whose centre lies within ``separation / 2 + h sqrt(2) / 2`` of its outline
(h the cell's side), so two charts whose cells do not meet are at least the separation apart;
the layout the moves give is checked exactly by the caller before it is kept.
"""
import numpy as np

from .around import GROW, _chart_cells
from .nest import _area, rotations

CELLS = 256        # raster cells along the square's side (4 texels a cell at 1024 px)
EDGE_SHARE = 3e-3  # a chart within this fraction of the side of the square's edge bounds it
AREA_SHARE = 0.15  # ... and is moved only when it holds less than this share of the charts' area
MOVES = 10         # at most this many charts moved a call (smallest first)
DEEPEST = 20       # the deepest free offsets checked cell by cell, per turn


def _grid_cells(q, reach, n):
    """Cells of the global n x n grid of the unit square whose centres lie within ``reach`` of
    the polygon q (n,2): (row, column) of the mask's corner and the (rows, cols) bool mask."""
    import shapely
    h = 1.0 / n
    lo = np.maximum(np.floor((q.min(axis=0) - reach) / h).astype(int), 0)
    hi = np.minimum(np.ceil((q.max(axis=0) + reach) / h).astype(int) + 1, n)
    grown = shapely.buffer(shapely.Polygon(q), reach * GROW + 1e-12)
    x, y = np.meshgrid((np.arange(lo[0], hi[0]) + 0.5) * h, (np.arange(lo[1], hi[1]) + 0.5) * h)
    return lo[1], lo[0], shapely.contains_xy(grown, x, y)


def occupied(placed, reach, n):
    """(n,n) bool: the cells of the unit square's n x n grid whose centres lie within ``reach``
    of any of the polygons ``placed`` (list of (m,2) arrays in the unit square)."""
    occ = np.zeros((n, n), dtype=bool)
    for q in placed:  # per chart: its cells
        r, c, mask = _grid_cells(q, reach, n)
        occ[r:r + mask.shape[0], c:c + mask.shape[1]] |= mask
    return occ


def relocate(outlines, angle, shift, side, separation, options, n=CELLS):
    """Move the small charts that bound the square into the free spot deepest inside it.

    Parameters
    ----------
    outlines : list of (n_i,2) float arrays, centred outlines
    angle : (k,) float, turns in degrees; shift : (k,2) float, in the square [0, side]^2
    side : float
    separation : float, least distance between two outlines (square units)
    options : PackOptions (rotate)
    n : int, raster cells along the side

    Returns
    -------
    angle, shift (copies, the moved charts changed) and the number of charts moved
    """
    import scipy.fft as sf
    h = 1.0 / n
    reach = 0.5 * separation / side + h * np.sqrt(0.5)
    angle, shift = angle.astype(np.float64).copy(), shift.astype(np.float64).copy()
    R = rotations(angle)
    placed = [(o @ R[i].T + shift[i]) / side for i, o in enumerate(outlines)]
    lo = np.array([q.min(axis=0) for q in placed])
    hi = np.array([q.max(axis=0) for q in placed])
    clear = np.minimum(lo.min(axis=1), 1 - hi.max(axis=1))   # to the nearest edge
    areas = np.array([_area(o) for o in outlines])
    bound = (clear - clear.min() < EDGE_SHARE) & (areas < AREA_SHARE * areas.sum())
    todo = [i for i in np.argsort(areas, kind="stable") if bound[i]][:MOVES]
    if not todo:
        return angle, shift, 0
    count = np.zeros((n, n), np.int32)
    where = []
    for q in placed:  # per chart: its cells on the grid
        r, c, mask = _grid_cells(q, reach, n)
        count[r:r + mask.shape[0], c:c + mask.shape[1]] += mask
        where.append((r, c, mask))
    free_turns = options.rotate != "none"
    moved = 0
    for i in todo:  # per chart, smallest first
        r, c, mask = where[i]
        count[r:r + mask.shape[0], c:c + mask.shape[1]] -= mask
        occ = (count > 0).astype(np.float32)
        turns = [angle[i] + 90.0 * j for j in range(4 if free_turns else 1)]
        cells = [(a, *_chart_cells(outlines[i] @ Rt.T / side, reach, h))
                 for a, Rt in zip(turns, rotations(turns))]
        cells = [x for x in cells if x[1].shape[0] <= n and x[1].shape[1] <= n]
        stack = np.zeros((len(cells), n, n), np.float32)
        for j, (_, m, _) in enumerate(cells):  # per turn
            stack[j, :m.shape[0], :m.shape[1]] = m
        hits = sf.irfft2(sf.rfft2(occ, workers=1) * np.conj(sf.rfft2(stack, workers=1)),
                         s=(n, n), workers=1)
        best = (clear[i] + 0.5 * h, None)
        for (a, m, off), hit in zip(cells, hits):  # per turn
            rows, cols = m.shape
            free = hit[:n - rows + 1, :n - cols + 1] < 0.5
            if not free.any():
                continue
            q = outlines[i] @ rotations([a])[0].T / side
            x0 = np.arange(n - cols + 1) * h + off[0] + q[:, 0].min()
            x1 = np.arange(n - cols + 1) * h + off[0] + q[:, 0].max()
            y0 = np.arange(n - rows + 1) * h + off[1] + q[:, 1].min()
            y1 = np.arange(n - rows + 1) * h + off[1] + q[:, 1].max()
            depth = np.minimum(np.minimum(y0, 1 - y1)[:, None], np.minimum(x0, 1 - x1)[None, :])
            depth[~free] = -np.inf
            top = np.argpartition(-depth, DEEPEST, axis=None)[:DEEPEST] \
                if depth.size > DEEPEST else np.arange(depth.size)
            for flat in top[np.argsort(-depth.flat[top], kind="stable")]:  # deepest first
                rr, cc = divmod(int(flat), n - cols + 1)
                if depth[rr, cc] <= best[0]:
                    break
                if not occ[rr:rr + rows, cc:cc + cols][m].any():   # exact on the cells
                    best = (depth[rr, cc], (a, rr, cc, m, off))
                    break
        if best[1] is None:
            count[r:r + mask.shape[0], c:c + mask.shape[1]] += mask
            continue
        a, rr, cc, m, off = best[1]
        count[rr:rr + m.shape[0], cc:cc + m.shape[1]] += m
        where[i] = (rr, cc, m)
        angle[i], shift[i] = a, (np.array([cc, rr]) * h + off) * side
        moved += 1
    return angle, shift, moved
