"""The smallest square found for the charts: spyrrow's strip packing turned into a square.

spyrrow fixes a strip's height H and shortens its width W; a square wants W = H, so H must be
guessed from the density the search will reach. Measured on the charts of closed meshes (see
docs/ARCHITECTURE.md): the density reached is 0.51-0.70 of the strip; a solve's first placement
costs about 15 ms of CPU a chart and every solve starts from scratch, so solves run one after
another (the old search over heights) spend most of a short budget placing; a density guessed
off by a fraction e costs about e of coverage. Hence:

- the density is guessed (0.63 times sqrt(1 - 1/k): fewer charts pack looser; more where the
  search is longer, :func:`searched_density`); no shape measure predicted it better;
- one solve at the guess by default (``solves`` 1), then compaction (:mod:`.compact`) of its
  best square for ``COMPACT_SHARE`` of the time: every further solve pays spyrrow's first
  placement again (1-4 s wall on 27-46 charts under load ~10), and compaction gains more a
  second than spyrrow's search (measured: cow 0.629 -> 0.70 in about 2 s of CPU). With
  ``solves`` 2, a second round at the square strip of the density the first reached; above 2,
  each round runs several at once in threads (spyrrow releases the GIL) at densities spread
  around its guess (-+7 %, then -+2.5 %); under load each gets part of the CPU;
- spyrrow reports each narrower strip it reaches, every one a feasible layout: each is a
  candidate square, so a strip too high still gives the square of the first layout narrower
  than it, not only the last one.
"""
import os
import threading
import time

import numpy as np

from ..errors import PackError
from .ahead import Ahead
from .compact import compact_square
from .few import FEW_MAX
from .large_first import LARGE_FIRST_CHARTS, large_first
from .nest import (EXPLORE, FIT, Placement, _area, _strip, least_squares, nest, rotations,
                   single_layout)
from .refit import EXACT_TOL, ROUNDING, on_exact, refitted

