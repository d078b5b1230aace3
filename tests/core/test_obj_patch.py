"""An OBJ unwrapped to an OBJ is its own text with only its UVs replaced (``bd_uv.obj.patch``):
every record but ``vt`` and ``f`` kept byte for byte in order, every face's vertex and normal
indices as written, polygons kept as polygons (a polygon kept in one island: each corner one
UV), and the new UVs certified as the file stores them, recomputed here from the file by a
reader that shares no code with bd_uv (``artist_obj``)."""
import json

import numpy as np
import pytest

from artist_obj import artist_obj, fan_uvs, read_faces, records
from bd_uv.cli import main
from bd_uv.errors import InvalidMeshError
from bd_uv.obj import patched_obj, polygon_corner_vt
from overlap_shapes import overlapping_triangle_pairs
from unwrap_contract import DATA, distortion_and_flips, read_off


def three_peaks_disk(n_faces=200):
    """The first ``n_faces`` faces of three_peaks, vertices renumbered: one disk."""
    V, F = read_off(DATA / "three_peaks.off")
    used, inv = np.unique(F[:n_faces], return_inverse=True)
    return V[used], inv.reshape(-1, 3)


def unwrap_figures(report):
    """(certified bound, max distortion as stored) of an ``unwrap`` report, every island
    certified."""
    rep = json.loads(report.read_text())
    assert all(e["status"] == "certified" for e in rep["islands"])
    return (max(e["bound_certified"] for e in rep["islands"]),
            max(s["max_distortion"] for e in rep["islands"] for s in e["stored"]))


def assert_uvs_replaced_only(src, out, written, figures, split=0):
    """The OBJ at ``out`` is ``src`` with only its UVs replaced, its UVs certified as stored
    (``figures``: the run's certified bound and max distortion as stored)."""
    a, b = src.read_bytes(), out.read_bytes()
    keep_a = [r for k, r in records(a) if k not in ("vt", "f")]
    keep_b = [r for k, r in records(b) if k not in ("vt", "f")]
    assert keep_a == keep_b, "a record other than vt and f changed, moved or went missing"
    # the faces in their places among the other records: one vt block, where the first vt was
    keys_a = [k for k, _ in records(a) if k != "vt"]
    keys_b = [k for k, _ in records(b) if k != "vt"]
    first_vt = [k for k, _ in records(b)].index("vt")
    assert [k for k, _ in records(b)][first_vt:].count("vt") == len(
        [k for k, _ in records(b) if k == "vt"])
    V, VT, faces = read_faces(b)
    if split == 0:
        assert keys_a == keys_b
        assert len(faces) == len(written)
        for (corners, text), w in zip(faces, written):
            assert text == w["tokens"], "a face's vertex or normal index text changed"
            assert [c[0] for c in corners] == w["v"]
            assert [c[2] for c in corners] == (w["vn"] or [None] * len(corners))
            assert all(c[1] is not None for c in corners), "a corner without its UV"
    # the UVs as the file stores them, recomputed from it: no flip, distortion within the
    # certified bound, the stored figures the report gives, no two UV triangles overlapping
    tris, uv, _ = fan_uvs(V, VT, faces)
    D, flipped = distortion_and_flips(V, tris, uv)
    bound, stored = figures
    assert not flipped.any()
    assert D.max() <= bound * (1 + 2e-6)
    assert D.max() == pytest.approx(stored, rel=1e-9)
    assert len(overlapping_triangle_pairs(uv)) == 0
    return faces


@pytest.mark.parametrize("crlf, bom", [(True, False), (False, True)])
def test_an_artist_obj_keeps_its_records_polygons_and_indices(tmp_path, capsys, crlf, bom):
    V, F = three_peaks_disk()
    data, written = artist_obj(V, F, crlf=crlf)
    src, out, rep = tmp_path / "model.obj", tmp_path / "out.obj", tmp_path / "r.json"
    src.write_bytes((b"\xef\xbb\xbf" if bom else b"") + data)
    before = src.read_bytes()
    assert main(["unwrap", str(src), "-o", str(out), "--report", str(rep), "-q"]) == 0
    said = capsys.readouterr().out
    assert src.read_bytes() == before
    assert "written as their triangles" not in said
    assert "of the file's vertices lie where another does" in said     # the split vertex
    assert out.read_bytes().startswith(b"\xef\xbb\xbf") == bom
    assert (b"\r\n" in out.read_bytes()) == crlf
    assert sorted({len(w["v"]) for w in written}) == [3, 4, 5]     # triangles, quads, a pentagon
    assert_uvs_replaced_only(src, out, written, unwrap_figures(rep))


