"""Polygons triangulated for the solve (bd_uv/polygons.py): a sound fan kept as it was, concave
polygons and corners in a line ear-clipped; checked with shapely's areas and, end to end, with
a USD stage of concave polygons whose written UVs are measured on this test's own constrained
triangulation (the `triangle` package)."""
import json

import numpy as np
import pytest
import triangle as tr
from shapely.geometry import Polygon
from shapely.ops import unary_union

from bd_uv.polygons import fan_triangles, triangulate
from helpers import reference_distortion
from overlap_shapes import overlapping_triangle_pairs

COMB = [(0, 0), (7, 0), (7, 3), (6, 3), (6, 1), (5, 1), (5, 3), (4, 3), (4, 1), (3, 1), (3, 3),
        (2, 3), (2, 1), (1, 1), (1, 3), (0, 3)]
L_SHAPE = [(2, 1), (1, 1), (1, 2), (0, 2), (0, 0), (2, 0)]      # its fan leaves the polygon
IN_A_LINE = [(0, 0), (1, 0), (2, 0), (2, 1), (0, 1)]           # its fan has a flat triangle


def star(n=9, inner=0.35):
    t = np.linspace(0, 2 * np.pi, 2 * n, endpoint=False)
    r = np.where(np.arange(2 * n) % 2 == 0, 1.0, inner)
    return np.column_stack([r * np.cos(t), r * np.sin(t)])


def _tiles(poly2d, tilt=(0.3, -0.2, 0.5)):
    """The polygon in a tilted plane of space: (V (c,3), its triangles as (t,3,2) in the plane)."""
    q = np.asarray(poly2d, dtype=np.float64)
    a, b = np.array([1.0, 0.0, tilt[0]]), np.array([tilt[1], 1.0, tilt[2]])
    return q[:, :1] * a + q[:, 1:] * b


def _check_tiles(q, T):
    """The triangles tile the polygon: every one turns its way with an area, their areas add up
    to the polygon's, and their union is the polygon."""
    P = q[T]
    area = 0.5 * ((P[:, 1, 0] - P[:, 0, 0]) * (P[:, 2, 1] - P[:, 0, 1])
                  - (P[:, 1, 1] - P[:, 0, 1]) * (P[:, 2, 0] - P[:, 0, 0]))
    shape = Polygon(q)
    assert (area > 1e-6 * shape.area).all()
    assert abs(area.sum() - shape.area) < 1e-9 * shape.area
    assert abs(unary_union([Polygon(t) for t in P]).area - shape.area) < 1e-9 * shape.area


@pytest.mark.parametrize("shape", [COMB, L_SHAPE, IN_A_LINE, star(), star(5, 0.1)],
                         ids=["comb", "L", "in a line", "star", "thin star"])
@pytest.mark.parametrize("first", [0, 3])
def test_unsound_fans_are_ear_clipped_into_tiles(shape, first):
    q = np.roll(np.asarray(shape, dtype=np.float64), -first, axis=0)
    V = _tiles(q)
    T, poly, clipped = triangulate(V, [len(q)], np.arange(len(q)))
    assert len(T) == len(q) - 2 and (poly == 0).all()
    _check_tiles(q, T)


def test_sound_fans_are_kept_and_rows_stay_per_polygon():
    # a convex hexagon, a square, a triangle, the L (unsound), a square again: only the L changes
    hexagon = [(np.cos(t), np.sin(t)) for t in np.linspace(0, 2 * np.pi, 6, endpoint=False)]
    shapes = [hexagon, [(0, 0), (1, 0), (1, 1), (0, 1)], [(0, 0), (1, 0), (0, 1)], L_SHAPE,
              [(0, 0), (2, 0), (2, 2), (0, 2)]]
    q = np.concatenate([np.asarray(s, dtype=np.float64) for s in shapes])
    counts = np.array([len(s) for s in shapes])
    corners = np.arange(len(q))[::-1].copy()               # corners need not be in order
    V = np.empty((len(q), 3))
    V[corners] = _tiles(q)
    T, poly, clipped = triangulate(V, counts, corners)
    fan, fan_poly = fan_triangles(counts)
    assert clipped.tolist() == [3] and np.array_equal(poly, fan_poly)
    keep = poly != 3
    assert np.array_equal(T[keep], fan[keep])
    _check_tiles(q[13:19], T[poly == 3] - 13)


