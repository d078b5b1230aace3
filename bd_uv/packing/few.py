"""A few charts into the smallest square, in milliseconds: greedy drops on an L-shaped frontier.

spyrrow (:mod:`.nest`) overshoots tiny search requests: Blender's cube (3 charts) asked for about
0.1 s of search takes 0.5-0.7 s, whatever its budget (measured in
benchmarks/results/bench_pack-2026-11-27-fewpack.md). For a handful of charts a small exhaustive
greedy search does as well in far less time:

- each chart is turned to a few candidate angles (its least-area box and least-square box
  orientations and their quarter turns; quarter turns only for ``rotate`` 90, none for none) and
  grown by half the separation (a mitred buffer holds every point that close to the chart);
- a layout places the charts one after another against the frontier of those already placed:
  dropped down onto the upper profile of the placed charts (column by column), or pushed left onto
  their right profile (row by row). Profiles are conservative step functions on a grid of
  ``GRID`` cells across the square: a chart above the upper profile in every column it covers is
  apart from every placed chart, whatever their shapes (true shapes, not boxes). Among every
  candidate angle, direction and grid offset, the one leaving the smallest bounding square wins
  (then the smallest box area, then the lowest-leftmost);
- the charts are taken in every order (up to 4 charts) or in a few orders (largest first, tallest
  first, then shuffles from the seed); the smallest square found is kept.

Deterministic for a seed. The layout is checked exactly (GEOS distances between the true outlines
and every point inside the square) before it is returned; a layout that does not hold is not
returned (the caller nests with spyrrow instead).
"""
import itertools

import numpy as np

from .compact import compact_square
from .nest import Placement, rotations

# up to this many charts: measured on eight's 6 charts, 0.573 in 0.56 s CPU (load ~4) against
# spyrrow's 0.584-0.590 in about as much; 2-4 charts 4-10x faster than spyrrow
FEW_MAX = 4
GRID_COARSE = 24    # profile cells across the guessed square side, for every order and fill
GRID = 192          # ... for the KEEP best of them (a multiple of GRID_COARSE)
KEEP = 3
SETTLED = 1         # of those, settled by exact moves, the smallest kept
# linear programs of compaction (:mod:`.compact`) of the layout found, a count (not a time) so
# the layout is deterministic; measured (seed 0, load ~3.5) for 0.05 s of CPU: UV sphere 0.663 ->
# 0.697, torus 0.746 -> 0.777, fandisk 0.707 -> 0.717; 0.15 s added under 0.005
COMPACT_PROGRAMS = 12
STRIPS = 16         # strip widths tried, from the widest chart's to STRIP_MAX the guessed side
STRIP_MAX = 1.4
SETTLE_ROUNDS = 3   # rounds of exact moves left and down (:func:`_settle`)
SETTLE_BISECT = 8   # halvings of a move that is not free all the way
SQUARE_GREEDY = 1
ORDERS = 24         # chart orders tried (every order up to 4 charts: 24)
GROW_SLACK = 1e-6   # grown charts apart by this fraction of the side more (float rounding)


def _candidate_angles(xy, rotate):
    """Turns (degrees) to try for one outline: none; quarter turns; or the least-area box and
    least-square box orientations and their quarter turns."""
    if rotate == "none":
        return [0.0]
    base = [0.0]
    if rotate == "any":
        import shapely
        hull = np.asarray(shapely.get_coordinates(shapely.convex_hull(shapely.Polygon(xy))))[:-1]
        e = np.roll(hull, -1, axis=0) - hull
        theta = np.unique(np.round(np.mod(-np.degrees(np.arctan2(e[:, 1], e[:, 0])), 90), 6))
        theta = np.unique(np.concatenate([theta, np.arange(0.0, 90.0, 1.0)]))
        q = np.einsum("aij,nj->ani", rotations(theta), hull)
        ext = np.ptp(q, axis=1)
        base = sorted({float(theta[np.argmin(ext[:, 0] * ext[:, 1])]),
                       float(theta[np.argmin(ext.max(axis=1))])})
    return [b + 90.0 * r for b in base for r in range(4)]


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


class _Turns:
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


def _greedy(turns, order, n_cells, h):
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


def _strip_fills(turns, runs, h):
    """Every run (order, strip width in cells) at once: the charts in its order dropped one by
    one into its strip, each at the turn and offset where its top ends lowest (then the first
    turn, then leftmost). Returns per run (side, [(chart, turn index, x, y)]) as
    :func:`_greedy` (side inf where a chart fits no turn)."""
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