def test_the_batch_writes_the_same_patched_obj(tmp_path):
    V, F = three_peaks_disk()
    data, written = artist_obj(V, F)
    (tmp_path / "in").mkdir()
    src = tmp_path / "in" / "model.obj"
    src.write_bytes(data)
    rep = tmp_path / "batch.json"
    assert main(["batch", str(tmp_path / "in"), "-o", str(tmp_path / "out"), "--report",
                 str(rep)]) == 0
    item = json.loads(rep.read_text())["items"][0]
    assert item["status"] == "certified" and "polygons_as_triangles" not in item
    assert_uvs_replaced_only(src, tmp_path / "out" / "model.obj", written,
                             (item["bound_certified"], item["max_distortion"]))


def spiral_obj(turns_deg=900, corners=16):
    """One polygon whose fan from its first corner turns ``turns_deg`` degrees round it (a
    helix): no flat map of it lies over itself nowhere, so its island is cut through it."""
    t = np.radians(np.arange(corners) * turns_deg / (corners - 1))
    P = np.column_stack([np.cos(t), np.sin(t), 0.1 * np.arange(corners)])
    lines = ["# a spiral", "o spiral", "v 0 0 0"] + [f"v {x!r} {y!r} {z!r}" for x, y, z in
                                                     P.tolist()]
    lines += ["vn 0 0 1", "usemtl m", "f " + " ".join(f"{i}//1" for i in range(1, corners + 2)),
              "# end"]
    return ("\n".join(lines) + "\n").encode()


def test_a_polygon_cut_through_is_written_as_its_triangles_and_said(tmp_path, capsys):
    src, out, rep = tmp_path / "spiral.obj", tmp_path / "out.obj", tmp_path / "r.json"
    src.write_bytes(spiral_obj())
    assert main(["unwrap", str(src), "-o", str(out), "--report", str(rep), "-q",
                 "--bound", "1.5"]) == 0
    assert "1 polygon(s) written as their triangles" in capsys.readouterr().out
    assert json.loads(rep.read_text())["polygons_as_triangles"] == 1
    faces = assert_uvs_replaced_only(src, out, None, unwrap_figures(rep), split=1)
    # its 15 fan triangles, in order, each with its normal index as written
    assert [[c[0] for c in corners] for corners, _ in faces] == [
        [0, j, j + 1] for j in range(1, 16)]
    assert all(text == [(str(c[0] + 1), "1") for c in corners] for corners, text in faces)


def test_polygon_corner_vt_one_uv_per_corner_or_the_polygon_is_not_whole():
    # a quad (triangles 0-1: corners 0,1,2 and 0,2,3), a triangle, a pentagon (3 triangles)
    poly = np.array([0, 0, 1, 2, 2, 2])
    F_vt = np.array([[0, 1, 2], [0, 2, 3],              # quad: agrees
                     [-1, -1, -1],                       # triangle: no UVs
                     [4, 5, 6], [4, 6, 7], [9, 7, 8]])   # pentagon: corner 0 is 4 and 9
    corner_vt, starts, whole = polygon_corner_vt(poly, F_vt)
    assert starts.tolist() == [0, 4, 7, 12]
    assert whole.tolist() == [True, True, False]
    assert corner_vt.tolist() == [0, 1, 2, 3, -1, -1, -1] + [-1] * 5
    # only some triangles of a polygon with UVs: not whole either
    assert not polygon_corner_vt([0, 0], [[0, 1, 2], [-1, -1, -1]])[2][0]