DENSITY_GUESS = 0.63  # strip density expected (measured 0.58-0.70 on 27-46 charts of 5 meshes)
START_PER_CHART = 0.015  # seconds of a solve's first placement per chart (measured, quiet)
HEADROOM = 1.10       # a strip's separation is the padding of a square this much larger
# ... and this much when a solve's search is shorter than its first placement (suzanne: 0.08 s
# of search after 0.4 s of placing): spyrrow can then barely narrow its first layout, and
# suzanne's came out 1.10-1.12 times wider than the strip's square, so most seeds paid a second
# solve (a first placement more: 7 seeds of 8 at load ~9); with 1.2 none did, for the same
# coverage (0.6004 against 0.5995, seeds 0-9) and 20 % less CPU. For every solve (camel searches
# 0.7 s) it lost 1.5-2 % (seeds 0-3): the layouts spyrrow narrows keep the tighter separation
SHORT_HEADROOM = 1.20
# ... but where that search would be under SHORT_SEARCH of a first placement and one re-estimated
# at SHORT_START a chart (measured 2026-11-28 at load 0.3-2: suzanne's 27 charts 0.12-0.17 s, not
# 0.4) leaves a search: that search, HEADROOM, and the compaction's share times SHORT_COMPACT (a
# search gained more a second than the compaction's tail: suzanne 0.596 -> 0.606 over 48 seeds
# at 0.43 -> 0.50 s, elephant 0.681 -> 0.685 over 16; dino, whose search was 0.52 s, even over 24
# seeds for 0.2 s more, hence SHORT_SEARCH; issue18-cover13-2026-11-28.md)
SHORT_SEARCH = 0.5
SHORT_START = 0.0075
SHORT_COMPACT = 0.8
SPREAD = (0.07, 0.025)  # each round's densities: its guess times 1 -+ SPREAD[round]
COMPACT_SHARE = 0.5     # of the time: compaction of the best layout found (.compact)
# above this many charts a compaction step (one linear program over every chart) is too slow to
# pay: measured under load ~11, 400 charts 4 steps in 10 s (+0.6 % coverage), 2,000 charts none
COMPACT_MAX_CHARTS = 200
# up to this many charts each solve runs on one thread (spyrrow's ``num_workers``): on so few,
# spyrrow overshoots its time (the cube's 3 charts asked 0.05-0.3 s take 0.5-1.0 s wall) and a
# second worker only adds CPU; measured on seven meshes of 2-3 charts, seeds 0-9: the same
# coverage within the seeds' spread, the cube 0.85 -> 0.47-0.60 s CPU, the torus 0.6-0.8 ->
# 0.3-0.5 s; eight's 6 charts lost 1 % on one worker over 20 seeds and doubled the spread
# (0.584 sd 0.027 against 0.590 sd 0.012; benchmarks/results/bench_pack-2026-11-27-workers.md)
FEW_CHARTS = 3
# ... and above that, on the coarse path (COARSE_MAX_CHARTS below), the cores but SPARE_CORES,
# shared among the solves at once: spyrrow's workers meet after every step of its search
# (sparrow keeps the best worker's layout), so a worker without a core can hold the others up.
# Measured on the 2-core machine (one worker against two, one solve, interleaved per seed, load
# 1.4-10; issue18-pack22-2026-11-28.md): 16 sets of 7-20 charts, 350 pairs, coverage +0.0059
# (se 0.0010; 207 wins, 129 losses), the same CPU and wall; igl-arm 0.685 -> 0.692; against
# main in separate processes at load ~2.5, 64 pairs: 0.6869 -> 0.6961 (40/23). Off that
# path (21-116 charts, and the large charts of large_first) it was even or lost: cow -0.005
# over 17 pairs, suzanne -0.002, dino +0.005. Not measured idle, nor on more cores (there: one
# worker less than before)
SPARE_CORES = 1
# up to COARSE_MAX_CHARTS charts (:func:`square_layout` asked ``coarse``) spyrrow nests the exact
# outlines simplified by COARSE of the padding at the guessed square (2 px at 4 px, not 0.1 px):
# the long outlines of charts of many faces lose half their points or more (rocker-arm 1,345 ->
# 664, knight 648 -> 280, cheburashka 1,132 -> 547), spyrrow's first placement costs about in
# proportion (rocker-arm 0.17 -> 0.10 s) and its search goes further in its time; the 2 COARSE
# padding more between the nested outlines is then compacted away on the exact outlines. Measured
# (12 seeds each, interleaved, same budget; issue18-packtime13-2026-11-28.md): rocker-arm 0.611
# -> 0.629, knight 0.697 -> 0.709, cesiumman 0.691 -> 0.707, cheburashka 0.697 -> 0.707,
# fancyteapot 0.664 -> 0.670, eight and spot within 0.003; the Utah teapot's 12 charts lost
# 0.004-0.014 (three runs); on more charts the compaction had too many gaps to close in its
# time: homer's 24 charts 0.646 -> 0.631, suzanne's 27 0.602 -> 0.579 (hence COARSE_MAX_CHARTS);
# and where the coarse outlines keep more than COARSE_KEEP of the points, spyrrow gains little
# and the compaction only has more to close (eight's 6 charts, 262 -> 243 points: the same
# coverage, 10-15 % more CPU)
COARSE = 0.5
COARSE_MAX_CHARTS = 20
COARSE_KEEP = 0.7
# On the coarse path the density guessed follows the search time: a strip's height is fixed, and
# once spyrrow's layout is narrower than the strip is high the square is the strip's height, so
# the rest of the search is lost. The guess holds for GUESS_SEARCH seconds of search a chart
# (the adaptive budget gives 0.015 or less); each e-fold more multiplies it by 1 + GUESS_GAIN,
# up to GUESS_MAX; from FEW_MAX + 1 charts (up to 5 the adaptive budget's minimum gives
# 0.035-0.043 s a chart). Measured (issue18-cover16-2026-11-28.md, load 9-10, seeds 0-3): at 4 s
# (0.1 s a chart on igl-elephant's 17) the guess 0.63 gave igl-elephant 0.671-0.716, the same as
# 1 s, and 0.70 gave 0.722-0.732; igl-arm, cheburashka, knight and rocker-arm 0.01-0.04 more.
GUESS_SEARCH = 0.03
GUESS_GAIN = 0.09
GUESS_MAX = 0.70 / 0.63
# A search ended at its square (``reach``) that has not reached it by the end of its exploration
# runs no compression phase (spyrrow's 1/5 of the search time, shrinking the strip by 0.05 % a
# success): the compaction that follows (.compact) gains 2-4 % of the side in a tenth of a
# second. Searches that reach their square end in the exploration and do not change. Measured
# (issue18-pack31-2026-11-29.md; 12 sets of 8-32 charts, 216 pairs interleaved, load 2-4):
# coverage -0.0029 (se 0.0011; 85 wins, 90 losses), nothing lost on the sets nearest the 1.05x
# line (igl-elephant +0.004, camel +0.001, cheburashka -0.000, homer +0.001, igl-arm +0.001,
# knight +0.002, rocker-arm -0.002), where the search does not reach its square CPU -7 to -18 %
# for about 1 % of coverage: igl-bunny 1.22 -> 1.10 s (-0.005), igl-decimated-max 1.81 -> 1.50 s
# (-0.009), igl-fertility 2.06 -> 1.73 s (-0.009), fancyteapot 2.20 -> 1.80 s (-0.010)
SQUARE_COMPRESS = False
# ... and on the coarse path, where a core is spare, its best layout is compacted on a thread
# once its time is over, while spyrrow overruns it (.ahead)
AHEAD = True


