"""Charts dropped into a strip onto conservative step profiles of the charts already placed
(:mod:`.few`).

A chart's profile on a grid of cells of width h: per column the least and greatest y of the chart
within the column's strip (from its boundary segments clipped to the strip). The placed charts'
upper profile (per column the greatest y of any placed chart) bounds them all from above: a chart
whose low profile is above it in every column it covers meets none of them, whatever their
shapes (true shapes, not boxes; a pocket under an overhang is not reached). Exact along the drop,
one cell coarse across it. Measured and dropped: a greedy on an L-shaped frontier (each chart
dropped down or pushed left where it leaves the smallest square), run beside the strips: the same
or less coverage on 7 meshes and three 5-chart sets, 14-25 % more CPU.
"""
import numpy as np


def _profiles(poly, h):
    """Conservative column profile of a polygon (n,2) on cells of width h from its low corner:
    (low, up) per column (least and greatest y within the column's strip, from the low corner),
    the extent (w, h) and the low corner."""
    lo = poly.min(axis=0)
    p = poly - lo
    q = np.roll(p, -1, axis=0)
    a, b = p[:, 0], q[:, 0]
    ya, yb = p[:, 1], q[:, 1]
    n = max(int(np.ceil(p[:, 0].max() / h - 1e-9)), 1)
    c0 = np.arange(n)[:, None] * h
    lo_x, hi_x = np.maximum(c0, np.minimum(a, b)), np.minimum(c0 + h, np.maximum(a, b))
    hit = lo_x <= hi_x
    d = b - a
    flat = np.abs(d) < 1e-300
    slope = np.where(flat, 0.0, (yb - ya) / np.where(flat, 1.0, d))
    y0 = np.where(flat, ya, ya + (lo_x - a) * slope)
    y1 = np.where(flat, yb, ya + (hi_x - a) * slope)
    least = np.where(hit, np.minimum(y0, y1), np.inf).min(axis=1)
    most = np.where(hit, np.maximum(y0, y1), -np.inf).max(axis=1)
    return least, most, p.max(axis=0), lo


class Turns:
    """One chart at its candidate turns, grown, on a grid of cells of width h: per turn its
    profiles (padded with +-inf to the longest), their lengths, extent and low corner."""

    def __init__(self, chart, turned, h):
        self.chart = chart
        self.angle = np.array([a for a, _ in turned])
        prof = [_profiles(g, h) for _, g in turned]
        self.ext = np.array([p[2] for p in prof])
        self.lo = np.array([p[3] for p in prof])
        self.ncol = np.array([len(p[0]) for p in prof])
        self.low = np.full((len(prof), int(self.ncol.max())), np.inf)
        self.up = np.full(self.low.shape, -np.inf)
        for a, (least, most, _, _) in enumerate(prof):  # per turn
            self.low[a, :len(least)], self.up[a, :len(most)] = least, most


def strip_fills(turns, runs, h):
    """Every run (order, strip width in cells) at once: the charts in its order dropped one by
    one into its strip, each at the turn and offset where its top ends lowest (then the first
    turn, then leftmost). Returns per run (side, [(chart, turn index, x, y)])
    (side inf where a chart fits no turn): x, y the grown chart's low corner."""
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