def test_patched_obj_writes_a_split_polygon_as_triangles_and_keeps_the_rest(tmp_path):
    src = tmp_path / "in.obj"
    src.write_bytes(b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 9 9\nvn 0 0 1\n"
                    b"f 1/1/1 2/1/1 3/1/1 4/1/1 # quad\nl 1/1 3/1\nf 1 2 3\nf -4//1 -2//1 -1//1\n")
    F = np.array([[0, 1, 2], [0, 2, 3], [0, 1, 2], [0, 2, 3]])
    poly = np.array([0, 0, 1, 2])
    uv = np.array([[0.0, 0.0], [0.5, 0.0], [0.5, 0.5], [0.0, 0.5], [0.25, 0.25]])
    F_vt = np.array([[0, 1, 2], [4, 2, 3], [-1, -1, -1], [0, 2, 3]])   # the quad disagrees
    assert patched_obj(str(src), str(tmp_path / "out.obj"), F, poly, F_vt, uv) == 1
    assert (tmp_path / "out.obj").read_text() == (
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
        "vt 0.0 0.0\nvt 0.5 0.0\nvt 0.5 0.5\nvt 0.0 0.5\nvt 0.25 0.25\n"
        "vn 0 0 1\n"
        "f 1/1/1 2/2/1 3/3/1\nf 1/5/1 3/3/1 4/4/1 # quad\n"
        "l 1 3\nf 1 2 3\nf -4/1/1 -2/3/1 -1/4/1\n")


def test_an_input_changed_since_it_was_read_is_refused_and_nothing_written(tmp_path):
    src = tmp_path / "in.obj"
    src.write_bytes(b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    uv = np.zeros((4, 2))
    for F, poly in ((np.array([[0, 1, 2], [0, 2, 3]]), np.array([0, 0])),
                    (np.array([[0, 1, 3], [0, 2, 3]]), np.array([0, 0])),    # other vertices
                    (np.array([[0, 1, 2]]), np.array([0])),                  # fewer corners
                    (np.array([[0, 1, 2], [0, 2, 3], [0, 1, 2]]), np.array([0, 0, 1]))):
        F_vt = np.tile([0, 1, 2], (len(F), 1))
        if len(F) == 2 and F[0, 2] == 2:
            continue        # the file's own faces: written
        with pytest.raises(InvalidMeshError, match="changed since it was read"):
            patched_obj(str(src), str(tmp_path / "out.obj"), F, poly, F_vt, uv)
        assert not (tmp_path / "out.obj").exists()


def test_a_fan_with_a_triangle_of_no_area_is_turned_to_another_corner():
    from bd_uv.mesh.arrays import DEGENERATE_RATIO
    from bd_uv.polygons import DEGENERATE_RATIO as FLAT, triangulate
    assert FLAT == DEGENERATE_RATIO       # the unwrap's own test of a face with no area

    def fan_corners(V, corner_v, starts):
        T, polygon, _ = triangulate(V, np.diff(starts), corner_v)
        return polygon, T - np.asarray(starts)[polygon][:, None]
    # a pentagon 0..4 whose corners 0, 1, 2 lie on a line (from 0: triangle 0 1 2 has no area)
    # and a square (its fan from 0 kept)
    V = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0], [3, 0, 0], [3, 1, 0]],
                 float)
    polygon, corners = fan_corners(V, [0, 1, 2, 3, 4, 2, 5, 6, 3], [0, 5, 9])
    assert polygon.tolist() == [0, 0, 0, 1, 1]
    assert corners.tolist() == [[1, 2, 3], [1, 3, 4], [1, 4, 0], [0, 1, 2], [0, 2, 3]]
    # a fan from the corner off the line, however near it (1e-7 of its length)
    W = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [1.5, 3e-7, 0]])
    assert fan_corners(W, [0, 1, 2, 3, 4], [0, 5])[1].tolist() == [[4, 0, 1], [4, 1, 2],
                                                                   [4, 2, 3]]
    # no corner gives a fan without such a triangle (all on a line): from the first, as before
    assert fan_corners(W[:4], [0, 1, 2, 3], [0, 4])[1].tolist() == [[0, 1, 2], [0, 2, 3]]


