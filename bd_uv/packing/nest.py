"""Nesting chart outlines with spyrrow (sparrow, an irregular strip-packing heuristic).

spyrrow packs polygons into a strip of fixed height, minimising its width, with any rotation (or a
list of angles) and a least separation between items. A square needs a search over the strip
height: :func:`square_layout` solves a few heights and keeps the smallest square that holds every
chart with the padding; :func:`tile_layouts` fills UDIM tiles of a fixed size one after another.
Placements are turns and translations only (a rotation matrix has determinant +1: never a mirror).
"""
from dataclasses import dataclass

import numpy as np

from ..errors import PackError

DENSITY_GUESS = 0.64   # first guess of outline area / square area (measured 0.6-0.7 on our charts)
HEADROOM = 1.08       # a strip's separation is the padding of a square this much larger
NARROW = 1.05         # outlines of area below NARROW * separation * height are grown (_nest_grown)


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


def nest(outlines, height, separation, options):
    """One spyrrow solve: every outline in a strip of ``height``, ``separation`` apart.

    Parameters
    ----------
    outlines : list of (n_i,2) float arrays, centred simple polygons
    height : float
    separation : float, least distance between two outlines
    options : PackOptions (orientations, solve_seconds, seed)

    Returns
    -------
    Placement, with x in [0, width] and y in [0, height] for every outline point
    """
    import spyrrow
    area = sum(_area(xy) for xy in outlines)
    if separation > 0 and area <= NARROW * separation * height:
        return _nest_grown(outlines, height, separation, options)
    items = [spyrrow.Item(str(i), [tuple(p) for p in xy], demand=1,
                          allowed_orientations=options.orientations())
             for i, xy in enumerate(outlines)]
    inst = spyrrow.StripPackingInstance("bd_uv", float(height), items)
    # solve_seconds 0: spyrrow's constructive placement only (no exploration: tens of ms).
    budget = (dict(total_computation_time=options.solve_seconds) if options.solve_seconds else
              dict(total_computation_time=None, exploration_time=0, compression_time=0))
    cfg = spyrrow.StripPackingConfig(early_termination=True,
                                     min_items_separation=float(separation) if separation > 0
                                     else None, seed=options.seed, **budget)
    try:
        sol = inst.solve(cfg)
    except BaseException as exc:  # a Rust panic arrives as pyo3's PanicException (BaseException)
        if type(exc).__name__ != "PanicException":
            raise
        raise PackError(f"the nesting failed on these charts: {exc}") from None
    angle = np.zeros(len(outlines))
    shift = np.zeros((len(outlines), 2))
    for p in sol.placed_items:  # per chart
        i = int(p.id)
        angle[i] = p.rotation
        shift[i] = p.translation
    return Placement(angle, shift, float(sol.width))


def _area(xy):
    """Area of a simple polygon (n,2)."""
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _nest_grown(outlines, height, separation, options):
    """:func:`nest` for outlines whose total area is at most about ``separation * height``.

    spyrrow starts from a strip of width (total item area) / height and shrinks it inwards by half
    the separation on each side; when that width is at most the separation the strip is empty and
    spyrrow panics ("Offset resulted in an empty polygon", measured: it fails exactly when
    separation >= area / height). Such charts (slivers, a lone thin chart) are nested here with
    no separation, each outline grown by half of it (mitred: the grown outline holds every point
    within that distance, and turns commute with growing), in a strip shorter by the separation;
    shifting the result by half the separation gives what spyrrow's separation gives: outlines
    ``separation`` apart and from the strip's edges."""
    import shapely
    half = 0.5 * separation
    grown = [np.asarray(shapely.get_coordinates(shapely.orient_polygons(shapely.Polygon(
        shapely.buffer(shapely.Polygon(xy), half, join_style="mitre").exterior))))[:-1]
        for xy in outlines]
    pl = nest(grown, height - separation, 0.0, options)
    return Placement(pl.angle, pl.shift + half, pl.width + separation)


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
        q = np.einsum("aij,nj->ani", R, xy)
        s = np.ptp(q, axis=1).max(axis=1)
        side[i], angle[i] = s.min(), turns[np.argmin(s)]
    return side, angle


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


def square_layout(outlines, options, tol):
    """The smallest square found that holds every outline with the padding.

    The padding scales with the square (it is in texels). Each solve packs a strip of height S
    with the separation of a square ``HEADROOM`` S, so its layout is a square layout of side the
    placed outlines' larger extent (plus the edges) whenever that is at most ``HEADROOM`` S; the
    next height is the geometric mean of the last height and the strip's width. With ``options.solves`` spent and no
    square found, heights keep growing until one is.

    Returns
    -------
    Placement (offset to the square's corner included in ``shift``), side, solves
    """
    area = sum(_area(xy) for xy in outlines)
    if len(outlines) == 1:
        return (*single_layout(outlines[0], options, tol), 0)
    widest = float(least_squares(outlines, options)[0].max())
    side = max(np.sqrt(area / DENSITY_GUESS), (widest + 2 * tol) / (1 - options.padding) * 1.01)
    best, solves = None, 0
    while solves < options.solves or (best is None and solves < options.solves + 8):
        height, sep, over = _strip(side, options, tol, HEADROOM)
        pl = nest(outlines, height, sep, options)
        solves += 1
        length = pl.width - 2 * over          # the strip's extent along it
        # The square fits the placed outlines' own box (often smaller than the strip): its side
        # S' leaves half the padding at S' plus tol to each edge; the separation, set for
        # HEADROOM S, keeps the padding for any S' up to that.
        lo, hi = placed_bounds(outlines, pl)
        lo, hi = lo.min(axis=0), hi.max(axis=0)
        square = (float((hi - lo).max()) + 2 * tol) / (1 - options.padding)
        if square <= HEADROOM * side and (best is None or square < best[1]):
            edge = 0.5 * options.padding * square + tol
            best = (Placement(pl.angle, pl.shift - lo + edge, pl.width), square)
        side = float(np.sqrt(side * length)) * (0.99 if square <= HEADROOM * side else 1.0)
    if best is None:
        raise PackError("the nesting found no square layout for these charts")
    return best[0], best[1], solves


def tile_layouts(outlines, options, tol):
    """Charts at a fixed size (tile side 1) in UDIM tiles: each tile is filled from a strip of the
    charts still unplaced; charts that end past the tile's right edge wait for the next tile.

    Returns
    -------
    Placement (shift within the tile, offset included), tile (k,) int64 tile index (0: 1001),
    solves
    """
    height, sep, over = _strip(1.0, options, tol)
    k = len(outlines)
    big = np.flatnonzero(least_squares(outlines, options)[0] > height - 2 * sep)
    if len(big):
        where = "UDIM tile" if options.udim else "square"
        raise PackError(f"chart {big[0]} is larger than a {where} at {options.texel_density:g} "
                        "texels per unit: lower the texel density")
    angle, shift, tile = np.zeros(k), np.zeros((k, 2)), np.full(k, -1, dtype=np.int64)
    todo, t, solves = np.arange(k), 0, 0
    while len(todo):
        sub = [outlines[i] for i in todo]
        pl = nest(sub, height, sep, options)
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
