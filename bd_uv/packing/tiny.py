"""Many tiny charts: the others packed alone, the tiny ones dropped into the free space left.

A mesh can come unwrapped into a few large charts and many tiny ones (the shader ball: 8 charts
hold 98.6 % of the area, 154 bolt charts a few texels across the other 1.4 %). Nesting and
compacting them all makes the time follow the chart count (the budget is 4 ms sqrt(charts x
faces), every compaction program has rows for every tiny chart's outline) while the tiny charts
barely change the square. So when most charts are tiny (each under ``TINY_SHARE`` of the charts'
area, at least ``TINY_COUNT_SHARE`` of the charts, together under ``TINY_AREA_SHARE``; the small
ones, under ``SMALL_SHARE``, join them, smallest first, while all hold under that share):

1. the other charts are packed as any set of charts is (:func:`.few.few_square` for 2-5,
   else :func:`.square.square_layout`), with ``OTHERS_TIME`` times the time of the count and
   faces of every chart that is not tiny, the small ones dropped included (cut where one of the
   others dominates, as ``PackOptions.search_seconds`` does for any set);
2. the dropped charts, largest first, are dropped into the free space of that square on a raster
   made conservative as in :mod:`.around` (a chart occupies every cell whose centre lies within
   ``separation / 2 + h sqrt(2) / 2`` of its outline, so two charts whose cells do not meet are
   at least the separation apart, and a chart whose cells stay in the grid is half of it from
   the square's edge): the lowest, then leftmost free offset of its bounding mask at each of its
   allowed turns (a summed-area table of the occupied cells), else of its own cells (an FFT
   correlation);
3. the whole layout is checked exactly (:func:`.refit.fits`); when a tiny chart finds no room
   or the check fails, None: the caller packs every chart together.
"""
import numpy as np

from .around import GROW, _candidates
from .few import few_square
from .nest import Placement, rotations
from .refit import ROUNDING, fits
from .relocate import occupied
from .square import square_layout

TINY_SHARE = 1e-3       # a chart under this share of the charts' area is tiny
# ... and the tiny ones are dropped when at least this share of the charts (the shader ball: 95 %;
# Wuson.off's 56 of 83, 67 %, and wuson.stl's 58 of 91, 64 %, went from large_first's nesting of
# all 83 to 27 charts nested and the rest dropped: 0.665 -> 0.698 and 0.652 -> 0.688 at half the
# CPU, 3.2 -> 1.6 s, seeds 0-3 at load 3, 7 wins and a tie; at load 8-9, seeds 4-9, +0.010 and
# +0.025, the 27's short nesting starving; issue18-pack25-2026-11-28.md). Not lower: the cow's 14
# of 45 (31 %) lost 0.755/0.717 -> 0.698/0.685 (large_first's nesting gone), the dino's 11 of 36
# gained; an older ChineseDragon set (61 % tiny) lost 0.581 -> 0.556, seeds 0-2, the large ones'
# shorter time losing more than it saved (issue18-tinypack12-2026-11-28.md)
TINY_COUNT_SHARE = 0.6
TINY_AREA_SHARE = 0.05  # ... holding less than this share of the area together
# ... and each shorter than this over the square root of all the charts' area: a long thin strip
# of little area (assimp's regr01.obj: 157 of its 246 charts under TINY_SHARE, 97 of them
# reaching 0.05, up to a sixth of the square across) finds no free box to drop into, and the
# failed drop, repeated by every re-pack, took 21.7 s of CPU where nesting all took 5.0 s
# (unseen25). Compact tiny charts are within it: all of Wuson.off's 50, wuson.stl's 54 and
# the shader ball's 108.
TINY_EXTENT = 0.05
# The others are nested for OTHERS_TIME times their own count's time: their square is the
# atlas's, and the tiny charts' share of Blender's time (it traces and scans for every chart) is
# left to them. x2 (issue18-pack26-2026-11-28.md, interleaved per seed): Wuson.off 0.651 -> 0.659
# (3/1), CPU 1.23 -> 1.88 s (Blender 13.1 s idle); wuson.stl 0.643 -> 0.670 (4/0), 1.58 -> 2.44 s
OTHERS_TIME = 2.0
# Once most charts are tiny, the small ones (under SMALL_SHARE of the area each) are dropped
# too, smallest first while the dropped ones hold under TINY_AREA_SHARE: the square is the
# others', and a small chart nested with them costs their search and compaction more than it
# moves the square; the others nest for the time the charts that are not tiny had (so not
# less than before). Measured (issue18-pack29-2026-11-29.md, interleaved per seed, load 4-8):
# Wuson.off's 83 charts (55 tiny, 11 small: 17 nested instead of 28) 0.687 -> 0.698 (12/6, 18
# seeds), CPU 1.97 -> 1.67 s; wuson.stl's 91 (55, 14: 22 instead of 36) 0.683 -> 0.691 (11/7),
# 2.36 -> 2.00 s. For the time of their own count (less): Wuson.off +0.011 (16/4) at load 4-7
# but -0.029 (1/4) at load 7-8, where that shorter nesting starved, and below this rule in the
# same runs (-0.002, 4/10; wuson.stl -0.008, 3/8); at 2e-3 (fewer small ones): Wuson.off +0.018
# (3/2), wuson.stl -0.003 (3/2), 5 seeds
SMALL_SHARE = 3e-3
SMALL_EXTENT = 0.13     # ... and within this extent (a square of 0.5 % of the area is 0.07 across)
CELLS = 512             # raster cells along the square's side (2 texels at 1024 px)