def test_an_ngon_with_three_corners_on_a_line_stays_one_polygon(tmp_path, capsys):
    """An n-gon whose straight side holds three corners (dissolved edges): fanned from its
    first corner its first triangle had no area, which the unwrap refused (exit 1) and the
    n-gon was written as its triangles; fanned from the second corner it is certified whole."""
    src, out, rep = tmp_path / "ngon.obj", tmp_path / "out.obj", tmp_path / "r.json"
    src.write_bytes(b"v 0 0 0\nv 1 0 0\nv 2 0 0\nv 2 1 0.2\nv 0 1 0\nv 0 2 0\nv 2 2 0\n"
                    b"vn 0 0 1\nf 1//1 2//1 3//1 4//1 5//1\nf 5//1 4//1 7//1 6//1\n")
    assert main(["unwrap", str(src), "-o", str(out), "--report", str(rep), "-q"]) == 0
    assert "written as their triangles" not in capsys.readouterr().out
    written = [dict(v=[0, 1, 2, 3, 4], vn=[0] * 5, tokens=[(str(i), "1") for i in range(1, 6)]),
               dict(v=[4, 3, 6, 5], vn=[0] * 4, tokens=[(str(i), "1") for i in (5, 4, 7, 6)])]
    faces = read_faces(out.read_bytes())[2]
    assert [len(c) for c, _ in faces] == [5, 4]
    # the certified triangles are the pentagon's fan from its second corner (a reader fanning
    # from the first gets one triangle of no area and two covering the same pentagon)
    V, VT, _ = read_faces(out.read_bytes())
    turned = [(corners[1:] + corners[:1], text) for corners, text in faces[:1]] + faces[1:]
    tris, uv, _ = fan_uvs(V, VT, turned)
    D, flipped = distortion_and_flips(V, tris, uv)
    bound, stored = unwrap_figures(rep)
    assert not flipped.any() and D.max() <= bound * (1 + 2e-6)
    assert D.max() == pytest.approx(stored, rel=1e-9)
    assert [text for _, text in faces] == [w["tokens"] for w in written]


def test_a_split_polygon_is_written_as_the_fan_it_was_unwrapped_as(tmp_path):
    src = tmp_path / "in.obj"
    src.write_bytes(b"v 0 0 0\nv 1 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nf 1 2 3 4 5\n")
    F = np.array([[1, 2, 3], [1, 3, 4], [1, 4, 0]])
    corners = np.array([[1, 2, 3], [1, 3, 4], [1, 4, 0]])
    uv = np.arange(14, dtype=float).reshape(7, 2)
    F_vt = np.array([[0, 1, 2], [0, 2, 3], [5, 3, 4]])       # corner 1 (vertex 2): 0 and 5
    assert patched_obj(str(src), str(tmp_path / "out.obj"), F, [0, 0, 0], F_vt, uv,
                       corners) == 1
    assert (tmp_path / "out.obj").read_text().splitlines()[-3:] == [
        "f 2/1 3/2 4/3", "f 2/1 4/3 5/4", "f 2/6 5/4 1/5"]


@pytest.mark.parametrize("encoding, mark", [("utf-16-le", b"\xff\xfe"),
                                            ("utf-16-be", b"\xfe\xff")])
def test_a_utf16_obj_is_written_back_in_its_own_encoding(tmp_path, encoding, mark):
    text = ("# \u00e9t\u00e9\r\no quad\r\nv 0 0 0\r\nv 1 0 0\r\nv 1 1 0.1\r\nv 0 1 0\r\n"
            "vn 0 0 1\r\ns 1\r\nf\t1//1 2//1 3//1 4//1\r\n")
    src, out = tmp_path / "in.obj", tmp_path / "out.obj"
    src.write_bytes(mark + text.encode(encoding))
    assert main(["unwrap", str(src), "-o", str(out), "-q"]) == 0
    data = out.read_bytes()
    assert data[:2] == mark
    got = data[2:].decode(encoding).splitlines()
    assert [ln for ln in got if not ln.startswith(("vt", "f"))] == \
        [ln for ln in text.splitlines() if not ln.startswith("f")]
    assert [ln for ln in got if ln.startswith("f")] == ["f 1/1/1 2/2/1 3/3/1 4/4/1"]
    assert sum(ln.startswith("vt ") for ln in got) == 4
