"""The charts that move, packed into the free space around pinned charts' true shapes.

spyrrow (0.9.0) nests into an empty strip and takes no fixed obstacles, so this is a raster
placement (as Blender's packer is), made conservative so the exact layout certificate holds:

- the unit square is a grid of N x N cells; a pinned chart occupies every cell whose centre lies
  within ``padding / 2 + h sqrt(2) / 2`` of its triangles (h = 1 / N), so every cell that meets the
  chart grown by half the padding is occupied;
- a moving chart, turned and scaled, occupies the cells whose centres lie within
  ``padding / 2 + tol + h sqrt(2) / 2`` of its simplified outline (the true chart is within
  ``tol`` of it); it is placed at whole-cell offsets where its cells meet no occupied cell (an FFT
  correlation of the two rasters), so two charts grown by half the padding never meet: every gap
  is at least the padding, and every chart is at least half of it from the square's edge (its
  cells stay in the grid);
- charts go largest first, each at its allowed turns (any angle: its least-square turn and the
  three quarter turns after it), at the offset whose top edge is lowest, then leftmost;
- the common scale: on a coarse grid, down from every chart's area filling the free area in
  steps of ``DESCEND`` until every chart finds room (a try that fails stops at the first chart
  without room, so tries far too large cost little), the last step then halved twice; on finer
  grids (less room lost to whole cells) raised in steps of ``STEP`` while the time lasts
  (``options.search_seconds``; a grid's first try is always made). Measured on cow's 46 charts
  with 4 pinned (load 8.5): 0.536 coverage in 1.7 s, against 0.533 in 3.7 s bisecting from half
  the largest scale.
"""
import time

import numpy as np

from .nest import least_squares, rotations

GRIDS = (128, 256, 512)     # grid cells along the square's side, coarse to fine
DESCEND = 0.95              # the coarse search's steps down from the largest scale conceivable
STEP = 1.02                 # the scale's steps up on the finer grids
GROW = 1.005                # buffers approximate arcs by chords: radii grown by this
TURNS = 4                   # any angle: the least-square turn and this many evenly after it
                            # (measured on cow's 46 charts, 4 pinned: 8 turns reached 0.503
                            # coverage against 0.533 with 4, in twice the time)


def pinned_cells(polygons, padding, n):
    """(n,n) bool occupancy, [row = v, column = u], of the pinned charts grown by half the
    padding (the polygons: a shapely geometry in the unit square, or None)."""
    import shapely
    occ = np.zeros((n, n), dtype=bool)
    if polygons is None or polygons.is_empty:
        return occ
    h = 1.0 / n
    grown = shapely.buffer(polygons, (0.5 * padding + h * np.sqrt(0.5)) * GROW + 1e-12)
    shapely.prepare(grown)
    c = (np.arange(n) + 0.5) * h
    x, y = np.meshgrid(c, c)
    occ[:] = shapely.contains_xy(grown, x, y)
    return occ


def _chart_cells(xy, reach, h):
    """Cells of one placed outline grown by ``reach``: mask (rows, cols) bool and the outline's
    offset from the mask's corner."""
    import shapely
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    m = reach + h
    shape = np.ceil((hi - lo + 2 * m) / h).astype(int)
    grown = shapely.buffer(shapely.Polygon(xy - lo + m), reach * GROW + 1e-12)
    cu, cv = (np.arange(shape[0]) + 0.5) * h, (np.arange(shape[1]) + 0.5) * h
    x, y = np.meshgrid(cu, cv)
    return shapely.contains_xy(grown, x, y), m - lo


def _candidates(outlines, options):
    """Allowed turns of each outline (degrees): a list of arrays."""
    if options.rotate == "none":
        return [np.zeros(1)] * len(outlines)
    quarter = np.arange(4) * 90.0
    if options.rotate == "90":
        return [quarter] * len(outlines)
    _, best = least_squares(outlines, options, step=2.0)
    return [a + np.arange(TURNS) * (360.0 / TURNS) for a in best]