def test_a_polygon_crossing_itself_keeps_a_triangle_per_corner():
    bowtie = np.array([(0, 0), (2, 2), (2, 0), (0, 2)], dtype=np.float64)
    T, poly, _ = triangulate(_tiles(bowtie), [4], np.arange(4))
    assert len(T) == 2 and set(T.ravel()) <= {0, 1, 2, 3}


def _glyph():
    """A flat sheet of a comb (17 corners, one in the middle of its right side), an L and a
    rectangle with a corner in the middle of a side, sharing edges, in a tilted plane: no fan of
    the comb or the L stays inside it, the rectangle's has a flat triangle. (points in the
    plane (n,2), in space (n,3), the polygons' corners)"""
    pts = {}

    def ids(poly):
        return [pts.setdefault(p, len(pts)) for p in poly]
    comb = ids(COMB[:2] + [(7, 2)] + COMB[2:])           # y 0..3, x 0..7
    ell = ids([(7, 0), (9, 0), (9, 4), (8, 4), (8, 2), (7, 2)])
    low = ids([(7, 2), (8, 2), (8, 4), (7, 4), (7, 3)])   # (7, 3) lies on its side
    q = np.array(sorted(pts, key=pts.get), dtype=np.float64)
    return q, _tiles(q, (0.2, 0.1, 0.3)), [comb, ell, low]


def _glyph_stage(path):
    """``_glyph`` as a USD stage (float32 points)."""
    from pxr import Usd, UsdGeom, Vt
    q, V, polys = _glyph()
    stage = Usd.Stage.CreateNew(str(path))
    mesh = UsdGeom.Mesh.Define(stage, "/Glyph")
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(V.astype(np.float32)))
    mesh.CreateFaceVertexCountsAttr([len(p) for p in polys])
    mesh.CreateFaceVertexIndicesAttr([v for p in polys for v in p])
    stage.GetRootLayer().Save()
    return V.astype(np.float32).astype(np.float64), q, polys


def _own_triangles(q, polygons):
    """This test's triangles of each polygon (corner lists of ids into ``q``): its constrained
    Delaunay triangulation in the plane, no point added; (t,3) places in ``polygons`` joined."""
    tris, start = [], 0
    for p in polygons:
        c = len(p)
        seg = np.stack([np.arange(c), (np.arange(c) + 1) % c], 1)
        t = tr.triangulate({"vertices": q[p], "segments": seg}, "p")
        assert len(t["vertices"]) == c
        tris.append(start + t["triangles"])
        start += c
    return np.concatenate(tris)


def test_a_stage_of_concave_polygons_is_certified_on_its_own_triangles(tmp_path):
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom
    from bd_uv.cli import main
    src, out, rep = tmp_path / "glyph.usda", tmp_path / "o.usda", tmp_path / "r.json"
    V, q, polys = _glyph_stage(src)
    assert main(["unwrap", str(src), "-o", str(out), "--report", str(rep)]) == 0
    (entry,) = json.loads(rep.read_text())["meshes"]
    assert entry["status"] == "certified"
    written = Usd.Stage.Open(str(out))       # kept: a prim of a collected stage is invalid
    pv = UsdGeom.PrimvarsAPI(written.GetPrimAtPath("/Glyph")).GetPrimvar("st")
    uv = np.asarray(pv.Get(), np.float64)[np.asarray(pv.GetIndices())]      # per face-vertex
    T = _own_triangles(q, polys)
    idx = np.concatenate(polys)
    D, flipped = reference_distortion(V, idx[T], uv[T])
    assert not flipped.any() and D.max() <= entry["bound_certified"] * (1 + 1e-6)
    assert len(overlapping_triangle_pairs(uv[T])) == 0


