"""Grouped packing: the charts of one material (or one object) packed together.

"Together" means one region per group that no chart of another group enters:

- fitted to the square (no texel density): one column of the square's height per group, side by
  side (:mod:`.columns`): each group's bounding box holds only its charts;
- at a fixed texel density (one tile, or UDIM tiles): each group's charts are nested on their own
  (spyrrow, :func:`.nest.nest`) in a strip about as high as it is wide, with the padding as their
  separation; the group's block is the convex hull of its placed outlines, and the blocks are
  nested as items into the tiles (:func:`.nest.tile_layouts`) with the padding between them, each
  turned as a whole (a chart's placement is its turn in the block followed by the block's). A
  block larger than a tile is refused.

A chart is in the group of most of its faces' 3D area (a chart across two materials belongs to
the one it mostly carries; seams are not cut at material borders here).
"""
import numpy as np

from ..errors import PackError
from .nest import FIT, Placement, _area, least_squares, nest, rotations, tile_layouts
from .columns import column_layout

INNER_DENSITY = 0.63    # a group's strip height: sqrt(its charts' area / this)


def chart_groups(F, V, face_island, face_group, k):
    """The group of each chart: the group of most of its faces' 3D area.

    Parameters
    ----------
    F : (m,3) int array, V : (n,3) float array
    face_island : (m,) int array, chart of each face (-1: not packed)
    face_group : (m,) int array, group (material, object) of each face
    k : int, charts

    Returns
    -------
    (k,) int64, group labels 0..g-1 (renumbered in order of first chart)
    """
    lab = np.asarray(face_island, dtype=np.int64)
    grp = np.asarray(face_group, dtype=np.int64).reshape(-1)
    if len(grp) != len(lab):
        raise PackError(f"the face groups have {len(grp)} entries for {len(lab)} faces")
    use = lab >= 0
    P = np.asarray(V, dtype=np.float64)[np.asarray(F, dtype=np.int64)[use]]
    a3 = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    names, g = np.unique(grp[use], return_inverse=True)
    weight = np.zeros((k, len(names)))
    np.add.at(weight, (lab[use], g.reshape(-1)), a3 + 1e-300)   # (a face of zero area counts)
    first = np.argmax(weight, axis=1)
    _, out = np.unique(first, return_inverse=True)
    return out.reshape(-1).astype(np.int64)


def _block(outlines, sep, options, seconds):
    """One group's charts nested together, ``sep`` apart. Returns the Placement (in the strip's
    frame) and the block's outline: the convex hull of the placed outlines (counter-clockwise)."""
    import shapely
    area = sum(_area(xy) for xy in outlines)
    widest = float(least_squares(outlines, options)[0].max())
    height = max(np.sqrt(area / INNER_DENSITY), widest * FIT[options.rotate]) + 2 * sep
    for _ in range(6):  # per strip height: spyrrow refuses a chart that barely fits
        try:
            pl = nest(outlines, height, sep, options, seconds)
            break
        except PackError:
            height *= 1.25
    else:
        raise PackError("the nesting failed on a group's charts")
    R = rotations(pl.angle)
    pts = np.concatenate([xy @ R[i].T + pl.shift[i] for i, xy in enumerate(outlines)])
    hull = shapely.orient_polygons(shapely.convex_hull(shapely.multipoints(pts)))
    return pl, np.asarray(shapely.get_coordinates(hull.exterior))[:-1]


def grouped_layout(outlines, group, options, tol, seconds, fixed=False):
    """Charts packed one region per group (module docstring).

    Parameters
    ----------
    outlines : list of (n_i,2) float arrays, centred chart outlines (scene units, or tile units
        with ``fixed``)
    group : (k,) int array, group of each chart (0..g-1)
    options : PackOptions
    tol : float, outline simplification tolerance in the outlines' units
    seconds : float, the search time (with ``fixed``: half for the blocks, shared by chart
        count, half for the tiles)
    fixed : bool, a fixed texel density: each tile has side 1

    Returns
    -------
    Placement (shift in the square of ``side``, or within its tile), side, tile (k,) int64
    (tile index: 0 for tile 1001), solves
    """
    group = np.asarray(group, dtype=np.int64)
    k, g = len(outlines), int(group.max()) + 1
    if not fixed:
        pl, side, solves = column_layout(outlines, group, options, tol, seconds)
        return pl, side, np.zeros(k, dtype=np.int64), solves
    sep = options.padding + 2 * tol        # the tiles' padding: known before packing
    angle, shift = np.zeros(k), np.zeros((k, 2))
    blocks, solves = [], 0
    for b in range(g):  # per group
        members = np.flatnonzero(group == b)
        if len(members) == 1:   # a lone chart is its own block
            blocks.append(outlines[members[0]])
            continue
        share = 0.5 * seconds * len(members) / k
        pl, hull = _block([outlines[i] for i in members], sep, options, share)
        solves += 1
        centre = 0.5 * (hull.min(axis=0) + hull.max(axis=0))
        angle[members], shift[members] = pl.angle, pl.shift - centre
        blocks.append(hull - centre)
    try:
        outer, tile, n = tile_layouts(blocks, options, tol, 0.5 * seconds)
    except PackError as exc:
        raise PackError(f"{exc} (grouped: each item is a group's block of charts)") from None
    R = rotations(outer.angle)[group]
    return (Placement(angle + outer.angle[group],
                      np.einsum("kij,kj->ki", R, shift) + outer.shift[group], 1.0),
            1.0, tile[group], solves + n)
