"""Nesting chart outlines with spyrrow (sparrow, an irregular strip-packing heuristic).

spyrrow packs polygons into a strip of fixed height, minimising its width, with any rotation (or a
list of angles) and a least separation between items. A square needs a search over the strip
height (:mod:`.square`); :func:`tile_layouts` fills UDIM tiles of a fixed size one after another.
Placements are turns and translations only (a rotation matrix has determinant +1: never a mirror).
"""
from dataclasses import dataclass
from datetime import timedelta

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from ..errors import PackError
from .early_stop import solve_until

# An outline too thin for spyrrow is grown to this fraction of the strip's height (with no
# padding: "Offset resulted in an empty polygon" when spyrrow offsets a sliver inwards)
EMPTY_RETRY = 1e-3
FEASIBLE = (0, 3, 4)  # spyrrow's ReportType of feasible layouts: ExplFeas, CmprFeas, Final
# Room the least side leaves the widest chart: spyrrow samples spots and gives up (a panic:
# "strip-width is running away, item does not seem to fit") when a chart has under about 1 % of
# the strip's height to spare at its only allowed turns (found by the atlas fuzz contract:
# slivers at 22 px padding on 179 px, huge with tiny charts at 4 px on 128 px, rotate none)
FIT = {"any": 1.01, "90": 1.03, "none": 1.03}
# spyrrow finds no pole of inaccessibility ("no pole found with 10 levels of recursion", a panic
# whose text Rust prints on stderr even when it is caught) for an outline thinner than about
# 1/1000 of its length (measured: a 1:1000 rectangle nests, 1:3300 panics; a 1:1000 triangle
# can panic); such outlines, and outlines that pass a vertex twice in float32, are grown by
# at least EMPTY_RETRY of the height before they are nested
THIN = 1e-3
# Depth of the quadtree of spyrrow's collision engine (jagua-rs; spyrrow's default 4). At 3 its
# search reached denser layouts in the same wall time on the charts of closed meshes: measured
# at the default budget (issue18-pack21-2026-11-28.md, seeds 0-7, interleaved, load 2-8), 16
# sets of 7-20 charts +0.0057 coverage (se 0.0014; 64 wins, 40 losses, the same CPU), 10 sets of
# 24-116 charts +0.0006 (se 0.0020; 13/13); 5 gave 0.003 less than 4 (seed 0, 16 sets)
QUADTREE_DEPTH = 3
EXPLORE = 0.8   # of a search's time, spyrrow's exploration (the rest its compression, as it does)


@dataclass(frozen=True)
class Placement:
    """Where the nesting put each chart's outline (centred coordinates, strip units).

    Attributes
    ----------
    angle : (k,) float64, turn of each chart in degrees (counter-clockwise)
    shift : (k,2) float64, translation after the turn
    width : float, the strip width used
    """
    angle: np.ndarray
    shift: np.ndarray
    width: float