def _place(occ, outlines, turns, order, scale, options, tol):
    """Greedy placement at one scale on the grid ``occ`` (copied). Returns (angle, shift) or None
    when some chart finds no room. The FFT correlation proposes offsets; each one taken is
    checked cell by cell on the integer rasters first (float rounding cannot let two charts'
    cells meet)."""
    import scipy.fft as sf
    n = occ.shape[0]
    h = 1.0 / n
    occ = occ.astype(np.float32)
    reach = 0.5 * options.padding + tol * scale + h * np.sqrt(0.5)
    angle, shift = np.zeros(len(outlines)), np.zeros((len(outlines), 2))
    F_occ = sf.rfft2(occ, workers=1)
    for i in order:  # per chart, largest first
        cells = [(a, *_chart_cells(scale * outlines[i] @ R.T, reach, h))
                 for a, R in zip(turns[i], rotations(turns[i]))]
        cells = [c for c in cells if c[1].shape[0] <= n and c[1].shape[1] <= n]
        if not cells:
            return None
        stack = np.zeros((len(cells), n, n), np.float32)
        for j, (_, mask, _) in enumerate(cells):  # per allowed turn
            stack[j, :mask.shape[0], :mask.shape[1]] = mask
        hits = sf.irfft2(F_occ * np.conj(sf.rfft2(stack, workers=1)), s=(n, n), workers=1)
        best = None
        for (a, mask, off), hit in zip(cells, hits):  # per allowed turn
            rows, cols = mask.shape
            free = hit[:n - rows + 1, :n - cols + 1] < 0.5
            for r in np.flatnonzero(free.any(axis=1)):  # per row, lowest first
                if best is not None and r + rows >= best[0][0]:
                    break
                c = next((int(c) for c in np.flatnonzero(free[r])
                          if not occ[r:r + rows, c:c + cols][mask].any()), None)
                if c is not None:
                    best = ((r + rows, c), a, r, c, mask, off)
                    break
        if best is None:
            return None
        _, angle[i], r, c, mask, off = best
        occ[r:r + mask.shape[0], c:c + mask.shape[1]] += mask
        shift[i] = np.array([c, r]) * h + off
        F_occ = sf.rfft2(occ, workers=1)
    return angle, shift


def place_around(pinned_geometry, outlines, areas, options, tol, free_area, least=0.0):
    """The largest common scale found (and the placements) at which every moving chart fits the
    free space around the pinned charts.

    Parameters
    ----------
    pinned_geometry : shapely geometry, the pinned charts' triangles in the unit square
    outlines : list of (n_i,2) float arrays, centred outlines of the moving charts (scene units)
    areas : (k,) float, their areas (largest placed first)
    options : PackOptions (padding, rotate, the time: ``search_seconds``)
    tol : float, outline simplification tolerance in scene units
    free_area : float, the square's area left by the pinned charts (bounds the scale)
    least : float, a scale already reached otherwise: only larger ones are searched

    Returns
    -------
    (scale, angle (k,), shift (k,2)): UV = scale * R(angle) x + shift for an outline point x;
    or None when no scale above ``least`` fits.
    """
    if free_area <= 0:
        return None
    t0 = time.perf_counter()
    seconds = options.search_seconds(len(outlines) + 1)
    order = np.argsort(-np.asarray(areas, dtype=np.float64), kind="stable")
    turns = _candidates(outlines, options)
    found = None
    top = float(np.sqrt(free_area / np.sum(areas)))    # every chart's area in the free area
    lo, hi = least, top
    for g, n in enumerate(GRIDS):  # per grid, coarse to fine
        occ = pinned_cells(pinned_geometry, options.padding, n)
        for j in range(64):  # per scale tried
            if g == 0:
                # down from the top in steps of DESCEND while failing (a failure stops at the
                # first chart without room: cheap far above the answer), then the last step
                # halved twice
                if found is not None and (hi / lo < DESCEND ** -0.25
                                          or time.perf_counter() - t0 > seconds):
                    break
                s = hi * DESCEND if found is None else np.sqrt(lo * hi)
                if s <= least:
                    break
            else:   # a step above the scale found (the same scale again would gain nothing)
                s = found[0] * STEP
                if s >= top or (j and time.perf_counter() - t0 > seconds):
                    break
            got = _place(occ, outlines, turns, order, s, options, tol)
            if got is None:
                if g == 0:
                    hi = s
                    continue
                break
            found, lo = (s, *got), s
        if found is None or time.perf_counter() - t0 > seconds:
            break
    return found
