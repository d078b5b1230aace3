"""``pack_islands``: charts into a texture square (or UDIM tiles) by their true outlines.

1. every chart is scaled to one texel density (:func:`chart_outlines`);
2. its outer outline is nested by spyrrow with turns (any angle, quarter turns or none), the
   padding as the least separation and half of it to the square's edge (:mod:`.nest`), and the
   best square layout compacted by small moves and turns (:mod:`.compact`); 2 to 5 charts in
   the square are laid out without spyrrow (:mod:`.few`: its search overshoots so small a
   request by 0.5 s and more), then compacted the same way;
3. each chart's corners get its turn, translation and the common scale: a similarity with positive
   determinant, so every face keeps its orientation and its conformal distortion.

Why spyrrow (measured on our charts, see docs/ARCHITECTURE.md and benchmarks/bench_pack.py): it
matched Blender's exact-shape packer in coverage in a fraction of its time, has wheels for every
platform and Python the zips serve, and is a maintained library rather than our own code.
"""
import importlib
import time
from dataclasses import dataclass, replace

import numpy as np

from ..errors import PackError
from .early_stop import can_stop
from .nest import rotations, tile_layouts
from .options import PackOptions, udim_tile
from .outlines import chart_outlines
from .pinned import chart_boxes, free_square
from .around import place_around
from .groups import chart_groups, grouped_layout
from .few import few_square
from .square import square_layout
from .tiny import TINY_SHARE, tiny_square

# what the packing imports where it calls them (spyrrow's nesting, shapely's outlines, scipy's
# HiGHS, FFT, k-d trees and sparse arrays)
LIBRARIES = ("scipy.fft", "scipy.optimize", "scipy.sparse", "scipy.spatial", "shapely",
             "spyrrow")


@dataclass(frozen=True)
class Packed:
    """A packed layout.

    Attributes
    ----------
    corner_uv : (m,3,2) float64, packed UVs (faces of no chart as given)
    face_island : (m,) int64, chart of each face (-1: not packed)
    tile : (k,) int64, UDIM number of each chart's tile (1001, 1002, ...)
    angle : (k,) float64, each chart's turn in degrees (counter-clockwise)
    texel_density : float, texels per scene unit of every chart
    seconds : float, packing time (the libraries it calls imported before its clock starts)
    solves : int, nesting solves run
    options : PackOptions
    """
    corner_uv: np.ndarray
    face_island: np.ndarray
    tile: np.ndarray
    angle: np.ndarray
    texel_density: float
    seconds: float
    solves: int
    options: PackOptions


