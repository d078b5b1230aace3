"""The layout certificate: measured with vector geometry on the UVs as stored (float32 allowed).

- every corner of a chart inside its UDIM tile (and how close to the tile's edge it comes);
- no two charts overlapping (:func:`bd_uv.overlap.layout_overlaps`: boundary segments meeting,
  decided by orientation signs with rounding error bounds, or one chart inside another);
- the least gap between two charts: the exact distance between their UV boundaries (GEOS
  segment-to-segment distances over an STRtree of the charts' boundaries), in texels;
- the density spread: largest over smallest texel density (sqrt of UV area over 3D area);
- every face turning the way it did when packed (counter-clockwise, as ``pack_islands`` takes
  charts): a face too thin for float32 at its place in the texture collapses or flips as stored.
Nothing is rasterised.
"""
from dataclasses import dataclass

import numpy as np

from ..overlap import layout_overlaps
from ..uv_boundary import uv_boundary


@dataclass(frozen=True)
class LayoutCertificate:
    """What the stored UVs of a packed layout prove.

    Attributes
    ----------
    certified : bool, inside, overlap-free, least gap >= padding, edge gap >= padding / 2 and
        no face flipped or collapsed as stored
    reason : str, why not (empty when certified)
    resolution : int
    padding_px : float, the padding asked for
    least_gap_px : float, least distance between two charts of one tile, in texels (inf: one chart)
    edge_gap_px : float, least distance from a chart to its tile's edge, in texels
    inside : bool, every corner inside its chart's tile
    overlaps : (p,2) int64, chart pairs that overlap
    coverage : float, chart area over the area of the tiles used
    tiles : list of int, UDIM numbers used
    density_spread : float, largest over smallest texel density (inf: a chart with 3D area has
        no UV area as stored)
    flipped_faces : int, faces of the layout whose signed UV area as stored is not positive
    """
    certified: bool
    reason: str
    resolution: int
    padding_px: float
    least_gap_px: float
    edge_gap_px: float
    inside: bool
    overlaps: np.ndarray
    coverage: float
    tiles: list
    density_spread: float
    flipped_faces: int = 0

    def summary(self):
        """The JSON report's figures (the ``pack`` object gets these)."""
        gap = self.least_gap_px
        return dict(certified=self.certified, reason=self.reason, resolution=self.resolution,
                    padding_px=self.padding_px,
                    least_gap_px=None if not np.isfinite(gap) else round(float(gap), 4),
                    edge_gap_px=round(float(self.edge_gap_px), 4), coverage=round(self.coverage, 5),
                    tiles=self.tiles,
                    density_spread=None if not np.isfinite(self.density_spread)
                    else round(self.density_spread, 6),
                    overlapping_pairs=int(len(self.overlaps)),
                    flipped_faces=int(self.flipped_faces))


def least_gaps(F, corner_uv, face_island):
    """Distance from every chart to its nearest other chart (exact, from the UV boundaries).

    Returns
    -------
    (k,) float64, inf for a chart alone
    """
    import shapely
    bd = uv_boundary(F, corner_uv, face_island)
    k = int(np.max(face_island)) + 1
    order = np.argsort(bd.island, kind="stable")
    segs = shapely.linestrings(np.stack([bd.p, bd.q], axis=1)[order])
    geoms = shapely.multilinestrings(segs, indices=bd.island[order])
    gap = np.full(k, np.inf)
    if k > 1:
        tree = shapely.STRtree(geoms)
        (i, j), d = tree.query_nearest(geoms, exclusive=True, return_distance=True)
        np.minimum.at(gap, i, d)
    return gap


def layout_certificate(V, F, corner_uv, face_island, tile, resolution, padding_px):
    """Certify a packed layout from its stored UVs.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array
    corner_uv : (m,3,2) float array, UVs as stored
    face_island : (m,) int array, chart of each face (-1: not in the layout; a chart with no
        face is left out)
    tile : (k,) int array, UDIM number of each chart's tile
    resolution : int, texels along a tile's side
    padding_px : float, the least gap asked for

    Returns
    -------
    LayoutCertificate
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    uv = np.asarray(corner_uv).astype(np.float64).reshape(len(F), 3, 2)
    lab = np.asarray(face_island, dtype=np.int64).reshape(-1)
    tile = np.asarray(tile, dtype=np.int64)
    use = lab >= 0
    k = len(tile)
    t = tile - 1001
    lo = np.stack([t % 10, t // 10], axis=1).astype(np.float64)[lab[use]][:, None, :]
    P = uv[use]
    inside = bool(np.all(np.isfinite(P)) and np.all(P >= lo) and np.all(P <= lo + 1))
    edge = np.minimum(P - lo, lo + 1 - P).min() * resolution if use.any() else np.inf
    overlaps = layout_overlaps(uv, np.where(use, lab, -1), F) if k > 1 else np.zeros((0, 2), int)
    # gaps only between charts of one tile: charts of two tiles are apart by their edge gaps
    gap = np.inf
    for u in np.unique(tile):  # per tile
        sel = use & np.isin(lab, np.flatnonzero(tile == u))
        sub = np.unique(lab[sel], return_inverse=True)[1].reshape(-1)
        if sub.max(initial=0) > 0:
            g = np.full(len(lab), -1)
            g[sel] = sub
            gap = min(gap, float(least_gaps(F, uv, g).min()) * resolution)
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    signed = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    auv = 0.5 * np.abs(signed)
    # a chart's faces turn counter-clockwise (``pack_islands`` refuses others): one that does
    # not as stored was flipped or collapsed by the storage's rounding (a sliver 1e-8 across)
    flipped = int(np.sum(np.isfinite(signed) & ~(signed > 0)))
    P3 = V[F[use]]
    a3 = 0.5 * np.linalg.norm(np.cross(P3[:, 1] - P3[:, 0], P3[:, 2] - P3[:, 0]), axis=1)
    present = np.unique(lab[use])
    area3 = np.bincount(lab[use], a3, k)[present]
    dens = np.sqrt(np.bincount(lab[use], auv, k)[present][area3 > 0] / area3[area3 > 0])
    # (a chart of zero 3D area has no texel density: it takes no part in the spread)
    tiles = sorted(int(x) for x in np.unique(tile[present]))
    coverage = float(auv.sum() / len(tiles)) if tiles else 0.0
    reasons = []
    if not inside:
        reasons.append("a chart corner lies outside its tile")
    if len(overlaps):
        reasons.append(f"{len(overlaps)} pair(s) of charts overlap")
    if gap < padding_px:
        reasons.append(f"least gap {gap:.3f} px < padding {padding_px:g} px")
    if edge < 0.5 * padding_px:
        reasons.append(f"a chart is {edge:.3f} px from its tile's edge < {0.5 * padding_px:g} px")
    if flipped:
        reasons.append(f"{flipped} face(s) flipped or collapsed as stored (too thin for the "
                       "stored precision at their place in the texture)")
    # a chart whose UV area is 0 as stored (a degenerate island of any UV map, or one
    # collapsed by float32 storage) has texel density 0: the spread is unbounded
    spread = (1.0 if not len(dens) else np.inf if dens.min() <= 0
              else float(dens.max() / dens.min()))
    return LayoutCertificate(not reasons, "; ".join(reasons), int(resolution), float(padding_px),
                             gap, float(edge), inside, overlaps, coverage, tiles, spread,
                             flipped)
