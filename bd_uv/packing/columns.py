"""Grouped charts in the square: one column per group, side by side, in one or more rows.

Each group's charts are nested by spyrrow in a strip of its row's height (the strip's width
minimised), and the groups' strips are set side by side, each starting the separation past the
previous group's charts; rows are stacked the same way. So every group holds one rectangle of the
square (the bounding box of its charts) that no other group's chart enters, and inside it the
charts pack as densely as spyrrow packs a strip: only the columns' edges are lost to grouping.
With many groups, full-height columns of a few charts each are mostly empty, so the columns are
set in rows about as high as the median group's own square would be, sqrt(all charts' area over
the median group's) of them (one row for a few groups of similar size), the groups dealt to the
rows by area, largest first, to the row holding the least. A group of one chart is set at its
least-square turn without a nesting.

As for ungrouped charts (:mod:`.square`), the square's side is guessed from the charts' area, the
strips are made for that side (the separation the padding of a square ``ROOM`` times
larger), and a second round is run at the side of a square strip for the density the first
reached; every round whose layout fits a square at most ``ROOM`` times its side is a
candidate, the smallest kept.
"""
import time

import numpy as np

from ..errors import PackError
from .nest import FIT, Placement, _area, _strip, least_squares, nest, placed_bounds
from .square import _squares

ROUNDS = 2      # rounds of strips: the guess, then the square strip of the density reached
GROWTH = 1.15   # the side's growth when no round found a square (or a chart did not fit)
# The first round's guess of the columns' density, and a round's separation: the padding of a
# square ROOM times larger. A round whose square comes out larger is refused, and under time
# pressure the second round (first placements only) may do worse than the first: measured on
# suzanne's 27 charts in 3 groups (load 9), 0.55 and 1.25 gave 0.28-0.44 coverage, 0.45 and 1.35
# gave 0.45 three times (cow: 0.437 against 0.452)
DENSITY = 0.45
ROOM = 1.35
MIN_SEARCH = 0.25   # seconds: a group's shorter search share is dropped (measured under load:
                    # a 0.1 s search of 3 charts took 0.15-1.0 s, its first placement 0.04-0.11 s)
ROW_SCALE = 1.0     # rows: sqrt(all charts' area / the median group's area) / ROW_SCALE
                    # (measured 1.5: 30 boxes in 10 groups 0.645 against 0.623, 60 in 20
                    # groups 0.406 against 0.626)


def column_layout(outlines, group, options, tol, seconds):
    """Charts in one column per group (module docstring).

    Parameters
    ----------
    outlines : list of (n_i,2) float arrays, centred chart outlines
    group : (k,) int array, group of each chart (0..g-1)
    options : PackOptions
    tol : float, outline simplification tolerance
    seconds : float, the search time, shared by the rounds, each round's shared by the groups'
        chart counts

    Returns
    -------
    Placement (offset to the square's corner included in ``shift``), side, solves
    """
    group = np.asarray(group, dtype=np.int64)
    k, g = len(outlines), int(group.max()) + 1
    area = sum(_area(xy) for xy in outlines)
    widest = float(least_squares(outlines, options)[0].max())
    least = (widest + 2 * tol) / (1 - options.padding * ROOM) * FIT[options.rotate]
    points = np.concatenate(outlines)
    owner = np.repeat(np.arange(k), [len(xy) for xy in outlines])
    side = max(float(np.sqrt(area / DENSITY)), least)
    # rows: about as high as the median group's own square (one row for a few similar groups)
    group_area = np.bincount(group, weights=[_area(xy) for xy in outlines], minlength=g)
    rows = max(1, int(np.sqrt(area / np.median(group_area)) / ROW_SCALE))
    solves = 0
    best, t0 = None, time.perf_counter()
    for r in range(ROUNDS + 8):  # per round; past ROUNDS only until a square is found
        if r >= ROUNDS and best is not None:
            break
        left = max(seconds - (time.perf_counter() - t0), 0.0) / max(ROUNDS - r, 1)
        height, sep, _ = _strip(side, options, tol, ROOM)
        try:
            # (no more rows than hold the widest chart each)
            pl = _columns(outlines, group, g, height, sep, options,
                          left if r < ROUNDS else 0.0, max(1, min(rows, int(side / least))))
        except PackError:
            side *= GROWTH
            continue
        solves += g
        found, low = _squares(points, owner, [pl], tol, options.padding)
        if found[0] <= ROOM * side and (best is None or found[0] < best[1]):
            edge = 0.5 * options.padding * found[0] + tol
            best = (Placement(pl.angle, pl.shift - low[0] + edge, pl.width), float(found[0]))
        # the next side: a square strip at the density this round reached (or larger)
        lo, hi = placed_bounds(outlines, pl)
        density = area / float(np.prod(hi.max(axis=0) - lo.min(axis=0)))
        fresh = (np.sqrt(area / density) - 2 * tol) / (1 + options.padding * ROOM)
        side = max(float(fresh), least) if r + 1 < ROUNDS else side * GROWTH
    if best is None:
        raise PackError("the nesting found no square layout for these groups of charts")
    return best[0], best[1], solves


def _columns(outlines, group, g, height, sep, options, seconds, rows=1):
    """Every group nested in a strip of ``height / rows``, the strips side by side ``sep`` apart
    in ``rows`` rows (groups dealt by area, largest first, to the row holding the least), the
    rows stacked ``sep`` apart. Returns a Placement whose width is the widest row's."""
    k = len(outlines)
    area = np.array([_area(xy) for xy in outlines])
    group_area = np.bincount(group, weights=area, minlength=g)
    row_of, load = np.zeros(g, dtype=np.int64), np.zeros(rows)
    for b in np.argsort(-group_area, kind="stable"):  # per group, largest first
        row_of[b] = int(np.argmin(load))
        load[row_of[b]] += group_area[b]
    angle, shift = np.zeros(k), np.zeros((k, 2))
    y, width = 0.0, 0.0
    for r in range(rows):  # per row
        x, in_row = 0.0, np.flatnonzero(row_of[group] == r)
        for b in np.flatnonzero(row_of == r):  # per group of the row (its column)
            members = np.flatnonzero(group == b)
            sub = [outlines[i] for i in members]
            if len(sub) == 1:    # a lone chart: at its least square's turn
                turn = least_squares(sub, options)[1]
                pl = Placement(turn, np.zeros((1, 2)), 0.0)
            else:   # (a share too short to search is left to the first placement)
                share = seconds * len(members) / k
                pl = nest(sub, height / rows, sep, options, share if share >= MIN_SEARCH else 0.0)
            lo, hi = placed_bounds(sub, pl)
            dx = x - lo[:, 0].min()
            angle[members] = pl.angle
            shift[members] = pl.shift + [dx, 0.0]
            x = hi[:, 0].max() + dx + sep
        if not len(in_row):
            continue
        lo, hi = placed_bounds([outlines[i] for i in in_row],
                               Placement(angle[in_row], shift[in_row], 0.0))
        shift[in_row, 1] += y - lo[:, 1].min()
        y += hi[:, 1].max() - lo[:, 1].min() + sep
        width = max(width, x - sep)
    return Placement(angle, shift, width)