def test_an_obj_of_concave_polygons_is_written_whole_and_certified(tmp_path):
    # the same sheet as an OBJ: written back with its polygons whole (OBJ to OBJ keeps them),
    # the UVs per corner measured on this test's own constrained triangulation
    from bd_uv.cli import main
    q, V, polys = _glyph()
    src, out, rep = tmp_path / "glyph.obj", tmp_path / "o.obj", tmp_path / "r.json"
    src.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in V.tolist())
                   + "".join("f " + " ".join(str(i + 1) for i in p) + "\n" for p in polys))
    assert main(["unwrap", str(src), "-o", str(out), "--report", str(rep), "-q"]) == 0
    report = json.loads(rep.read_text())
    assert [e["status"] for e in report["islands"]] == ["certified"]
    lines = out.read_text().splitlines()
    vt = np.array([[float(t) for t in ln.split()[1:3]] for ln in lines if ln.startswith("vt ")])
    faces = [[tuple(int(x) - 1 for x in c.split("/")[:2]) for c in ln.split()[1:]]
             for ln in lines if ln.startswith("f ")]
    assert [[v for v, _ in f] for f in faces] == polys           # polygons whole, as written
    T = _own_triangles(q, polys)
    corner = np.concatenate([[(v, t) for v, t in f] for f in faces])     # (v, vt) per corner
    tris, uv = corner[T][..., 0], vt[corner[T][..., 1]]
    D, flipped = reference_distortion(V, tris, uv)
    assert not flipped.any() and D.max() <= report["islands"][0]["bound_certified"] * (1 + 1e-6)
    assert len(overlapping_triangle_pairs(uv)) == 0


@pytest.mark.parametrize("binary", [False, True], ids=["ascii", "binary"])
@pytest.mark.parametrize("shape", [L_SHAPE, IN_A_LINE, COMB], ids=["L", "in a line", "comb"])
def test_a_ply_of_polygons_of_one_length_is_triangulated_as_other_polygons(tmp_path, shape,
                                                                          binary):
    # found by the polygon fuzz contract (test_fuzz_polygons.py): an ASCII PLY, or a binary one
    # whose faces all have one length, is read by trimesh, which fanned its polygons from their
    # first corner (a triangle outside the L, one of no area in a line); now each polygon is
    # triangulated as an OBJ's or a mixed binary PLY's are, its triangles tiling it
    import struct
    from bd_uv.meshio import load_mesh
    q = np.asarray(shape, dtype=np.float64)
    V = _tiles(q).astype(np.float32)
    c = len(q)
    head = (f"ply\nformat {'binary_little_endian' if binary else 'ascii'} 1.0\n"
            f"element vertex {c}\nproperty float x\nproperty float y\nproperty float z\n"
            f"element face 1\nproperty list uchar int vertex_indices\nend_header\n").encode()
    if binary:
        body = V.astype("<f4").tobytes() + struct.pack(f"<B{c}i", c, *range(c))
    else:
        body = ("".join(" ".join(repr(float(x)) for x in v) + "\n" for v in V.tolist())
                + f"{c} " + " ".join(map(str, range(c))) + "\n").encode()
    path = tmp_path / "poly.ply"
    path.write_bytes(head + body)
    m = load_mesh(str(path))
    assert len(m.F) == c - 2
    _check_tiles(q, m.F)