def _orders(outlines, seed):
    """Chart orders to try: every one up to 4 charts, else largest first, tallest first and
    shuffles from the seed."""
    k = len(outlines)
    if k <= 4:
        return list(itertools.permutations(range(k)))
    from .nest import _area
    area = np.array([_area(xy) for xy in outlines])
    tall = np.array([np.ptp(xy, axis=0).max() for xy in outlines])
    out = [tuple(np.argsort(-area, kind="stable")), tuple(np.argsort(-tall, kind="stable"))]
    rng = np.random.default_rng(seed)
    while len(out) < ORDERS:
        out.append(tuple(rng.permutation(k)))
    return list(dict.fromkeys(out))


def _grown(outlines, angles, grow):
    """Each (chart, turn): the turned outline grown by ``grow`` (mitred: it holds every point
    within that distance of the chart)."""
    import shapely
    out = []
    for i, xy in enumerate(outlines):  # per chart
        poly = shapely.buffer(shapely.Polygon(xy), grow, join_style="mitre") if grow > 0 \
            else shapely.Polygon(xy)
        g = np.asarray(shapely.get_coordinates(poly.exterior))[:-1]
        out.append([(a, g @ rotations([a])[0].T) for a in angles[i]])
    return out


def few_square(outlines, options, tol):
    """The smallest square found for 2 to ``FEW_MAX`` outlines: :func:`few_layout`, then
    ``COMPACT_PROGRAMS`` compaction steps (:func:`.compact.compact_square`). Returns
    (Placement with shift to the square's corner, side, 0 solves), or None (another count of
    charts, or no layout found)."""
    found = few_layout(outlines, options, tol)
    if found is None:
        return None
    pl, side, _ = compact_square(outlines, *found, options, tol, np.inf,
                                 max_programs=COMPACT_PROGRAMS)
    return pl, side, 0


def few_layout(outlines, options, tol):
    """The smallest square found for a few outlines (up to ``FEW_MAX``), or None.

    The separation between two outlines is ``padding`` S + 2 ``tol`` for the square's side S,
    and half of it to the square's edge, as :func:`.square.square_layout` keeps. S is guessed
    and the charts grown by half the separation at it; every order and fill is run on a coarse
    grid (``GRID_COARSE`` cells across the guess), the ``KEEP`` best again on the fine grid
    (``GRID``), the best of those settled by exact moves (:func:`_settle`). When the square
    reached needs more separation than the charts were grown by, again at that square.

    Returns
    -------
    (Placement with shift to the square's corner, side), or None when no layout holds
    """
    k = len(outlines)
    if not 2 <= k <= FEW_MAX:
        return None
    from .nest import _area
    pad = options.padding
    angles = [_candidate_angles(xy, options.rotate) for xy in outlines]
    area = sum(_area(xy) for xy in outlines)
    widest = max(float(np.ptp(xy, axis=0).max()) for xy in outlines)
    guess = max(np.sqrt(area / 0.6), widest)
    orders = _orders(outlines, options.seed)
    for _ in range(3):  # per guess of the side
        sep = pad * guess + 2 * tol
        grow = 0.5 * sep * (1 + GROW_SLACK) + GROW_SLACK * guess
        grown = _grown(outlines, angles, grow)
        for fine in (False, True)[:1 + (KEEP > 0)]:  # coarse, then fine
            grid = GRID if fine else GRID_COARSE
            h = guess / grid
            turns = [_Turns(i, g, h) for i, g in enumerate(grown)]
            if not fine:
                narrow = max(int(t.ncol.min()) for t in turns)
                widths = np.unique(np.linspace(narrow, STRIP_MAX * grid, STRIPS).round())
                runs = [(order, None) for order in orders if SQUARE_GREEDY] + [
                    (order, int(w)) for order in orders for w in widths]
            else:   # the best coarse runs, on the fine grid (the same strip widths)
                ratio = GRID // GRID_COARSE
                runs = [(o, w if w is None else w * ratio)
                        for _, _, (o, w), _, _ in sorted(found, key=lambda f: f[:2])[:KEEP]]
            strips = [r for r in runs if r[1] is not None]
            laid = _strip_fills(turns, strips, h) if strips else []
            laid += [_greedy(turns, o, int(np.ceil(2.5 * grid)), h) for o, w in runs if w is None]
            runs = strips + [r for r in runs if r[1] is None]
            found = [(side, n, run, placed, turns)
                     for n, (run, (side, placed)) in enumerate(zip(runs, laid))
                     if placed and np.isfinite(side)]
        if not found:
            return None
        # each fine layout settled (the order they reached changes after the exact moves)
        found = sorted(found, key=lambda f: f[:2])[:SETTLED]
        laid = [_placement(outlines, f[3], f[4], options, tol, sep) for f in found]
        held = [x for x in laid if x]
        if held:
            return min(held, key=lambda x: x[1])
        if all(x is False for x in laid):   # every one failed the exact check
            return None
        # the square reached needs a larger separation than the charts were grown by
        guess = (found[0][0] - 2 * grow + 2 * tol) / (1 - pad) * 1.01
    return None


