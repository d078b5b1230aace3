"""The charts to pack: one texel density for every chart, and each chart's outer outline.

A chart is scaled (not turned) so its UV area equals its 3D area, as Blender's Average Islands
Scale does; conformal distortion is scale-invariant (Lipman 2012, eq. 4.9), so its certificate
holds. The outline is the outer boundary of the chart's triangles (holes are not used by the
nesting), simplified by ``tol``: every point of the true outline lies within ``tol`` of the
simplified one (Douglas-Peucker), so outlines kept ``sep`` apart keep the charts ``sep - 2 tol``
apart.
"""
from dataclasses import dataclass

import numpy as np

from ..errors import PackError
from ..uv_boundary import uv_boundary
from .square import DENSITY_GUESS

TOL_PX = 0.1   # outline simplification, in texels: the separation grows by twice this


@dataclass(frozen=True)
class Charts:
    """Charts at one density, ready to nest.

    Attributes
    ----------
    uv : (m,3,2) float64, corner UVs scaled per chart to UV area = 3D area (NaN outside charts)
    label : (m,) int64, chart of each face (-1: not packed)
    area : (k,) float64, each chart's UV area after scaling (= its 3D area)
    outlines : list of (n_i,2) float64, each chart's simplified outer outline, counter-clockwise,
        centred on ``centre``
    exact : list of (m_i,2) float64, each chart's outer outline before the simplification, in
        the same frame (the simplified one keeps a subset of its points)
    centre : (k,2) float64, the point of each chart the outline is centred on
    """
    uv: np.ndarray
    label: np.ndarray
    area: np.ndarray
    outlines: list
    centre: np.ndarray
    exact: list


def _areas(P):
    """Signed areas of triangles P (m,3,2)."""
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    return 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])


def _hull_outline(tris):
    """An outline holding every triangle of a chart whose boundary does not close into one ring
    (a pinched or touching boundary, as other unwrappers make): the outer ring of the triangles'
    union when it is one polygon, else the union's convex hull."""
    import shapely
    union = shapely.union_all(shapely.polygons(tris))
    if union.geom_type == "Polygon":
        return shapely.Polygon(union.exterior)
    return shapely.convex_hull(union)


def chart_outlines(V, F, corner_uv, face_island, n_charts, options, tol_px=TOL_PX):
    """Scale every chart to one density and find its outline.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array
    corner_uv : (m,3,2) float array
    face_island : (m,) int array, chart of each face (-1: not packed); faces with non-finite UVs
        must not be in a chart
    n_charts : int
    options : PackOptions (resolution and texel density give a texel's size)
    tol_px : float, outline simplification tolerance in texels (estimated for the square search)

    Returns
    -------
    Charts, and tol (float): the simplification tolerance in the same units
    """
    import shapely
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    uv = np.asarray(corner_uv, dtype=np.float64).reshape(len(F), 3, 2)
    lab = np.asarray(face_island, dtype=np.int64).reshape(-1)
    use = lab >= 0
    if not np.isfinite(uv[use]).all():
        raise PackError("a chart to pack has UVs that are not finite numbers")
    P3 = V[F[use]]
    a3 = 0.5 * np.linalg.norm(np.cross(P3[:, 1] - P3[:, 0], P3[:, 2] - P3[:, 0]), axis=1)
    auv = _areas(uv[use])
    if (auv <= 0).any():
        raise PackError(f"{int((auv <= 0).sum())} face(s) of the charts are flipped or "
                        "degenerate in UV: only flip-free charts are packed")
    A3 = np.bincount(lab[use], weights=a3, minlength=n_charts)
    Auv = np.bincount(lab[use], weights=auv, minlength=n_charts)
    if (A3 <= 0).any() or (Auv <= 0).any():
        raise PackError("a chart to pack has no area (in 3D or in UV)")
    scale = np.sqrt(A3 / Auv)
    out = np.full(uv.shape, np.nan)
    out[use] = uv[use] * scale[lab[use]][:, None, None]
    if options.texel_density is not None:
        texel = 1.0 / options.texel_density
    else:  # the square's side is about sqrt(area / DENSITY_GUESS)
        texel = float(np.sqrt(A3.sum() / DENSITY_GUESS)) / options.resolution
    tol = tol_px * texel
    bd = uv_boundary(F, out, lab)
    order = np.argsort(bd.island, kind="stable")
    cuts = np.searchsorted(bd.island[order], np.arange(n_charts + 1))
    segs = shapely.linestrings(np.stack([bd.p, bd.q], axis=1)[order])
    outlines, exact, centre = [], [], np.zeros((n_charts, 2))
    for i in range(n_charts):  # per chart
        polys = shapely.get_parts(shapely.polygonize(segs[cuts[i]:cuts[i + 1]]))
        # the outer ring encloses the most (a hole's own face can have more area than the chart)
        rings = shapely.polygons(shapely.get_exterior_ring(polys))
        outer = rings[np.argmax(shapely.area(rings))] if len(polys) else None
        if outer is None or outer.area < 0.999 * A3[i]:
            outer = _hull_outline(out[lab == i])
        ring = shapely.simplify(outer, tol, preserve_topology=True)
        xy = np.asarray(shapely.get_coordinates(shapely.orient_polygons(ring)))[:-1]
        lo, hi = xy.min(axis=0), xy.max(axis=0)
        centre[i] = 0.5 * (lo + hi)
        outlines.append(xy - centre[i])
        exact.append(np.asarray(shapely.get_coordinates(shapely.orient_polygons(
            shapely.Polygon(outer.exterior))))[:-1] - centre[i])
    return Charts(out, lab, A3, outlines, centre, exact), tol