def tiny_charts(area, extent=None):
    """Indices of the charts to drop (int64), or None when the charts are not mostly tiny
    ones (or fewer than two would be left to pack). ``extent`` (k,), optional: each chart's
    longest side over the square root of all the charts' area; a chart reaching
    ``TINY_EXTENT`` is not tiny, whatever its area. Where they are mostly tiny, the small
    charts (under ``SMALL_SHARE`` of the area, within ``SMALL_EXTENT``) are dropped too,
    smallest first while all the dropped ones hold under ``TINY_AREA_SHARE`` of the area."""
    area = np.asarray(area, dtype=np.float64)
    extent = np.zeros(len(area)) if extent is None else np.asarray(extent, dtype=np.float64)
    tiny = (area < TINY_SHARE * area.sum()) & (extent < TINY_EXTENT)
    if (tiny.sum() < TINY_COUNT_SHARE * len(area) or (~tiny).sum() < 2
            or area[tiny].sum() >= TINY_AREA_SHARE * area.sum()):
        return None
    small = np.flatnonzero((area < SMALL_SHARE * area.sum()) & (extent < SMALL_EXTENT) & ~tiny)
    small = small[np.argsort(area[small], kind="stable")]
    room = TINY_AREA_SHARE * area.sum() - area[tiny].sum()
    small = small[np.cumsum(area[small]) < room][:max(int((~tiny).sum()) - 2, 0)]
    tiny[small] = True
    return np.flatnonzero(tiny)


def tiny_square(charts, options, tol, faces):
    """The square of the charts that are not tiny, with the tiny ones dropped into its free
    space: (Placement, side, solves), or None (not mostly tiny charts, or no room found).

    Parameters
    ----------
    charts : outlines.Charts
    options : PackOptions
    tol : float, outline simplification tolerance
    faces : (k,) int, faces of each chart (the time follows the charts packed)
    """
    extent = np.array([np.ptp(o, axis=0).max() if len(o) else 0.0 for o in charts.outlines])
    scaled = extent / np.sqrt(max(float(np.sum(charts.area)), 1e-300))
    tiny = tiny_charts(charts.area, scaled)
    if tiny is None:
        return None
    k = len(charts.outlines)
    big = np.setdiff1d(np.arange(k), tiny)
    outlines = [charts.outlines[i] for i in big]
    exact = [charts.exact[i] for i in big]
    found = few_square(outlines, options, tol, exact)
    if found is None:
        # the time of every chart that is not tiny (the small ones dropped too: their share is
        # left to the others), cut where one of the others dominates them
        timed = np.flatnonzero((charts.area >= TINY_SHARE * charts.area.sum())
                               | (scaled >= TINY_EXTENT))
        seconds = OTHERS_TIME * options.search_seconds(
            len(timed), int(np.sum(np.asarray(faces)[timed])),
            float(charts.area[big].max() / charts.area[timed].sum()))
        found = square_layout(outlines, options, tol, seconds, exact)
    pl, side, solves = found
    angle, shift = np.zeros(k), np.zeros((k, 2))
    angle[big], shift[big] = pl.angle, pl.shift
    margin = ROUNDING * side
    pm = options.padding + 1e-5
    sep = pm * side + 2 * margin
    order = tiny[np.argsort(-charts.area[tiny], kind="stable")]
    got = _drop(charts.exact, big, order, angle, shift, side, sep, options)
    if got is None:
        return None
    angle, shift = got
    if not fits(charts.exact, angle, shift, side, options.padding, options.padding, margin):
        return None
    return Placement(angle, shift, side), side, solves