def rotations(angle):
    """(k,2,2) rotation matrices of angles in degrees (determinant +1)."""
    t = np.deg2rad(np.asarray(angle, dtype=np.float64))
    c, s = np.cos(t), np.sin(t)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def nest(outlines, height, separation, options, seconds=0.0, reports=None, workers=None,
         retry=True, narrow=None, compress=True, progress=None):
    """One spyrrow solve: every outline in a strip of ``height``, ``separation`` apart.

    Parameters
    ----------
    outlines : list of (n_i,2) float arrays, centred simple polygons
    height : float
    separation : float, least distance between two outlines
    options : PackOptions (orientations, seed)
    seconds : float, time for the search after the first placement (0: that placement only),
        split 4:1 between exploration and compression as spyrrow does (``compress`` False: the
        exploration's share only, no compression: :data:`.square.SQUARE_COMPRESS`)
    reports : list, optional: every feasible layout the search passes through is appended to it
        as a Placement (a narrower strip is a better one; the last is the result)
    workers : int, optional: threads of spyrrow's search (default: one per core)
    retry : bool, nest the outlines grown by half the separation with none between
        (:func:`_nest_grown`), and after a panic grown by a hair; False: as given
    narrow : float, optional (with ``reports``): the search ends at the first feasible layout
        this narrow where it can (:mod:`.early_stop`)
    compress : bool, spyrrow's compression phase after its exploration (False: none)
    progress : callable, optional (with ``narrow``): called with each feasible layout (a
        Placement, as in ``reports``) as the search reaches it, on another thread

    Returns
    -------
    Placement, with x in [0, width] and y in [0, height] for every outline point
    """
    import spyrrow
    if retry:
        # the separation is never left to spyrrow: its own offset of an outline by half the
        # separation made polygons with duplicate vertices ("Simple polygon has non-consecutive
        # duplicate vertices": a 49-point chart of OpenChessSet, its points closer together
        # than the separation) and an empty strip from a sliver ("Offset resulted in an empty
        # polygon"); both panics were caught and nested grown, Rust's text printed on stderr
        grow = separation
        if any(_thin(xy) for xy in outlines):
            grow = max(separation, EMPTY_RETRY * height)
        if grow > 0:
            return _nest_grown(outlines, height, grow, options, seconds, reports, workers,
                               narrow, compress, progress)
    items = [spyrrow.Item(str(i), [tuple(p) for p in xy], demand=1,
                          allowed_orientations=options.orientations())
             for i, xy in enumerate(outlines)]
    inst = spyrrow.StripPackingInstance("bd_uv", float(height), items)
    cfg = spyrrow.StripPackingConfig(
        early_termination=True, min_items_separation=float(separation) if separation > 0
        else None, seed=options.seed, total_computation_time=None, exploration_time=0,
        compression_time=0, num_workers=workers, quadtree_depth=QUADTREE_DEPTH)
    # spyrrow's constructor takes whole seconds; its attributes take any duration
    cfg.exploration_time = timedelta(seconds=EXPLORE * seconds)
    cfg.compression_time = timedelta(seconds=(1 - EXPLORE) * seconds if compress else 0.0)
    queue = spyrrow.ProgressQueue() if reports is not None else None
    drained = None
    try:
        if queue is not None and narrow is not None:
            sol, drained, _ = solve_until(
                inst, cfg, queue, FEASIBLE, narrow,
                None if progress is None else lambda s: progress(_placement(s, len(outlines))))
        else:
            sol = inst.solve(cfg, queue) if queue is not None else inst.solve(cfg)
    except BaseException as exc:  # a Rust panic arrives as pyo3's PanicException (BaseException)
        if type(exc).__name__ != "PanicException":
            raise
        first = (str(exc).strip().splitlines() or [""])[0]   # no Rust backtrace in a message
        if retry:
            # (a chart's outline too thin for its pole of inaccessibility, "no pole found": a
            # bishop of OpenChessSet; outlines are nested grown by a hair of the height)
            return _nest_grown(outlines, height, EMPTY_RETRY * height, options, seconds,
                               reports, workers, narrow, compress, progress)
        raise PackError(f"the nesting failed on these charts: {first}") from None
    if queue is not None:
        reports.extend(_placement(s, len(outlines)) for kind, s in
                       (queue.drain() if drained is None else drained) if int(kind) in FEASIBLE)
    return _placement(sol, len(outlines))


def _placement(sol, k):
    """A Placement from a spyrrow solution of k items."""
    angle = np.zeros(k)
    shift = np.zeros((k, 2))
    for p in sol.placed_items:  # per chart
        i = int(p.id)
        angle[i] = p.rotation
        shift[i] = p.translation
    return Placement(angle, shift, float(sol.width))