def pack_islands(V, F, corner_uv, face_island, options=None, pinned=None, face_labels=None):
    """Pack every chart into the square (or UDIM tiles) at one texel density.

    Parameters
    ----------
    V : (n,3) float array, the mesh (3D areas give the density)
    F : (m,3) int array
    corner_uv : (m,3,2) float array, each chart flip-free
    face_island : (m,) int array, chart of each face, labels 0..k-1 (-1: left as it is)
    options : PackOptions, default PackOptions()
    pinned : (k,) bool array, optional: charts that stay where they are (bit for bit, inside the
        unit square); the others are packed at one density into the free space around their
        shapes, keeping the padding (:func:`.around.place_around`)
    face_labels : dict, optional: {"material": (m,) int, "object": (m,) int}, each face's
        material or object; ``options.group`` other than "none" packs the charts of one group
        together (:mod:`.groups`) and needs that entry

    Returns
    -------
    Packed
    """
    _load_libraries()
    t0 = time.perf_counter()
    options = options or PackOptions()
    F = np.asarray(F, dtype=np.int64)
    uv = np.asarray(corner_uv, dtype=np.float64).reshape(len(F), 3, 2)
    lab = np.asarray(face_island, dtype=np.int64).reshape(-1)
    if len(lab) != len(F):
        raise PackError(f"face_island has {len(lab)} entries for {len(F)} faces")
    k = int(lab.max()) + 1 if len(lab) else 0
    if k == 0:
        return Packed(uv.copy(), lab.copy(), np.zeros(0, np.int64), np.zeros(0), 0.0,
                      time.perf_counter() - t0, 0, options)
    if np.any(np.bincount(lab[lab >= 0], minlength=k) == 0):
        raise PackError("chart labels must run from 0 to k-1 without gaps")
    group = None
    if options.group != "none":
        if face_labels is None or face_labels.get(options.group) is None:
            raise PackError(f"grouping by {options.group} needs each face's {options.group}, "
                            "which this input does not give")
        group = chart_groups(F, V, lab, face_labels[options.group], k)
    if pinned is not None and np.any(pinned):
        if group is not None and group.max() > 0:
            raise PackError("charts are not grouped around pinned charts: pin none, or pack "
                            "without grouping")
        return _around_pinned(V, F, uv, lab, options, np.asarray(pinned, dtype=bool), t0)
    charts, tol = chart_outlines(V, F, uv, lab, k, options)
    tiny = int((charts.area < TINY_SHARE * charts.area.sum()).sum())
    seconds = options.search_seconds(k, int((lab >= 0).sum()), tiny=tiny)
    if group is not None and group.max() > 0:
        f = 1.0 if options.texel_density is None else options.texel_density / options.resolution
        pl, side, tile, solves = grouped_layout([xy * f for xy in charts.outlines], group,
                                                options, tol * f, seconds,
                                                fixed=options.texel_density is not None)
    elif options.texel_density is not None:
        f = options.texel_density / options.resolution   # tile units per scene unit
        outlines = [xy * f for xy in charts.outlines]
        pl, tile, solves = tile_layouts(outlines, options, tol * f, seconds)
        side = 1.0
    else:
        f = 1.0
        # (a chart holding much of the area: less time, options.DOMINANT_SHARE)
        largest = float(charts.area.max() / charts.area.sum())
        seconds = options.search_seconds(k, int((lab >= 0).sum()), largest, tiny)
        # mostly tiny charts: the others packed alone, the tiny ones dropped into the space
        # left (.tiny); else (or when a tiny chart finds no room) 2-5 charts laid out without
        # spyrrow (.few), more (or when it finds none) nested, and nested too when a search
        # time or more solves are asked for, the smaller square kept
        found = None
        if options.solve_seconds is None and options.solves == 1:
            found = tiny_square(charts, options, tol, np.bincount(lab[lab >= 0], minlength=k))
        if found is None:
            found = few_square(charts.outlines, options, tol, charts.exact)
            if found is None or options.solve_seconds is not None or options.solves > 1:
                # the longer reach only where its search can end early (.early_stop: the main
                # thread of a Python process); on a worker thread (Blender's operator, Dask) it
                # would run all of it, so there the time is as it was
                nested = square_layout(charts.outlines, options, tol, seconds, charts.exact,
                                       coarse=True,
                                       reach=_reach(options, k, int((lab >= 0).sum()),
                                                    largest) if can_stop() else 1.0,
                                       gain=options.root_gain(k, int((lab >= 0).sum())))
                if found is None or nested[1] < found[1]:
                    found = nested
                else:
                    found = (found[0], found[1], nested[2])
        pl, side, solves = found
        tile = np.zeros(k, dtype=np.int64)
    R = rotations(pl.angle)
    use = lab >= 0
    x = (charts.uv[use] - charts.centre[lab[use]][:, None, :]) * f
    placed = np.einsum("fij,fcj->fci", R[lab[use]], x) + pl.shift[lab[use]][:, None, :]
    offset = np.array([udim_tile(t)[1] for t in range(int(tile.max()) + 1)], dtype=np.float64)
    out = uv.copy()
    out[use] = placed / side + offset[tile[lab[use]]][:, None, :]
    density = options.resolution * f / side
    return Packed(out, lab.copy(), 1001 + tile, pl.angle, float(density),
                  time.perf_counter() - t0, solves, options)


def _load_libraries():
    """The libraries the packing calls, imported before its clock starts: ``Packed.seconds`` is
    the packing, not their first import in the process (measured after bench_pack's own
    imports, files cached: 0.07-0.1 s of CPU, 0.13-0.2 s of wall at load 5, counted in
    rocker-arm's 0.6 s pack, the first of the lead's bench run; more from a cold disk). Later
    calls find them imported."""
    for name in LIBRARIES:  # per library
        importlib.import_module(name)


