"""``pack_islands``: charts into a texture square (or UDIM tiles) by their true outlines.

1. every chart is scaled to one texel density (:func:`chart_outlines`);
2. its outer outline is nested by spyrrow with turns (any angle, quarter turns or none), the
   padding as the least separation and half of it to the square's edge (:mod:`.nest`);
3. each chart's corners get its turn, translation and the common scale: a similarity with positive
   determinant, so every face keeps its orientation and its conformal distortion.

Why spyrrow (measured on our charts, see docs/ARCHITECTURE.md and benchmarks/bench_pack.py): it
matched Blender's exact-shape packer in coverage in a fraction of its time, has wheels for every
platform and Python the zips serve, and is a maintained library rather than our own code.
"""
import time
from dataclasses import dataclass

import numpy as np

from ..errors import PackError
from .nest import rotations, square_layout, tile_layouts
from .options import PackOptions, udim_tile
from .outlines import chart_outlines


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
    seconds : float, packing time
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


def pack_islands(V, F, corner_uv, face_island, options=None):
    """Pack every chart into the square (or UDIM tiles) at one texel density.

    Parameters
    ----------
    V : (n,3) float array, the mesh (3D areas give the density)
    F : (m,3) int array
    corner_uv : (m,3,2) float array, each chart flip-free
    face_island : (m,) int array, chart of each face, labels 0..k-1 (-1: left as it is)
    options : PackOptions, default PackOptions()

    Returns
    -------
    Packed
    """
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
    charts, tol = chart_outlines(V, F, uv, lab, k, options)
    if options.texel_density is not None:
        f = options.texel_density / options.resolution   # tile units per scene unit
        outlines = [xy * f for xy in charts.outlines]
        pl, tile, solves = tile_layouts(outlines, options, tol * f)
        side = 1.0
    else:
        f = 1.0
        pl, side, solves = square_layout(charts.outlines, options, tol)
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
