"""Many charts: the largest nested and compacted alone, the small ones rastered into the room
left, then every chart compacted together.

On many charts (cow: 45, the largest 6 holding 80 % of the area), spyrrow's short search spends
its moves on every chart alike and a first placement costs about 15 ms a chart, while the
square's side is set by how the few large charts interlock. Measured on cow, with all 45 charts
at the product's budget, spyrrow's first placement was already narrower than the strip was high
(0.95 of it): its search narrowed the strip further and never shrank the square (the same
coverage with no search, 0.697 against 0.698, seeds 0-7). Nested alone, the large charts get
the whole search; the small ones then fill the pockets and bands the large ones leave, and the
compaction (:mod:`.compact`) closes what the raster left.

1. the largest charts holding ``LARGE_SHARE`` of the area (at least ``LARGE_LEAST``), and the
   charts longer than ``LONG`` of the side the charts' area would fill at ``DENSITY``, get a
   square layout of their own (``nested``: :func:`.square.square_layout` with its compaction)
   for ``LARGE_TIME`` of the time, with the padding of a square ``LARGE_HEADROOM`` larger (so
   the square may grow that much around them with every gap still the padding);
2. the others, largest first, go into the free cells of that square at the lowest offset
   (:func:`.around._place`, conservative: cells of charts that do not meet are the padding
   apart); while they do not all fit, the square grows by ``GROW`` (beyond the headroom the
   large charts' shifts grow with it, which keeps them inside and, checked exactly, apart);
   where that took ``TURN_STEPS`` growths or more, the large charts' layout turned by quarter
   turns is tried too at the smaller sides (``QUARTERS``);
   where the small charts went into a band the growth opened rather than into the large
   charts' pockets (the square holds less of its area than the large charts held of theirs,
   :func:`_loose`), the largest holding ``WIDE_SHARE`` are nested again instead, for
   ``WIDE_TIME`` of their time (taken from the compaction), the rest rastered around them, and
   the smaller square of the two kept (the quarter turns then tried on the second only);
3. every chart is compacted from there for the rest of the time (less the turned tries, or
   the second nesting with its raster and turns: at most half of it).
"""
import time
from dataclasses import replace

import numpy as np

from .around import _candidates, _place
from .compact import compact_square
from .nest import Placement, _area, _hull_vertices, least_squares, rotations
from .refit import fits, on_exact
from .relocate import occupied

LARGE_FIRST_CHARTS = 40   # from this many charts (see docs: camel 29 and homer 24 lost 1-3 %)
LARGE_SHARE = 0.8         # the largest charts holding this share of the area are nested alone
LARGE_LEAST = 6           # ... at least this many
LARGE_TIME = 0.5          # of the time: their nesting and compaction
REST_TIME = 0.35          # ... and the compaction of every chart after the raster
LARGE_HEADROOM = 1.4      # their padding is that of a square this much larger
CELLS = 256               # raster cells along the square's side for the small charts
GROW = 1.02               # the square's growth while the small charts do not fit
GROW_TRIES = 30
# where the small charts needed TURN_STEPS growths or more (8 %), the large charts' layout is
# also tried turned by one, two and three quarter turns about its square's centre, at the smaller
# sides, the least side first; the time it takes is taken from the compaction after it. Measured
# (8 seeds, the compaction's inputs cached): camel at C = 1.5 0.712 -> 0.742 (8/0), cow
# subdivided twice 0.662 -> 0.701 (7/1), armadillo 0.659 -> 0.665, cow 0.731 -> 0.733 and dino
# at C = 1.5 0.700 -> 0.698 (their growth is mostly under 8 %); for every set (no gate, the time
# not taken back) cow lost 0.3 % for 0.2 s more. At most half the compaction's time is taken
QUARTERS = 4
TURN_STEPS = 4
# ... and so is every chart longer than LONG of the side of the square of the charts' area at
# DENSITY: rastered with the small charts, cow subdivided twice's two strips (a third of that side
# long, 2 % of the area each) found room only in a band above the large charts after the square
# grew 10-15 %: 0.683 -> 0.646 over 6 seeds against all charts nested at once; nested with the
# large ones, 0.679. Of the other sets of 40+ charts (cow, dino and camel at C = 1.5, armadillo,
# ChineseDragon, the shader ball) none has a small chart longer than 0.23 of that side
LONG = 0.3
DENSITY = 0.68
# where the small charts left the square looser than the large ones left theirs (more than LOOSE
# of it), the largest holding WIDE_SHARE are nested again. Measured on real low-poly assets of
# many charts (issue18-many24-2026-11-28.md, load 8-15, seeds 0-3, every set at 0.95 at once):
# the Spider's 63 charts (legs: five small charts 0.2-0.3 of the side long) 0.598 -> 0.681 for
# less CPU (its fill grew the square 15 %), Wuson's 83 0.646 -> 0.669, max3ds's 93 0.633 ->
# 0.658; but cow's 45 lost 0.733 -> 0.668 at 0.95 (its small charts fill the pockets of its 6
# large ones: the square grew 4 %, the fill left it denser than the large charts alone), hence
# the test on the fill rather than one share for all. LOOSE: with any loss at all (0) the
# Chinese dragon's 116 charts went there too (its fill 1.7 % looser) and lost 0.622 -> 0.599
# (seeds 0-1) for 25 % more CPU; max3ds (2.3 % looser) gained nothing over seeds 0-4 (0.615 ->
# 0.614); the Spider's and Wuson's fills are 5-15 % looser (Wuson.off and wuson.stl go to .tiny
# since pack25: 60 % of their charts are tiny)
WIDE_SHARE = 0.95
LOOSE = 0.035
# ... for WIDE_TIME of the time, all of it (the nesting, its raster and turns) taken from the
# compaction (at most half of it): Wuson seeds 0-5 0.674 at 2.56 s CPU (main 0.627 at 2.68 s,
# seeds 0-3), the Spider 0.635 at 1.6 s (main 0.589 at 2.06 s); with the first nesting's time
# and only the excess taken, 0.684 and 0.652 for 20-25 % more CPU than main (load 9-15). At
# load ~3 the nesting gets its whole clock time: Wuson 0.642 -> 0.671 for 19 % more time, the
# Spider 0.641 -> 0.706 for 1.4 -> 2.1 s (with its larger budget, options.MANY_CHARTS)
WIDE_TIME = 0.6