def _reach(options, charts, faces, largest):
    """How much longer the nesting may search, each search ended at its square: the options'
    reach where no chart dominates, else their dominant reach (one of the two is 1)."""
    return max(options.reach(charts, faces, largest),
               options.dominant_reach(charts, faces, largest))


def _around_pinned(V, F, uv, lab, options, pinned, t0):
    """Pinned charts kept bit for bit; the rest packed at one density into the free space around
    the pinned charts' true shapes (:func:`.around.place_around`, a conservative raster
    placement). The largest free square beside the pinned charts' bounding boxes (nested by
    spyrrow, the padding scaled so it stays ``padding_px`` texels once the square is scaled into
    place: the previous method) is tried too when it could reach a higher density, and kept
    when it does."""
    import shapely
    k = int(lab.max()) + 1
    if len(pinned) != k:
        raise PackError(f"pinned has {len(pinned)} entries for {k} charts")
    if options.texel_density is not None:
        raise PackError("charts are packed around pinned charts at the largest density that "
                        "fits; a fixed texel density with pinned charts is not supported")
    fixed = np.flatnonzero(pinned)
    lo, hi = chart_boxes(uv, lab, fixed)
    if (lo < 0).any() or (hi > 1).any():
        raise PackError(f"pinned chart {fixed[np.any((lo < 0) | (hi > 1), axis=1)][0]} lies "
                        "outside the unit square: pinned charts stay where they are")
    moving = np.flatnonzero(~pinned)
    out = uv.copy()
    angle = np.zeros(k)
    if not len(moving):
        return Packed(out, lab.copy(), np.full(k, 1001), angle, 0.0,
                      time.perf_counter() - t0, 0, options)
    sub = np.full(k, -1)
    sub[moving] = np.arange(len(moving))
    sub_lab = np.where(lab >= 0, sub[np.maximum(lab, 0)], -1)
    sel = sub_lab >= 0
    # 1. the free space around the pinned charts' shapes (a raster placement)
    charts, tol = chart_outlines(V, F, uv, sub_lab, len(moving), options)
    held = (lab >= 0) & pinned[np.maximum(lab, 0)]
    # the pinned triangles and their edges (so a pinned chart of no UV area is avoided too)
    tris = uv[held]
    e1, e2 = tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    shapes = shapely.union_all(np.concatenate([
        shapely.polygons(tris[area > 0]), shapely.linestrings(tris[area <= 0][:, [0, 1, 2, 0]])]))
    around = place_around(shapes, charts.outlines, charts.area, options, tol,
                          1.0 - float(area.sum()))
    reached = around[0] if around is not None else 0.0
    # 2. the largest free square beside the pinned charts' boxes (nested by spyrrow), unless
    # even every chart in it at full density would not reach the raster's scale
    corner, side = free_square(lo, hi, 0.5 * options.padding)
    square = None
    if (side * options.resolution >= 8 * max(options.padding_px, 1.0)
            and side / np.sqrt(charts.area.sum()) > reached):
        inner = pack_islands(V, F, uv, sub_lab, replace(options, padding_px=options.padding_px
                                                        / side))
        square = (inner.texel_density * side, inner)
    if around is not None and (square is None or reached * options.resolution >= square[0]):
        scale, turn, shift = around
        R = rotations(turn)
        x = (charts.uv[sel] - charts.centre[sub_lab[sel]][:, None, :]) * scale
        out[sel] = np.einsum("fij,fcj->fci", R[sub_lab[sel]], x) + shift[sub_lab[sel]][:, None, :]
        angle[moving] = turn
        return Packed(out, lab.copy(), np.full(k, 1001), angle, scale * options.resolution,
                      time.perf_counter() - t0, 0, options)
    if square is None:
        raise PackError("no room left beside the pinned charts for the others")
    density, inner = square
    out[sel] = inner.corner_uv[sel] * side + corner
    angle[moving] = inner.angle
    return Packed(out, lab.copy(), np.full(k, 1001), angle, density,
                  time.perf_counter() - t0, inner.solves, options)
