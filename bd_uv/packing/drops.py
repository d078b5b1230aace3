"""Charts dropped onto conservative step profiles of the charts already placed (:mod:`.few`).

A chart's profiles on a grid of cells of width h: per column the least and greatest y of the chart
within the column's strip (from the boundary segments clipped to it), per row the least and
greatest x. The placed charts' upper profile (per column the greatest y of any placed chart,
raised by every cell a chart's cell overlaps) bounds them all from above: a chart whose low
profile is above it in every column it covers meets none of them, whatever their shapes. So is
one pushed left onto their right profile. Both are exact in the direction of the drop and one
cell coarse across it.
"""
import numpy as np


def _profiles(poly, h):
    """Conservative step profiles of a polygon (n,2) on cells of width h from its low corner:
    (low, up) per column (least and greatest y within the column's strip, from the low corner)
    and (left, right) per row, and the extent (w, h)."""
    lo = poly.min(axis=0)
    p = poly - lo
    q = np.roll(p, -1, axis=0)
    out = []
    for ax in (0, 1):  # columns (over x), then rows (over y)
        a, b = p[:, ax], q[:, ax]
        ya, yb = p[:, 1 - ax], q[:, 1 - ax]
        n = max(int(np.ceil(p[:, ax].max() / h - 1e-9)), 1)
        c0 = np.arange(n)[:, None] * h
        c1 = c0 + h
        s0, s1 = np.minimum(a, b), np.maximum(a, b)
        lo_x, hi_x = np.maximum(c0, s0), np.minimum(c1, s1)
        hit = lo_x <= hi_x
        d = b - a
        flat = np.abs(d) < 1e-300
        slope = np.where(flat, 0.0, (yb - ya) / np.where(flat, 1.0, d))
        y0 = np.where(flat, ya, ya + (lo_x - a) * slope)
        y1 = np.where(flat, yb, ya + (hi_x - a) * slope)
        least = np.where(hit, np.minimum(y0, y1), np.inf).min(axis=1)
        most = np.where(hit, np.maximum(y0, y1), -np.inf).max(axis=1)
        out.append((least, most))
    ext = p.max(axis=0)
    return out[0], out[1], ext, lo


class Turns:
    """One chart at its candidate turns, grown, on a grid of cells of width h: per turn its
    profiles (padded with +-inf to the longest), their lengths, extent and low corner."""

    def __init__(self, chart, turned, h):
        self.chart = chart
        self.angle = np.array([a for a, _ in turned])
        prof = [_profiles(g, h) for _, g in turned]
        self.ext = np.array([p[2] for p in prof])
        self.lo = np.array([p[3] for p in prof])
        self.ncol = np.array([len(p[0][0]) for p in prof])
        self.nrow = np.array([len(p[1][0]) for p in prof])
        self.low, self.up = self._stack([p[0] for p in prof], self.ncol)
        self.left, self.right = self._stack([p[1] for p in prof], self.nrow)

    @staticmethod
    def _stack(pairs, n):
        near = np.full((len(pairs), int(n.max())), np.inf)
        far = np.full(near.shape, -np.inf)
        for a, (lo, hi) in enumerate(pairs):  # per turn
            near[a, :len(lo)], far[a, :len(hi)] = lo, hi
        return near, far


def _drops(frontier, near, length):
    """Per turn a and grid offset i, the least position of a chart above ``frontier`` (its cells
    i.. against the chart's near profile): max over j of frontier[i + j] - near[a, j], at least 0;
    inf where the chart (``length[a]`` cells) passes the frontier's end. (A, n) float64."""
    from numpy.lib.stride_tricks import sliding_window_view
    n, L = len(frontier), near.shape[1]
    win = sliding_window_view(np.concatenate([frontier, np.full(L - 1, -np.inf)]), L)
    pos = np.maximum((win[None, :, :] - near[:, None, :]).max(axis=2), 0.0)
    pos[np.arange(n)[None, :] + length[:, None] > n] = np.inf
    return pos