def _thin(xy):
    """True for an outline (n,2) thinner than ``THIN`` of its length (twice its area over its
    perimeter, its width for a strip, against the larger side of its box), or passing one point
    twice once in float32, as spyrrow reads it."""
    if len(np.unique(xy.astype(np.float32), axis=0)) < len(xy):   # spyrrow works in float32
        return True
    perimeter = np.sum(np.linalg.norm(xy - np.roll(xy, 1, axis=0), axis=1))
    length = float(np.max(xy.max(axis=0) - xy.min(axis=0)))
    return not 2 * _area(xy) > THIN * length * perimeter


def _area(xy):
    """Area of a simple polygon (n,2)."""
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _nest_grown(outlines, height, separation, options, seconds=0.0, reports=None,
                workers=None, narrow=None, compress=True, progress=None):
    """:func:`nest` of outlines ``separation`` apart, each outline grown by half of it.

    The grown outlines (mitred: the grown outline holds every point within that distance, and
    turns commute with growing) are nested with no separation in a strip shorter by the
    separation; shifting the result by half of it gives outlines ``separation`` apart and from
    the strip's edges, as spyrrow's own separation does. spyrrow's offset of the outlines failed
    where shapely's does not: slivers whose inward-offset strip came out empty (measured: it
    fails exactly when separation >= total area / height) and outlines with points closer
    together than the separation (duplicate vertices after its offset). Measured on the charts
    of suzanne, cow, camel, eight and dino (1 s search, 3 seeds, load ~6): the same density
    within the seeds' spread (0.574/0.580, 0.681/0.692, 0.640/0.616, 0.587/0.575, 0.630/0.624
    spyrrow's separation / grown) and 0.25-1.2 s less wall time a solve."""
    import shapely
    half = 0.5 * separation
    grown = [_without_repeats(np.asarray(shapely.get_coordinates(shapely.orient_polygons(
        shapely.Polygon(shapely.buffer(shapely.Polygon(xy), half, join_style="mitre")
                        .exterior))))[:-1]) for xy in outlines]
    more = [] if reports is not None else None
    pl = nest(grown, height - separation, 0.0, options, seconds, more, workers, retry=False,
              narrow=None if narrow is None else narrow - separation, compress=compress,
              progress=None if progress is None else lambda r: progress(
                  Placement(r.angle, r.shift + half, r.width + separation)))
    if reports is not None:
        reports.extend(Placement(r.angle, r.shift + half, r.width + separation) for r in more)
    return Placement(pl.angle, pl.shift + half, pl.width + separation)


def _without_repeats(xy):
    """The ring (n,2) without points equal to the one before them once in float32, as spyrrow
    reads it (the same polygon, no zero-length edge)."""
    x32 = xy.astype(np.float32)
    keep = np.any(x32 != np.roll(x32, 1, axis=0), axis=1)
    return xy[keep] if keep.any() else xy[:1]


def least_squares(outlines, options, step=1.0):
    """Per outline, the side of the least square box holding it in an allowed orientation (any
    angle: sampled every ``step`` degrees, so a hair above the least), and that angle.

    Returns
    -------
    side : (k,) float64
    angle : (k,) float64, degrees
    """
    angles = options.orientations()
    turns = np.arange(0.0, 90.0, step) if angles is None else np.asarray(angles[:2])
    R = rotations(turns)
    side, angle = np.zeros(len(outlines)), np.zeros(len(outlines))
    for i, xy in enumerate(outlines):  # per chart
        # an outline's extent in any direction is its convex hull's, found at the hull's
        # vertices: the same sides and angles from them (rocker-arm's largest chart at 0.05
        # degrees: 49 -> 5 ms)
        xy = xy.take(_hull_vertices(xy), axis=0)
        q = np.einsum("aij,nj->ani", R, xy)
        s = np.ptp(q, axis=1).max(axis=1)
        side[i], angle[i] = s.min(), turns[np.argmin(s)]
    return side, angle