def _squares(points, owner, placements, tol, padding):
    """The square side holding each placement's outlines with the padding, and the outlines'
    low corner: (p,) float64 and (p,2) float64."""
    side = np.zeros(len(placements))
    low = np.zeros((len(placements), 2))
    for j, pl in enumerate(placements):  # per candidate layout
        R = rotations(pl.angle)[owner]
        q = np.einsum("nij,nj->ni", R, points) + pl.shift[owner]
        lo, hi = q.min(axis=0), q.max(axis=0)
        side[j] = (float((hi - lo).max()) + 2 * tol) / (1 - padding)
        low[j] = lo
    return side, low


def _solve_all(outlines, sides, options, tol, seconds, headroom=HEADROOM, spare=0,
               square=False, progress=None):
    """One solve per square side, all at once (threads): per side, every feasible layout reached
    (reports, then the result), or None where spyrrow gave up (it panics when it cannot place a
    chart in the strip); the last such refusal (PackError) or None. Each solve searches on
    ``(os.cpu_count() - spare) // len(sides)`` threads (at least one), one up to
    ``FEW_CHARTS`` charts. ``square``: each search ends once its layout is no wider than the
    strip is high (then on this thread for a single side, so that it can: :mod:`.early_stop`),
    without spyrrow's compression phase (``SQUARE_COMPRESS``); ``progress`` (a single side in
    that mode): called with each feasible layout as it is found."""
    out, errors, refused = [None] * len(sides), [], []
    workers = 1 if len(outlines) <= FEW_CHARTS else max(
        1, ((os.cpu_count() or 1) - spare) // len(sides))

    def work(i):
        try:
            height, sep, _ = _strip(sides[i], options, tol, headroom)
            reports = []
            final = nest(outlines, height, sep, options, seconds, reports, workers,
                         narrow=height if square else None,
                         compress=SQUARE_COMPRESS or not square, progress=progress)
            out[i] = reports + [final]
        except PackError as exc:
            refused.append(exc)
        except BaseException as exc:  # handed to the caller's thread
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(len(sides))]
    if square and len(sides) == 1:
        work(0)
        threads = []
    for t in threads:  # per solve
        t.start()
    for t in threads:  # per solve
        t.join()
    if errors:
        raise errors[0]
    return out, (refused[-1] if refused else None)


