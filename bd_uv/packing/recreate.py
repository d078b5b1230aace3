"""Ruin and recreate: the small charts taken out, the large ones compacted alone, the small ones
put back into the free space they leave.

Compaction (:mod:`.compact`) ends in a local optimum fixed by which charts sit next to which:
small charts wedged between large ones hold them apart, and small moves cannot take them out.
A step here:

1. the smallest charts holding up to a fraction ``q`` of the charts' area are taken out;
2. the others are compacted alone (:func:`.compact.compact_square`) to a smaller side;
3. the small ones are put back, largest first, into the free space of a square of that side (or
   a hair larger, the others' places scaled with it) on a conservative raster: the others grown
   by their outline tolerance and half the padding mark every cell they meet (as pinned charts
   do, :func:`.around.pinned_cells`), each small chart at its allowed turns grown by half the
   padding plus its tolerance the same way; it goes where its cells' bounding box meets no
   marked cell (summed-area table), else where its cells meet none (an FFT correlation), at the
   lowest top edge, then leftmost;
4. the layout is checked exactly (:func:`.compact._fits`), then compacted whole again, and kept
   when its side is smaller.
"""
import time

import numpy as np

from .around import _candidates, _chart_cells, pinned_cells
from .compact import _fits, compact_square
from .nest import Placement, rotations

GRID = 512                 # raster cells along the square's side
SMALL = (0.1, 0.2, 0.05)   # fractions of the charts' area taken out, tried in turn
TURNS = "current"
ROOM = (1.0, 1.005, 1.01, 1.02)   # sides tried for the put-back, times the big charts' side


def _summed(occ):
    """(n+1, n+1) int32 summed-area table of the marked cells."""
    n = occ.shape[0]
    S = np.zeros((n + 1, n + 1), np.int32)
    np.cumsum(np.cumsum(occ, axis=0, dtype=np.int32), axis=1, out=S[1:, 1:])
    return S


def _free_offsets(S, rows, cols):
    """(n-rows+1, n-cols+1) bool: offsets where a rows x cols box meets no marked cell (``S``
    the summed-area table)."""
    return (S[rows:, cols:] - S[:-rows, cols:] - S[rows:, :-cols] + S[:-rows, :-cols]) == 0


def _exact_offsets(F_occ, n, mask):
    """Offsets where ``mask``'s cells meet no marked cell (FFT correlation with the marked
    cells' transform ``F_occ``; checked cell by cell by the caller)."""
    import scipy.fft as sf
    pad = np.zeros((n, n), np.float32)
    pad[:mask.shape[0], :mask.shape[1]] = mask
    hit = sf.irfft2(F_occ * np.conj(sf.rfft2(pad, workers=1)), s=(n, n), workers=1)
    return hit[:n - mask.shape[0] + 1, :n - mask.shape[1] + 1] < 0.5


def put_back(occ, outlines, turns, scale, options, tol, until=np.inf):
    """Each outline (in the order given) placed on the raster ``occ`` (marked in place).
    Returns (angle, shift) in the raster's unit square, or None when one finds no room (or the
    process's CPU clock passes ``until``)."""
    n = occ.shape[0]
    h = 1.0 / n
    reach = 0.5 * options.padding + tol * scale + h * np.sqrt(0.5)
    angle, shift = np.zeros(len(outlines)), np.zeros((len(outlines), 2))
    for i, xy in enumerate(outlines):  # per chart, largest first
        if time.process_time() > until:
            return None
        cells = [(a, *_chart_cells(scale * xy @ R.T, reach, h))
                 for a, R in zip(turns[i], rotations(turns[i]))]
        cells = [c for c in cells if c[1].shape[0] <= n and c[1].shape[1] <= n]
        best, table = None, _summed(occ)
        for exact in (False, True):  # boxes first, then the cells themselves
            if exact:
                import scipy.fft as sf
                table = sf.rfft2(occ.astype(np.float32), workers=1)
            for a, mask, off in cells:  # per allowed turn
                rows, cols = mask.shape
                free = (_exact_offsets(table, n, mask) if exact
                        else _free_offsets(table, rows, cols))
                for r in np.flatnonzero(free.any(axis=1)):  # per row, lowest first
                    if best is not None and r + rows >= best[0]:
                        break
                    c = next((int(c) for c in np.flatnonzero(free[r])
                              if not occ[r:r + rows, c:c + cols][mask].any()), None)
                    if c is not None:
                        best = (r + rows, a, r, c, mask, off)
                        break
            if best is not None:
                break
        if best is None:
            return None
        _, angle[i], r, c, mask, off = best
        occ[r:r + mask.shape[0], c:c + mask.shape[1]] |= mask
        shift[i] = np.array([c, r]) * h + off
    return angle, shift


