"""seams="auto" with polygons (issue 11): Blender hands the triangles of quads and n-gons, and a
chart boundary along a polygon's diagonal is no edge a UV map (or a seam) can hold. With
``polygons=`` every chart is a union of whole polygons, a disk, certified at C with stretch
within S. Checked here from the returned charts and UVs (numpy), not from bd_uv's reports.
"""
import numpy as np
import pytest

import bd_uv
from bd_uv.seams import unwrap_auto

from seams_helpers import torus, uv_sphere
from test_seams import C, S, check_charts


def _quad_torus(nu=32, nv=12):
    """The torus grid with both triangles of each cell in one quad (genus 1)."""
    V, F, _, _ = torus(nu=nu, nv=nv)
    cells = nu * nv
    return V, F, np.concatenate([np.arange(cells), np.arange(cells)])


def _check_whole_polygons(F, poly, res, added):
    """No chart boundary and no added seam inside a polygon."""
    # Every polygon in one chart.
    pairs = np.unique(np.stack([poly, res.face_island], axis=1), axis=0)
    assert len(pairs) == len(np.unique(poly)), "a polygon is split between charts"
    # Within a chart, a polygon's triangles share their diagonal's corners (one UV each).
    for r in res.islands:
        p = poly[r.faces]
        order = np.argsort(p, kind="stable")
        same = p[order][1:] == p[order][:-1]
        for f, g in zip(r.faces[order][:-1][same], r.faces[order][1:][same]):
            shared = np.intersect1d(F[f], F[g])
            if len(shared) == 2:            # the diagonal between the two triangles
                for v in shared:
                    uf = res.corner_uv[f][F[f] == v][0]
                    ug = res.corner_uv[g][F[g] == v][0]
                    assert np.array_equal(uf, ug)
    # No added seam is a diagonal (both of its faces in one polygon).
    for a, b in added.tolist():
        fs = np.flatnonzero(np.isin(F, [a, b]).sum(axis=1) == 2)
        assert len(fs) == 2 and poly[fs[0]] != poly[fs[1]]


@pytest.mark.parametrize("mesh", ["sphere", "torus"])
def test_charts_are_whole_polygons_disks_and_certified(mesh):
    if mesh == "sphere":
        V, F, poly = uv_sphere(24, 12)
    else:
        V, F, poly = _quad_torus()
    res, added, info = unwrap_auto(V, F, bound=C, stretch=S, polygons=poly)
    check_charts(V, F, res)
    _check_whole_polygons(F, poly, res, added)
    assert info["charts"] == len(res.islands)
    # The same through unwrap(seams="auto"), where face_groups are the polygons.
    res2 = bd_uv.unwrap(V, F, seams="auto", bound=C, stretch=S, face_groups=poly)
    assert np.array_equal(res2.face_island, res.face_island)


def test_without_polygons_a_quad_diagonal_may_be_cut_with_them_never():
    """The polygons make a difference: on this sphere the triangle search cuts a diagonal."""
    V, F, poly = uv_sphere()
    _, added, _ = unwrap_auto(V, F, bound=C, stretch=S)
    inner = [np.flatnonzero(np.isin(F, p).sum(axis=1) == 2) for p in added.tolist()]
    diagonal = sum(poly[f[0]] == poly[f[1]] for f in inner)
    res, added, _ = unwrap_auto(V, F, bound=C, stretch=S, polygons=poly)
    _check_whole_polygons(F, poly, res, added)
    assert diagonal > 0


def test_polygons_bad_input():
    V, F, poly = uv_sphere()
    with pytest.raises(ValueError, match="polygons"):
        unwrap_auto(V, F, polygons=poly[:-1])
    with pytest.raises(ValueError, match="polygons"):
        unwrap_auto(V, F, polygons=poly.astype(float))
    # A marked seam along a quad's diagonal.
    q = np.flatnonzero(np.bincount(poly) == 2)[0]
    f, g = np.flatnonzero(poly == q)
    diag = np.intersect1d(F[f], F[g])
    with pytest.raises(ValueError, match="inside a polygon"):
        unwrap_auto(V, F, seams=diag[None], polygons=poly)