def _placement(outlines, placed, turns, options, tol, grown_sep):
    """The Placement of the placed grown charts in the least square around them, settled
    (:func:`_settle`) and checked exactly; None when that square needs more separation than
    ``grown_sep`` (the charts were grown by half of it), False when the exact check fails."""
    import shapely
    k = len(outlines)
    angle, shift = np.zeros(k), np.zeros((k, 2))
    for c, a, x, y in placed:  # per chart: the grown outline's low corner to (x, y)
        angle[c] = turns[c].angle[a]
        shift[c] = np.array([x, y]) - turns[c].lo[a]
    R = rotations(angle)
    q = [xy @ R[i].T + shift[i] for i, xy in enumerate(outlines)]
    side = _side(q, options, tol)
    if options.padding * side + 2 * tol > grown_sep:
        return None
    q, moved = _settle(q, options, tol)
    shift = shift + moved
    side = _side(q, options, tol)
    lo = np.min([p.min(axis=0) for p in q], axis=0)
    edge = 0.5 * options.padding * side + tol
    shift = shift - lo + edge
    polys = np.array([shapely.Polygon(p - lo + edge) for p in q])
    i, j = np.triu_indices(k, 1)
    if np.any(shapely.distance(polys[i], polys[j]) < options.padding * side + 2 * tol):
        return False
    return Placement(angle, shift, side), side


def _side(q, options, tol):
    """The least square side holding placed outlines q (list of (n,2)) with the edge gap."""
    lo = np.min([p.min(axis=0) for p in q], axis=0)
    hi = np.max([p.max(axis=0) for p in q], axis=0)
    return (float((hi - lo).max()) + 2 * tol) / (1 - options.padding)


def _settle(q, options, tol):
    """Each placed outline moved left, then down, as far as the others allow at the exact
    separation of the current square (GEOS distances; the farthest move tried first, else
    bisection), in rounds, lowest-leftmost first. Removes the grid's slack and the separation
    guessed above the one needed. Returns the moved outlines and each one's move (k,2)."""
    import shapely
    k = len(q)
    q = [p.copy() for p in q]
    moved = np.zeros((k, 2))
    for _ in range(SETTLE_ROUNDS):  # per round
        side = _side(q, options, tol)
        sep = options.padding * side + 2 * tol
        base = np.min([p.min(axis=0) for p in q], axis=0)
        lows = np.array([p.min(axis=0) for p in q])
        gained = 0.0
        for i in np.argsort(lows.sum(axis=1), kind="stable"):  # per chart
            others = np.array([shapely.Polygon(q[j]) for j in range(k) if j != i])
            for ax in (0, 1):  # left, then down
                room = float(q[i][:, ax].min() - base[ax])
                if room <= 1e-12 * side:
                    continue
                step = np.zeros(2)

                def free(t):
                    step[ax] = -t
                    return bool(np.all(shapely.distance(shapely.Polygon(q[i] + step), others)
                                       >= sep))
                t, lo, hi = 0.0, 0.0, room
                if free(room):
                    t = room
                else:
                    for _ in range(SETTLE_BISECT):  # per halving
                        mid = 0.5 * (lo + hi)
                        lo, hi = (mid, hi) if free(mid) else (lo, mid)
                    t = lo
                if t > 0:
                    q[i][:, ax] -= t
                    moved[i, ax] -= t
                    gained += t
        if gained <= 1e-6 * side:
            break
    return q, moved
