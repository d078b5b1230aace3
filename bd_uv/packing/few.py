"""A few charts (2 to ``FEW_MAX``) into the smallest square in tens of milliseconds, without
spyrrow.

spyrrow (:mod:`.nest`) overshoots tiny search requests: Blender's cube (3 charts) asked for about
0.1 s of search took 0.5-1.0 s whatever its budget (its first placement alone: 20-40 ms; sparrow
checks its clock only between its separator's strikes, each a fixed count of iterations, and
spyrrow 0.9 exposes no iteration limit), and a cube is packed at every unwrap of one
(glTF-Transform's many-cubes.gltf: 501 of them). Here:

- each chart is turned to a few candidate angles (its least-area box and least-square box turns
  and their quarter turns; quarter turns for ``rotate`` 90, none for none; never a mirror) and
  grown by half the separation at a guessed side (a mitred buffer holds every point that close);
- layouts drop the charts one by one into a strip onto conservative step profiles of those
  already placed (:mod:`.drops`: true shapes, not boxes), each where its top ends lowest, for
  ``STRIPS`` widths and every order (up to 4 charts; else ``ORDERS`` from the seed) at once,
  all on a coarse grid (``GRID_COARSE`` cells across the guess), the ``KEEP`` best again on the
  fine grid (``GRID``);
- the best is moved chart by chart left and down by exact GEOS distances at the separation of the
  square reached (:func:`_settle`: the grid's slack and the guessed separation's excess go), checked
  exactly (every pair apart by the separation, every point inside), then compacted by
  ``COMPACT_PROGRAMS`` linear programs (:mod:`.compact`, a count: the layout is deterministic).

When the square reached needs more separation than the charts were grown by, again at that
square; None when nothing holds (the caller nests with spyrrow). Measured against spyrrow in
benchmarks/results/bench_pack-2026-11-27-fewpack.md.
"""
import itertools

import numpy as np

from .compact import compact_square
from .drops import Turns, strip_fills
from .nest import Placement, rotations
from .refit import on_exact

# up to this many charts. Measured (seeds 0-2, load 9-13, subsets of eight's 6 and face's 7
# charts): 5 charts, mean coverage 0.609 / 0.595 / 0.658 against spyrrow's 0.594 / 0.548 / 0.623
# in about its CPU (0.42-0.59 s against 0.28-0.70 s); 6 charts even on average (0.570 / 0.638 /
# 0.686 / 0.682 against 0.574 / 0.658 / 0.689 / 0.688), so spyrrow keeps 6 and more; 2-4 charts
# take 2-4x less CPU than spyrrow
FEW_MAX = 5
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


def few_square(outlines, options, tol, exact=None):
    """The smallest square found for 2 to ``FEW_MAX`` outlines: :func:`few_layout`, then
    ``COMPACT_PROGRAMS`` compaction steps (:func:`.compact.compact_square`; of the ``exact``
    outlines when given, :func:`.refit.on_exact`). Returns (Placement with shift to the
    square's corner, side, 0 solves), or None (another count of charts, or no layout found)."""
    found = few_layout(outlines, options, tol)
    if found is None:
        return None
    outlines, found, tol = on_exact(outlines, exact, *found, options, tol)
    pl, side, _ = compact_square(outlines, *found, options, tol, np.inf,
                                 max_programs=COMPACT_PROGRAMS)
    return pl, side, 0


def few_layout(outlines, options, tol):
    """The smallest square found for a few outlines (up to ``FEW_MAX``), or None.

    The separation between two outlines is ``padding`` S + 2 ``tol`` for the square's side S,
    and half of it to the square's edge, as :func:`.square.square_layout` keeps. S is guessed
    and the charts grown by half the separation at it; every order and strip width run on a coarse
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
        found = []
        for fine in (False, True)[:1 + (KEEP > 0)]:  # coarse, then fine
            grid = GRID if fine else GRID_COARSE
            h = guess / grid
            turns = [Turns(i, g, h) for i, g in enumerate(grown)]
            if not fine:
                narrow = max(int(t.ncol.min()) for t in turns)
                widths = np.unique(np.linspace(narrow, STRIP_MAX * grid, STRIPS).round())
                runs = [(order, int(w)) for order in orders for w in widths]
            else:   # the best coarse runs, on the fine grid (the same strip widths)
                runs = [(order, w * (GRID // GRID_COARSE))
                        for _, _, (order, w), _, _ in sorted(found, key=lambda f: f[:2])[:KEEP]]
            laid = strip_fills(turns, runs, h)
            found = [(side, n, run, placed, turns)
                     for n, (run, (side, placed)) in enumerate(zip(runs, laid))
                     if np.isfinite(side)]
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