def _hull_vertices(xy):
    """Indices of the convex hull's vertices of the points xy (n,2) (all of them where there
    are few or the hull is degenerate)."""
    if len(xy) <= 16:
        return np.arange(len(xy))
    try:
        return ConvexHull(xy).vertices
    except QhullError:
        return np.arange(len(xy))


def single_layout(xy, options, tol):
    """One chart alone: turned to its least square box, half the padding from the edges."""
    _, angle = least_squares([xy], options, step=0.25)
    q = xy @ rotations(angle)[0].T
    lo, hi = q.min(axis=0), q.max(axis=0)
    side = (float((hi - lo).max()) + 2 * tol) / (1 - options.padding)
    edge = 0.5 * options.padding * side + tol
    return Placement(angle, (edge - lo)[None, :], side), side


def placed_bounds(outlines, placement):
    """(k,2) low and (k,2) high corners of every placed outline's bounding box."""
    R = rotations(placement.angle)
    lo = np.zeros((len(outlines), 2))
    hi = np.zeros((len(outlines), 2))
    for i, xy in enumerate(outlines):  # per chart
        q = xy @ R[i].T + placement.shift[i]
        lo[i], hi[i] = q.min(axis=0), q.max(axis=0)
    return lo, hi


def _strip(side, options, tol, headroom=1.0):
    """(strip height, separation, overhang) for a square of ``side``.

    The separation is the padding of a square ``headroom`` times larger, plus ``2 tol``, so a
    layout up to that square still keeps the padding. spyrrow keeps the separation to the strip's
    edges too; outlines are to keep half the padding plus ``tol`` to the square's edge, so the
    strip overhangs the square by the difference on each side."""
    pad = options.padding * side * headroom
    sep = pad + 2 * tol
    over = sep - (0.5 * pad + tol)
    return side + 2 * over, sep, over


def tile_layouts(outlines, options, tol, seconds):
    """Charts at a fixed size (tile side 1) in UDIM tiles: each tile is filled from a strip of the
    charts still unplaced; charts that end past the tile's right edge wait for the next tile.
    The search time ``seconds`` is for all tiles: half of it for the first tile's solve, half of
    what is left for the next, ...

    Returns
    -------
    Placement (shift within the tile, offset included), tile (k,) int64 tile index (0: 1001),
    solves
    """
    height, sep, over = _strip(1.0, options, tol)
    k = len(outlines)
    # (with room to spare, as for a square: spyrrow gives up on a chart that barely fits)
    big = np.flatnonzero(least_squares(outlines, options)[0] * FIT[options.rotate]
                         > height - 2 * sep)
    if len(big):
        where = "UDIM tile" if options.udim else "square"
        raise PackError(f"chart {big[0]} is larger than a {where} at {options.texel_density:g} "
                        "texels per unit: lower the texel density")
    angle, shift, tile = np.zeros(k), np.zeros((k, 2)), np.full(k, -1, dtype=np.int64)
    todo, t, solves = np.arange(k), 0, 0
    while len(todo):
        sub = [outlines[i] for i in todo]
        # the time for all tiles: half of it for the first, half of the rest for the next, ...
        pl = nest(sub, height, sep, options, seconds * 0.5 ** (t + 1))
        solves += 1
        lo, hi = placed_bounds(sub, pl)
        fits = hi[:, 0] + sep <= height
        if not options.udim and not fits.all():
            raise PackError(f"the charts do not fit the square at {options.texel_density:g} "
                            f"texels per unit: lower the texel density or use UDIM tiles")
        if not fits.any():
            i = todo[int(np.argmin(lo[:, 0]))]
            raise PackError(f"chart {i} is larger than a UDIM tile at {options.texel_density:g} "
                            f"texels per unit: lower the texel density")
        done = todo[fits]
        angle[done], shift[done], tile[done] = pl.angle[fits], pl.shift[fits] - over, t
        todo, t = todo[~fits], t + 1
    return Placement(angle, shift, 1.0), tile, solves