def square_layout(outlines, options, tol, seconds, exact=None, split=True, coarse=False,
                  reach=1.0, gain=1.0):
    """The smallest square found that holds every outline with the padding.

    The padding scales with the square (it is in texels). A solve packs a strip of height H for
    a square of side S with the separation of a square ``HEADROOM`` S (``SHORT_HEADROOM`` S when
    a round's search is shorter than a first placement), so any of its layouts is a square
    layout of side the placed outlines' larger extent (plus the edges) whenever that is at most
    that larger square. Two rounds, each searching for half the time: (solves + 1) // 2
    solves at once at the sides of the guessed density times 1 -+ ``SPREAD[0]``, then solves // 2
    around the density the solve nearest to a square reached (1 -+ ``SPREAD[1]``);
    ``options.solves`` 1: one solve at the guess. With no square found, sides keep growing
    (first placements only) until one is. Then, up to ``COMPACT_MAX_CHARTS`` charts, the best
    layout is compacted (:func:`.compact.compact_square`) for ``COMPACT_SHARE`` of the time, in
    CPU seconds of this process (the nesting gets the rest, by the clock). From
    ``LARGE_FIRST_CHARTS`` charts (one solve asked, a time to take), the largest charts are laid
    out this way alone first and the others rastered around them (:mod:`.large_first`).

    Parameters
    ----------
    outlines : list of (n_i,2) float arrays
    options : PackOptions
    tol : float, outline simplification tolerance
    seconds : float, the time to take (each solve's first placement is not bounded: it is
        left out of the nesting's share, measured as about ``START_PER_CHART`` seconds a chart)
    exact : list of (m_i,2) float arrays, optional: the outlines before their simplification
        (same frame), compacted instead of the simplified ones (:func:`.refit.on_exact`)
    split : bool, the large charts first where there are many (False: all nested at once)
    coarse : bool, up to ``COARSE_MAX_CHARTS`` charts with ``exact`` outlines: spyrrow nests the
        exact outlines simplified by ``COARSE`` of the padding (:func:`_coarse`) when that keeps
        at most ``COARSE_KEEP`` of the points, the compaction the exact ones
    reach : float, above 1: the nesting may take ``reach`` times its share (the density guessed
        for that search), each search ending once its layout is square (:func:`_solve_all`)
    gain : float, the time taken is ``gain`` times ``seconds`` (nesting and compaction alike,
        the large charts' first too: ``PackOptions.root_gain``)

    Returns
    -------
    Placement (offset to the square's corner included in ``shift``), side, solves
    """
    k = len(outlines)
    if k == 1:
        return (*single_layout(outlines[0], options, tol), 0)
    seconds *= gain
    if (split and LARGE_FIRST_CHARTS <= k <= COMPACT_MAX_CHARTS and seconds > 0
            and options.solves == 1):
        found = large_first(outlines, exact, options, tol, seconds,
                            lambda o, opt, s, ex: square_layout(o, opt, tol, s, ex, split=False))
        if found is not None:
            return found
    area = sum(_area(xy) for xy in outlines)
    given = tol
    if coarse and exact is not None and k <= COARSE_MAX_CHARTS:
        fewer, wider = _coarse(exact, max(tol, COARSE * options.padding
                                          * float(np.sqrt(area / DENSITY_GUESS))))
        coarse = sum(map(len, fewer)) <= COARSE_KEEP * sum(map(len, outlines))
        if coarse:
            outlines, tol = fewer, wider
    else:
        coarse = False
    points = np.concatenate(outlines)
    owner = np.repeat(np.arange(k), [len(xy) for xy in outlines])
    boxes = least_squares(outlines, options)[0]
    widest = float(boxes.max())
    share = COMPACT_SHARE if k <= COMPACT_MAX_CHARTS else 0.0
    nesting = (1 - share) * seconds * reach
    # (solves + 1) // 2 solves at once around the guess, then solves // 2 around the density the
    # one nearest to a square reached
    rounds = 1 if options.solves == 1 else 2
    at_once = [(options.solves + 1) // 2, options.solves // 2]
    dens = DENSITY_GUESS * np.sqrt(1 - 1 / k)
    start = START_PER_CHART * k
    headroom = HEADROOM
    short = False
    if seconds > 0 and (nesting - start * rounds) / rounds < start:
        headroom = SHORT_HEADROOM
        if rounds == 1 and nesting - start < SHORT_SEARCH * start and nesting > SHORT_START * k:
            start, headroom, short = SHORT_START * k, HEADROOM, True
    if coarse and k > FEW_MAX:   # (2-5 charts: see GUESS_SEARCH)
        dens *= searched_density((nesting - start * rounds) / rounds / k)
    # the strip must hold the widest chart with the separation to both its edges: its height is
    # S (1 + p headroom) + 2 tol, the chart's extent at most S (1 - p headroom) - 2 tol
    least = (widest + 2 * tol) / (1 - options.padding * headroom) * FIT[options.rotate]

    def compact(best, clock=time.process_time, cancel=None):
        """The best layout compacted for its share of the time (CPU seconds of ``clock``):
        (Placement, side)."""
        # (no layout is smaller than the widest chart's least square with the padding; sampled
        # every 0.05 degrees, a hair above it)
        big = int(np.argmax(boxes))
        if not coarse:
            fine = float(least_squares([outlines[big]], options, step=0.05)[0][0])
            outl, begin, tl = on_exact(outlines, exact, *best, options, tol)
        else:   # the exact outlines, with the margin on_exact gives them (else the coarse ones)
            margin = max(EXACT_TOL * given, ROUNDING * best[1])
            begin = refitted(exact, best[0], options, margin)
            outl, begin, tl = (exact, begin, margin) if begin is not None else \
                (outlines, best, tol)
            fine = float(least_squares([outl[big]], options, step=0.05)[0][0])
        pl, side, _ = compact_square(outl, *begin, options, tl,
                                     share * (SHORT_COMPACT if short else 1.0) * seconds,
                                     least_side=(fine + 2 * tl) / (1 - options.padding),
                                     clock=clock, cancel=cancel)
        return pl, side

    ahead = None
    if (AHEAD and share and coarse and reach > 1 and rounds == 1 and seconds > 0
            and (os.cpu_count() or 1) > SPARE_CORES):
        ahead = Ahead(compact)
    try:
        best, solves = _rounds(outlines, options, tol, points, owner, area, least, rounds,
                               at_once, nesting, start, headroom, dens, coarse, reach, seconds,
                               ahead)
    except BaseException:
        if ahead is not None:
            ahead.cancel()
        raise
    if not share:
        return best[0], best[1], solves
    # its share of the time, in CPU seconds: compaction of the best layout (done on a thread
    # while the search went on, or now)
    done = ahead.finish(best) if ahead is not None else None
    pl, side = done if done is not None else compact(best)
    return pl, side, solves


def _rounds(outlines, options, tol, points, owner, area, least, rounds, at_once, nesting,
            start, headroom, dens, coarse, reach, seconds, ahead=None):
    """The rounds of solves of :func:`square_layout` (then larger squares, placing only, until
    one is found): the best square layout (Placement offset to the square's corner, side) and
    the solves run. ``ahead``: an :class:`.ahead.Ahead` offered each better square layout of a
    single square-ending search as it is found."""
    t0 = time.perf_counter()
    best, solves, sides = None, 0, [least]
    for r in range(rounds + 8):  # per round; then larger squares, placing only
        if r >= rounds and best is not None:
            break
        # each round's search: an equal share of what is left, less a first placement (measured)
        left = nesting - (time.perf_counter() - t0) - start * max(rounds - r, 1)
        search = max(left / (rounds - r), 0.0) if r < rounds and seconds > 0 else 0.0
        # the sides of square strips at the densities (after the rounds: the density reached,
        # aiming at a strip as wide as high, and 5 % larger at least, until a square is found;
        # aiming 5 % below it gave eight 0.571 coverage, 8 seeds, against 0.588, suzanne 0.593
        # against 0.595: a strip too high leaves the first layout a band the compaction fills
        # badly)
        grow = r >= rounds
        spread = np.linspace(-1, 1, at_once[r]) if not grow and at_once[r] > 1 else 0.0
        dens = np.atleast_1d(dens) * (1 + SPREAD[min(r, 1)] * spread)
        fresh = (np.sqrt(area / dens) - 2 * tol) / (1 + options.padding * headroom)
        sides = [max(float(s), least, 1.05 * max(sides) if grow else 0.0) for s in fresh]
        t1 = time.perf_counter()
        square = reach > 1 and r < rounds
        offer = _offer(points, owner, tol, options, sides[0], headroom, ahead, search) if (
            square and ahead is not None and len(sides) == 1) else None
        runs, refused = _solve_all(outlines, sides, options, tol, search,
                                   **({} if headroom == HEADROOM else {"headroom": headroom}),
                                   **({"spare": SPARE_CORES} if coarse else {}),
                                   **({"square": True, "progress": offer} if square else {}))
        start = max(time.perf_counter() - t1 - search, 0.0)
        solves += len(sides)
        # all refused: larger sides (by 1.1, and 1.05 more for the larger squares after the
        # rounds)
        nearest, dens = np.inf, float(np.min(dens)) / (1.1 if r + 1 < rounds else 1.155)
        for side, found in zip(sides, runs):  # per solve
            if found is None:
                continue
            squares, low = _squares(points, owner, found, tol, options.padding)
            height = _strip(side, options, tol, headroom)[0]
            if abs(np.log(found[-1].width / height)) < nearest:   # the next round's density
                nearest = abs(np.log(found[-1].width / height))
                dens = area / (height * found[-1].width)
            fit = np.flatnonzero(squares <= headroom * side)
            if not len(fit):
                continue
            j = fit[np.argmin(squares[fit])]
            if best is None or squares[j] < best[1]:
                edge = 0.5 * options.padding * squares[j] + tol
                pl = found[j]
                best = (Placement(pl.angle, pl.shift - low[j] + edge, pl.width), squares[j])
    if best is None:
        raise refused or PackError("the nesting found no square layout for these charts")
    return best, solves


def _offer(points, owner, tol, options, side, headroom, ahead, search):
    """A search's progress callback: each feasible layout that makes a better square (as
    :func:`_rounds` picks them from its reports) offered to ``ahead``, which starts none before
    the search's time is over (its first report, the first placement's, plus the exploration's
    share of ``search``: no compression phase follows, ``SQUARE_COMPRESS``)."""
    least, first = [np.inf], [True]

    def progress(pl):
        if first[0]:
            first[0] = False
            ahead.start_after(time.perf_counter()
                              + (1.0 if SQUARE_COMPRESS else EXPLORE) * search)
        squares, low = _squares(points, owner, [pl], tol, options.padding)
        if squares[0] <= headroom * side and squares[0] < least[0]:
            least[0] = squares[0]
            edge = 0.5 * options.padding * squares[0] + tol
            ahead.offer((Placement(pl.angle, pl.shift - low[0] + edge, pl.width), squares[0]))
    return progress


def searched_density(per_chart):
    """The factor on the guessed density for a first round searching ``per_chart`` seconds a
    chart: 1 up to ``GUESS_SEARCH``, then 1 + ``GUESS_GAIN`` a e-fold more, at most
    ``GUESS_MAX``."""
    if not per_chart > GUESS_SEARCH:
        return 1.0
    return float(min(1 + GUESS_GAIN * np.log(per_chart / GUESS_SEARCH), GUESS_MAX))


def _coarse(exact, tol):
    """The exact outlines simplified by ``tol`` (Douglas-Peucker: every point of each within
    ``tol`` of its simplified one, so simplified outlines ``sep`` apart keep the exact ones
    ``sep - 2 tol`` apart, as :mod:`.outlines` does at 0.1 texel), counter-clockwise, in the
    same frame: (outlines, tol)."""
    import shapely
    out = []
    for xy in exact:  # per chart
        ring = shapely.simplify(shapely.Polygon(xy), tol, preserve_topology=True)
        out.append(np.asarray(shapely.get_coordinates(shapely.orient_polygons(ring)))[:-1])
    return out, tol