def large_first(outlines, exact, options, tol, seconds, nested):
    """A square layout of many charts, the large ones nested first (module docstring).

    Parameters
    ----------
    outlines : list of (n_i,2) float arrays, centred simplified outlines
    exact : list of (m_i,2) float arrays or None, the outlines before simplification
    options : PackOptions
    tol : float, outline simplification tolerance
    seconds : float, the time to take
    nested : callable(outlines, options, seconds, exact) -> (Placement, side, solves): the
        square layout (nesting and compaction) of a subset of the charts

    Returns
    -------
    (Placement, side, solves), or None when the small charts found no room
    """
    k = len(outlines)
    area = np.array([_area(o) for o in outlines])
    order = np.argsort(-area, kind="stable")
    cum = np.cumsum(area[order]) / area.sum()
    long = _diameters(outlines) >= LONG * np.sqrt(area.sum() / DENSITY)
    turns = _candidates(outlines, options)
    got = _split(outlines, exact, options, tol, seconds, nested, order, cum, long, turns,
                 LARGE_SHARE)
    if got is None:
        return None
    spent, solves = 0.0, got[-1]
    if WIDE_SHARE > LARGE_SHARE and _loose(got, area):   # the small ones went to a band
        t0 = time.process_time()
        wide = _split(outlines, exact, options, tol, WIDE_TIME * seconds, nested, order, cum,
                      long, turns, WIDE_SHARE)
        if wide is not None:
            solves += wide[-1]
            wide, spent = _turned_fill(wide, outlines, turns, options, tol)
            if wide[0] <= got[0]:
                got = wide
        spent = time.process_time() - t0
    else:
        got, spent = _turned_fill(got, outlines, turns, options, tol)
    side, large, small, turned, placed = got[:5]
    angle, shift = np.zeros(k), np.zeros((k, 2))
    angle[large], shift[large] = turned.angle, turned.shift
    angle[small], shift[small] = placed[0], placed[1] * side
    # the rest of the time (CPU seconds of this process, as the compaction counts it)
    left = REST_TIME * seconds - min(max(spent, 0.0), 0.5 * REST_TIME * seconds)
    widest = int(np.argmax(least_squares(outlines, options)[0]))
    fine = float(least_squares([outlines[widest]], options, step=0.05)[0][0])
    outl, start, tol2 = on_exact(outlines, exact, Placement(angle, shift, side), side, options,
                                 tol)
    pl, side, _ = compact_square(outl, *start, options, tol2, left,
                                 least_side=(fine + 2 * tol) / (1 - options.padding))
    return pl, side, solves