def _put_back_all(outlines, areas, turns, angle, shift, big, T, options, tol, until):
    """The small charts (not ``big``) put back around the big ones in the square of side T:
    (angle, shift) of every chart, checked exactly, or None."""
    import shapely
    R = rotations(angle)
    kept = [shapely.Polygon((outlines[i] @ R[i].T + shift[i]) / T) for i in np.flatnonzero(big)]
    occ = pinned_cells(shapely.buffer(shapely.union_all(kept), tol / T), options.padding, GRID)
    small = np.flatnonzero(~big)
    order = small[np.argsort(-areas[small], kind="stable")]
    got = put_back(occ, [outlines[i] for i in order], [turns[i] for i in order], 1.0 / T,
                   options, tol, until)
    if got is None:
        return None
    angle, shift = angle.copy(), shift.copy()
    angle[order], shift[order] = got[0], got[1] * T
    if not _fits(outlines, angle, shift, T, options.padding, options.padding, tol):
        return None
    return angle, shift


def recreate_square(outlines, placement, side, options, tol, seconds, log=None):
    """Ruin-and-recreate steps (small charts out, the big compacted, the small put back, all
    compacted) for about ``seconds`` of CPU of this process.

    Returns
    -------
    Placement, side (no larger than given), steps that shrank the side
    """
    t0 = time.process_time()
    left = lambda: seconds - (time.process_time() - t0)   # noqa: E731
    k = len(outlines)
    areas = np.array([_area(o) for o in outlines])
    base = _candidates(outlines, options)
    angle, shift, S = placement.angle.copy(), placement.shift.copy(), float(side)
    won, tries = 0, 0
    order = np.argsort(areas, kind="stable")
    cum = np.cumsum(areas[order]) / areas.sum()
    while left() > 0 and tries < len(SMALL):
        q = SMALL[tries % len(SMALL)]
        tries += 1
        big = np.ones(k, dtype=bool)
        big[order[cum <= q]] = False
        if big.all() or not big.any():
            continue
        idx = np.flatnonzero(big)
        pl, Sb, _ = compact_square([outlines[i] for i in idx],
                                   Placement(angle[idx], shift[idx], S), S, options, tol,
                                   0.4 * left())
        a, s = angle.copy(), shift.copy()
        a[idx], s[idx] = pl.angle, pl.shift
        turns = base
        if options.rotate == "any" and TURNS == "current":   # each chart's turn as compacted
            turns = [a[i] + np.arange(4) * 90.0 for i in range(k)]
        elif options.rotate == "any" and TURNS == "both":
            turns = [np.unique(np.r_[t, a[i] + np.arange(4) * 90.0] % 360.0)
                     for i, t in enumerate(base)]
        got = None
        for room in ROOM:  # per side tried, smallest first
            T = Sb * room
            if T >= S * (1 - 1e-4) or left() <= 0:
                break
            s2 = s.copy()
            s2[idx] = s[idx] * room
            if room > 1 and not _fits([outlines[i] for i in idx], a[idx], s2[idx], T,
                                      options.padding, options.padding, tol):
                continue
            got = _put_back_all(outlines, areas, turns, a, s2, big, T, options, tol,
                                t0 + seconds)
            if got is not None:
                break
        if log is not None:
            log.append((q, Sb / S, None if got is None else T / S, time.process_time() - t0))
        if got is None:
            continue
        pl, T2, _ = compact_square(outlines, Placement(*got, T), T, options, tol,
                                   max(0.5 * left(), 0.0))
        if T2 < S:
            angle, shift, S = pl.angle, pl.shift, T2
            won += 1
            tries = 0 if won < 4 else tries
    return Placement(angle, shift, S), S, won


def _area(xy):
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