def greedy(turns, order, n_cells, h):
    """Charts in ``order`` placed one by one on an L-shaped frontier: dropped down onto the
    placed charts' upper profile or pushed left onto their right profile, at the turn and offset
    leaving the smallest square (then the least box area, then the lowest-leftmost). Returns
    (side, [(chart, turn index, x, y)]) with x, y the grown chart's low corner."""
    top = np.zeros(n_cells)     # per column: the placed charts' greatest y
    right = np.zeros(n_cells)   # per row: their greatest x
    W = H = 0.0
    placed = []
    for c in order:  # per chart
        t = turns[c]
        # offsets past the square so far only grow it more than the first of them
        n = min(n_cells, int(np.ceil(max(W, H) / h)) + 1 + max(t.low.shape[1], t.left.shape[1]))
        best = None
        for down in (True, False):
            if down:
                pos = _drops(top[:n], t.low, t.ncol)
                along = np.arange(n)[None, :] * h
                w, ht = np.maximum(W, along + t.ext[:, :1]), np.maximum(H, pos + t.ext[:, 1:])
            else:
                pos = _drops(right[:n], t.left, t.nrow)
                along = np.arange(n)[None, :] * h
                ht, w = np.maximum(H, along + t.ext[:, 1:]), np.maximum(W, pos + t.ext[:, :1])
            side = np.maximum(w, ht).ravel()
            j = int(np.lexsort(((along + pos).ravel(), (w * ht).ravel(), np.round(side / h, 6)))[0])
            cand = (float(side[j]), float((w * ht).ravel()[j]))
            if best is None or cand < best[0]:
                a, i = divmod(j, n)
                xy = (i * h, float(pos[a, i])) if down else (float(pos[a, i]), i * h)
                best = (cand, a, *xy, float(w.ravel()[j]), float(ht.ravel()[j]))
        if not np.isfinite(best[0][0]):
            return np.inf, []
        _, a, x, y, W, H = best
        placed.append((c, a, x, y))
        _raise(top, t.up[a, :t.ncol[a]], x, y, h)
        _raise(right, t.right[a, :t.nrow[a]], y, x, h)
    return max(W, H), placed


def strip_fills(turns, runs, h):
    """Every run (order, strip width in cells) at once: the charts in its order dropped one by
    one into its strip, each at the turn and offset where its top ends lowest (then the first
    turn, then leftmost). Returns per run (side, [(chart, turn index, x, y)]) as
    :func:`greedy` (side inf where a chart fits no turn)."""
    from numpy.lib.stride_tricks import sliding_window_view
    k, A = len(turns), max(len(t.angle) for t in turns)
    L = max(t.low.shape[1] for t in turns)
    low = np.full((k, A, L), np.inf)
    up = np.full((k, A, L), -np.inf)
    ncol = np.full((k, A), 1 << 30)
    ext = np.zeros((k, A, 2))
    for c, t in enumerate(turns):  # per chart
        a, m = len(t.angle), t.low.shape[1]
        low[c, :a, :m], up[c, :a, :m], ncol[c, :a], ext[c, :a] = t.low, t.up, t.ncol, t.ext
    order = np.array([r[0] for r in runs])
    width = np.array([r[1] for r in runs])
    B, n = len(runs), int(width.max())
    rows = np.arange(B)
    top = np.zeros((B, n + L - 1))
    top[:, n:] = -np.inf
    W, H = np.zeros(B), np.zeros(B)
    ok = np.ones(B, dtype=bool)
    place = np.zeros((B, k, 4))
    cols = np.arange(n)
    for step in range(k):  # per chart of every run
        c = order[:, step]
        win = sliding_window_view(top, L, axis=1)[:, :n]                     # (B, n, L)
        pos = np.maximum((win[:, None, :, :] - low[c][:, :, None, :]).max(axis=3), 0.0)
        bad = cols[None, None, :] + ncol[c][:, :, None] > width[:, None, None]
        key = np.where(bad, np.inf, pos + ext[c][:, :, 1:])
        j = np.argmin(key.reshape(B, -1), axis=1)
        a, i = np.divmod(j, n)
        ok &= np.isfinite(key.reshape(B, -1)[rows, j])
        y = pos[rows, a, i]
        e = ext[c, a]
        place[:, step] = np.stack([c, a, i * h, y], axis=1)
        W, H = np.maximum(W, i * h + e[:, 0]), np.maximum(H, y + e[:, 1])
        idx = np.minimum(i[:, None] + np.arange(L)[None, :], n + L - 2)
        val = np.where(np.isfinite(up[c, a]), y[:, None] + up[c, a], -np.inf)
        top[rows[:, None], idx] = np.maximum(top[rows[:, None], idx], val)
        top[:, n:] = -np.inf
    side = np.where(ok, np.maximum(W, H), np.inf)
    return [(float(side[b]), [(int(p[0]), int(p[1]), float(p[2]), float(p[3]))
                              for p in place[b]]) for b in range(B)]


def _raise(prof, far, at, base, h):
    """The frontier ``prof`` raised by a chart's far profile placed at offset ``at`` (a cell
    boundary or not: each cell of the chart covers at most two of the frontier's)."""
    i = at / h
    i0 = int(np.floor(i + 1e-9))
    val = base + far
    n = min(len(val), len(prof) - i0)
    np.maximum(prof[i0:i0 + n], val[:n], out=prof[i0:i0 + n])
    if abs(i - round(i)) > 1e-9:  # straddling: each chart cell touches the next frontier cell
        n1 = min(len(val), len(prof) - i0 - 1)
        np.maximum(prof[i0 + 1:i0 + 1 + n1], val[:n1], out=prof[i0 + 1:i0 + 1 + n1])