def _split(outlines, exact, options, tol, seconds, nested, order, cum, long, turns, share):
    """The largest charts holding ``share`` of the area (at least ``LARGE_LEAST``, and the long
    ones) nested alone, the others rastered around them at the least growth (no turn of the
    large charts' layout yet): (side, large, small, the large charts' Placement, the small
    ones' (angle, shift), the nested square S, growths, the large charts' Placement in S,
    solves), or None (no small chart, or no room found)."""
    n_large = max(int(np.searchsorted(cum, share)) + 1, LARGE_LEAST)
    long = long.copy()
    long[order[:n_large]] = True
    large, small = order[long[order]], order[~long[order]]
    if not len(small):
        return None
    roomy = replace(options, padding_px=options.padding_px * LARGE_HEADROOM)
    pl, S, solves = nested([outlines[i] for i in large], roomy, LARGE_TIME * seconds,
                           None if exact is None else [exact[i] for i in large])
    own = [outlines[i] for i in large]
    part = [outlines[i] for i in small]
    for j in range(GROW_TRIES):  # per side tried, the layout as it is
        got = _try(own, part, pl, S, S * GROW ** j, [turns[i] for i in small], options, tol,
                   (0,))
        if got is not None:
            return (got[0], large, small, got[1], got[2], S, j, pl, solves)
    return None


def _loose(got, area):
    """Whether the small charts of ``_split``'s layout ``got`` left the square looser than the
    large charts alone left theirs (their area over the square's: grown into a band rather than
    held in the large charts' pockets), by more than ``LOOSE`` of it."""
    side, large, S = got[0], got[1], got[5]
    return area.sum() / side ** 2 < (1 - LOOSE) * area[large].sum() / S ** 2


def _turned_fill(got, outlines, turns, options, tol):
    """``_split``'s layout, and where it took ``TURN_STEPS`` growths or more, the large charts'
    layout turned by one to three quarter turns about its square's centre at the smaller sides,
    the least side first (the first that holds the small charts): (the layout, CPU seconds)."""
    side, large, small, _, _, S, steps, pl, solves = got
    if steps < TURN_STEPS:
        return got, 0.0
    t0 = time.process_time()
    own = [outlines[i] for i in large]
    part = [outlines[i] for i in small]
    for j in range(steps):  # per smaller side: the other turns
        found = _try(own, part, pl, S, S * GROW ** j, [turns[i] for i in small], options, tol,
                     range(1, QUARTERS))
        if found is not None:
            return ((found[0], large, small, found[1], found[2], S, j, pl, solves),
                    time.process_time() - t0)
    return got, time.process_time() - t0


def _diameters(outlines):
    """(k,) float: each outline's diameter (the longest distance between two of its points)."""
    from scipy.spatial.distance import pdist
    out = np.zeros(len(outlines))
    for i, xy in enumerate(outlines):  # per chart: its hull's vertices
        hull = xy.take(_hull_vertices(xy), axis=0)
        out[i] = pdist(hull).max() if len(hull) > 1 else 0.0
    return out


def _turned(angle, shift, side, quarter):
    """Charts at ``angle``, ``shift`` in the square [0, side]^2 turned by ``quarter`` quarter
    turns about its centre: a Placement."""
    c = np.array([0.5 * side, 0.5 * side])
    R = rotations([90.0 * quarter])[0]
    return Placement((angle + 90.0 * quarter) % 360.0, (shift - c) @ R.T + c, side)


def _try(own, part, pl, S, side, turns, options, tol, quarters):
    """The small charts rastered around the large ones at ``side`` (their shifts scaled with
    it beyond the headroom), the large charts' layout turned by each of ``quarters`` in turn
    about the centre of [0, S]^2: (side, the large charts' Placement, the small ones' (angle,
    shift)) at the first where they fit, or None."""
    h = 1.0 / CELLS
    reach = 0.5 * options.padding + tol / side + h * np.sqrt(0.5)
    for quarter in quarters:  # per turn of the large charts' layout
        turned = _turned(pl.angle, pl.shift, S, quarter)
        shift = turned.shift * max(side / (S * LARGE_HEADROOM), 1.0)
        if not fits(own, turned.angle, shift, side, options.padding, options.padding, tol):
            continue
        R = rotations(turned.angle)
        occ = occupied([(o @ R[j].T + shift[j]) / side for j, o in enumerate(own)], reach,
                       CELLS)
        got = _place(occ, part, turns, np.arange(len(part)), 1.0 / side, options, tol)
        if got is not None:
            return side, Placement(turned.angle, shift, side), got
    return None
