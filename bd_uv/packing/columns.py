"""Grouped charts in the square: one column per group, side by side.

Each group's charts are nested by spyrrow in a strip of the square's height (the strip's width
minimised), and the groups' strips are set side by side, each starting the separation past the
previous group's charts. So every group holds one rectangle of the square (the bounding box of
its charts) that no other group's chart enters, and inside it the charts pack as densely as
spyrrow packs a strip: only the columns' edges are lost to grouping.

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
DENSITY = 0.55  # the first round's guess of the columns' density
ROOM = 1.25     # a round's separation is the padding of a square this much larger


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
    best, solves, t0 = None, 0, time.perf_counter()
    for r in range(ROUNDS + 8):  # per round; past ROUNDS only until a square is found
        if r >= ROUNDS and best is not None:
            break
        left = max(seconds - (time.perf_counter() - t0), 0.0) / max(ROUNDS - r, 1)
        height, sep, _ = _strip(side, options, tol, ROOM)
        try:
            pl = _columns(outlines, group, g, height, sep, options, left if r < ROUNDS else 0.0)
        except PackError:
            side *= GROWTH
            continue
        solves += g
        found, low = _squares(points, owner, [pl], tol, options.padding)
        if found[0] <= ROOM * side and (best is None or found[0] < best[1]):
            edge = 0.5 * options.padding * found[0] + tol
            best = (Placement(pl.angle, pl.shift - low[0] + edge, pl.width), float(found[0]))
        # the next side: a square strip at the density this round reached (or larger)
        density = area / (height * pl.width)
        fresh = (np.sqrt(area / density) - 2 * tol) / (1 + options.padding * ROOM)
        side = max(float(fresh), least) if r + 1 < ROUNDS else side * GROWTH
    if best is None:
        raise PackError("the nesting found no square layout for these groups of charts")
    return best[0], best[1], solves


def _columns(outlines, group, g, height, sep, options, seconds):
    """Every group nested in a strip of ``height``, the strips side by side ``sep`` apart.
    Returns a Placement whose width is the columns' total width."""
    k = len(outlines)
    angle, shift = np.zeros(k), np.zeros((k, 2))
    x = 0.0
    for b in range(g):  # per group (its column)
        members = np.flatnonzero(group == b)
        sub = [outlines[i] for i in members]
        pl = nest(sub, height, sep, options, seconds * len(members) / k)
        lo, hi = placed_bounds(sub, pl)
        dx = x - lo[:, 0].min()
        angle[members] = pl.angle
        shift[members] = pl.shift + [dx, 0.0]
        x = hi[:, 0].max() + dx + sep
    return Placement(angle, shift, x - sep)