def _masks(turned, reach, h):
    """Per polygon of ``turned`` (list of (m,2) arrays, unit square's units): the cells whose
    centres lie within ``reach`` of it, as :func:`.around._chart_cells` finds them (one shapely
    call for all): a list of (mask (rows, cols) bool, offset of the polygon from its corner)."""
    import shapely
    m = reach + h
    lo = [q.min(axis=0) for q in turned]
    shape = [np.ceil((q.max(axis=0) - low + 2 * m) / h).astype(int) for q, low in zip(turned, lo)]
    rings = shapely.linearrings(np.concatenate([q - low + m for q, low in zip(turned, lo)]),
                                indices=np.repeat(np.arange(len(turned)), [len(q) for q in turned]))
    grown = shapely.buffer(shapely.polygons(rings), reach * GROW + 1e-12)
    sizes = [int(s[0] * s[1]) for s in shape]
    xs = [np.tile((np.arange(s[0]) + 0.5) * h, s[1]) for s in shape]
    ys = [np.repeat((np.arange(s[1]) + 0.5) * h, s[0]) for s in shape]
    inside = shapely.contains_xy(np.repeat(grown, sizes), np.concatenate(xs), np.concatenate(ys))
    cuts = np.cumsum([0] + sizes)
    return [(inside[cuts[j]:cuts[j + 1]].reshape(s[1], s[0]), m - low)
            for j, (s, low) in enumerate(zip(shape, lo))]


def _free_boxes(occ, rows, cols):
    """(n - rows + 1, n - cols + 1) bool: offsets where a rows x cols box meets no occupied
    cell of ``occ`` (a summed-area table)."""
    sat = np.zeros((occ.shape[0] + 1, occ.shape[1] + 1), np.int32)
    sat[1:, 1:] = occ.cumsum(axis=0, dtype=np.int32).cumsum(axis=1, dtype=np.int32)
    return (sat[rows:, cols:] - sat[:-rows, cols:] - sat[rows:, :-cols] + sat[:-rows, :-cols]) == 0


def _drop(outlines, big, order, angle, shift, side, sep, options, n=CELLS):
    """The charts ``order`` placed one by one into the free cells left by the placed charts
    ``big``: (angle, shift) with theirs set, or None when one finds no room.

    Each chart goes to the lowest, then leftmost offset where its bounding mask meets no
    occupied cell, over its allowed turns (per mask size, the free offsets are kept up to date
    around each chart placed), else where its own cells meet none (an FFT correlation)."""
    import scipy.fft as sf
    h = 1.0 / n
    reach = 0.5 * sep / side + h * np.sqrt(0.5)
    R = rotations(angle)
    occ = occupied([(outlines[i] @ R[i].T + shift[i]) / side for i in big], reach, n)
    turns = _candidates([outlines[i] for i in order], options)
    turned = [(i, a, outlines[i] @ Rt.T / side)
              for i, allowed in zip(order, turns) for a, Rt in zip(allowed, rotations(allowed))]
    masks = _masks([q for _, _, q in turned], reach, h)
    cells = {}
    for (i, a, _), (m, off) in zip(turned, masks):  # per chart and turn
        if m.shape[0] <= n and m.shape[1] <= n:
            cells.setdefault(i, []).append((a, m, off))
    boxes = {}   # (rows, cols) -> the free offsets of such a box
    for i in order:  # per tiny chart, largest first
        best = None
        for a, m, off in cells.get(i, []):  # per allowed turn: the bounding mask free
            if m.shape not in boxes:
                boxes[m.shape] = _free_boxes(occ, *m.shape)
            box = boxes[m.shape]
            flat = int(np.argmax(box))
            if box.flat[flat]:
                at = divmod(flat, box.shape[1])
                if best is None or at < best[0]:
                    best = (at, a, m, off)
        if best is None:   # no free box: the chart's own cells (FFT correlation)
            F_occ = sf.rfft2(occ.astype(np.float32), workers=1)
            for a, m, off in cells.get(i, []):  # per allowed turn
                rows, cols = m.shape
                pad = np.zeros((n, n), np.float32)
                pad[:rows, :cols] = m
                hit = sf.irfft2(F_occ * np.conj(sf.rfft2(pad, workers=1)), s=(n, n), workers=1)
                free = hit[:n - rows + 1, :n - cols + 1] < 0.5
                for flat in np.flatnonzero(free):  # lowest, then leftmost first
                    at = divmod(int(flat), n - cols + 1)
                    if best is not None and at >= best[0]:
                        break
                    if not occ[at[0]:at[0] + rows, at[1]:at[1] + cols][m].any():
                        best = (at, a, m, off)
                        break
        if best is None:
            return None
        (rr, cc), a, m, off = best
        occ[rr:rr + m.shape[0], cc:cc + m.shape[1]] |= m
        for (rows, cols), box in boxes.items():  # per box size: the offsets around the chart
            r0, c0 = max(rr - rows + 1, 0), max(cc - cols + 1, 0)
            r1 = min(rr + m.shape[0], box.shape[0])
            c1 = min(cc + m.shape[1], box.shape[1])
            box[r0:r1, c0:c1] = _free_boxes(occ[r0:r1 + rows - 1, c0:c1 + cols - 1], rows, cols)
        angle[i], shift[i] = a, (np.array([cc, rr]) * h + off) * side
    return angle, shift