def test_a_usd_polygon_has_no_triangle_float32_cannot_tell_from_a_line(tmp_path):
    # found by the polygon fuzz contract: two cells of a gently curved sheet as one hexagon,
    # three corners in a line on each long side; float32 moved the middle ones off their lines
    # by ~1e-9, so the fan from the first corner kept a triangle over three of them, which the
    # scene unwrap (measuring faces at float32) refused as of no area: with --seams none the
    # island failed and the stage was not written
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom
    from bd_uv.cli import main
    from bd_uv.repair import zero_area_faces
    xy = np.array([(0, 0), (1, 0), (0, 1), (1, 1), (0, 2), (1, 2)], dtype=np.float64)
    V = np.column_stack([xy, 0.03 * (xy[:, 0] - 0.5) ** 2 + 0.02 * xy[:, 1]])
    V = V.astype(np.float32).astype(np.float64)
    hexagon = [0, 1, 3, 5, 4, 2]
    T, _, _ = triangulate(V, [6], np.array(hexagon), precision=np.float32)
    F = np.array(hexagon)[T]
    assert not zero_area_faces(V, F, np.float32).any()
    assert zero_area_faces(V, np.array(hexagon)[fan_triangles([6])[0]], np.float32).any()
    src, out = tmp_path / "sheet.usda", tmp_path / "o.usda"
    stage = Usd.Stage.CreateNew(str(src))
    mesh = UsdGeom.Mesh.Define(stage, "/Sheet")
    mesh.CreatePointsAttr([tuple(p) for p in V.tolist()])
    mesh.CreateFaceVertexCountsAttr([6])
    mesh.CreateFaceVertexIndicesAttr(hexagon)
    stage.GetRootLayer().Save()
    assert main(["unwrap", str(src), "-o", str(out), "--seams", "none", "-q"]) == 0
    assert out.exists()


@pytest.mark.parametrize("at", [0, 4, 17])
def test_a_usd_polygon_with_two_corners_at_one_place_is_one_island(tmp_path, at):
    # found by the polygon fuzz contract: a star whose corners ``at`` and ``at + 1`` are two
    # points at one place; the triangle between them has no area and is left out, and the
    # star's other triangles met only at a point: two islands, whose UVs at that face-vertex
    # one UV per face-vertex cannot hold ("fail as stored", the stage not written). The two
    # points are one vertex for the unwrap now (as an OBJ's are welded)
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom
    from bd_uv.cli import main
    q = star(9, 0.35)
    q = np.insert(q, at + 1, q[at], axis=0)
    V = _tiles(q).astype(np.float32)
    src, out, rep = tmp_path / "star.usda", tmp_path / "o.usda", tmp_path / "r.json"
    stage = Usd.Stage.CreateNew(str(src))
    mesh = UsdGeom.Mesh.Define(stage, "/Star")
    mesh.CreatePointsAttr([tuple(p) for p in V.tolist()])
    mesh.CreateFaceVertexCountsAttr([len(q)])
    mesh.CreateFaceVertexIndicesAttr(list(range(len(q))))
    stage.GetRootLayer().Save()
    assert main(["unwrap", str(src), "-o", str(out), "--report", str(rep), "-q"]) == 0
    (entry,) = json.loads(rep.read_text())["meshes"]
    assert entry["status"] == "certified" and entry["zero_area_faces"] == 1
    written = Usd.Stage.Open(str(out))       # kept: a prim of a collected stage is invalid
    pv = UsdGeom.PrimvarsAPI(written.GetPrimAtPath("/Star")).GetPrimvar("st")
    uv = np.asarray(pv.Get(), np.float64)
    if pv.IsIndexed():
        uv = uv[np.asarray(pv.GetIndices())]
    assert np.array_equal(uv[at], uv[at + 1])          # one place, one UV
    T, _, _ = triangulate(V.astype(np.float64), [len(q)], np.arange(len(q)),
                          precision=np.float32)
    P = V.astype(np.float64)
    area = np.linalg.norm(np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]]), axis=1)
    keep = area > 1e-9
    D, flipped = reference_distortion(P, T[keep], uv[T[keep]])
    assert not flipped.any() and D.max() <= entry["bound_certified"] * (1 + 1e-6)
    assert len(overlapping_triangle_pairs(uv[T[keep]])) == 0
