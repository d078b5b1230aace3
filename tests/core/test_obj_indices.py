"""OBJ files as exporters and assimp's test set (github.com/assimp/assimp test/models/OBJ, BSD)
write them (unseen22): negative indices count back from the records read so far, object by
object; records separated by tabs; UTF-16 text with a byte order mark. An index that names no
vertex is refused with the file's line, never read as another vertex."""
import numpy as np
import pytest

from bd_uv.cli import main
from bd_uv.errors import InvalidMeshError
from bd_uv.meshio import load_mesh

# Two objects, each a unit square (two triangles) with its own UVs, written as whole-file
# (absolute) indices and as an exporter writing object by object writes them (relative).
SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]


def _objects(relative):
    lines = []
    for k in range(2):
        lines.append(f"o part{k}")
        lines += [f"v {x + 3 * k} {y} {0.5 * k}" for x, y in SQUARE]
        lines += [f"vt {0.4 * x + 0.5 * k} {0.4 * y}" for x, y in SQUARE]
        idx = [-4, -3, -2, -1] if relative else [4 * k + i for i in (1, 2, 3, 4)]
        lines.append("f " + " ".join(f"{i}/{i}" for i in idx[:3]))
        lines.append("f " + " ".join(f"{i}/{i}" for i in (idx[0], idx[2], idx[3])))
    return "\n".join(lines) + "\n"


def test_negative_indices_count_back_from_the_records_read_so_far(tmp_path):
    (tmp_path / "abs.obj").write_text(_objects(relative=False))
    (tmp_path / "rel.obj").write_text(_objects(relative=True))
    a, r = load_mesh(str(tmp_path / "abs.obj")), load_mesh(str(tmp_path / "rel.obj"))
    assert a.F.tolist() == [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]]
    assert np.array_equal(r.F, a.F)
    assert np.array_equal(r.corner_uv, a.corner_uv)
    # each face's corners are its own object's square: its x within [3k, 3k + 1]
    for f, k in zip(r.F, (0, 0, 1, 1)):
        assert np.all((r.V[f, 0] >= 3 * k) & (r.V[f, 0] <= 3 * k + 1))
    # the command line writes the first object's faces on the first object's vertices
    out = tmp_path / "out.obj"
    assert main(["unwrap", str(tmp_path / "rel.obj"), "-o", str(out), "-q"]) == 0
    back = load_mesh(str(out))
    assert np.array_equal(back.V[back.F], a.V[a.F])


@pytest.mark.parametrize("encoding", ["utf-16-le", "utf-16-be"])
def test_utf16_with_a_byte_order_mark_and_tab_separated_records(tmp_path, encoding):
    text = _objects(relative=False)
    (tmp_path / "plain.obj").write_text(text)
    tabbed = text.replace("v ", "v\t").replace("f ", "f\t").replace("vt ", "vt\t")
    (tmp_path / "wide.obj").write_bytes("\ufeff".encode(encoding) + tabbed.encode(encoding))
    plain, wide = load_mesh(str(tmp_path / "plain.obj")), load_mesh(str(tmp_path / "wide.obj"))
    assert np.array_equal(plain.V, wide.V) and np.array_equal(plain.F, wide.F)
    assert np.array_equal(plain.corner_uv, wide.corner_uv)
    assert wide.labels["object"].tolist() == [0, 0, 1, 1]


@pytest.mark.parametrize("face, said", [
    ("f 1 2 0", r"line 4: face uses v 0, but 3 v record\(s\) come before it"),
    ("f -1 -2 -4", r"line 4: face uses v -4, but 3 v record\(s\) come before it"),
    ("f 1 2 7", r"line 4: face uses v 7, but the file has 3 v record\(s\)"),
    ("f 1 2 x", r"line 4: 'x' is not a v index"),
])
def test_an_index_naming_no_vertex_is_refused_with_its_line(tmp_path, capsys, face, said):
    p = tmp_path / "bad.obj"
    p.write_text(f"v 0 0 0\nv 1 0 0\nv 0 1 0\n{face}\n")
    with pytest.raises(InvalidMeshError, match="bad.obj " + said):
        load_mesh(str(p))
    out = tmp_path / "out.obj"
    assert main(["unwrap", str(p), "-o", str(out), "-q"]) == 2
    assert not out.exists() and "Traceback" not in capsys.readouterr().err


def test_a_negative_index_before_any_vertex_says_so(tmp_path):
    """tinyobjloader's invalid-relative-vertex-index.obj (a face first): the message read
    "but 0 v record(s) come before it (v indices run 1..0, or -1..-0 counting back)"."""
    p = tmp_path / "first.obj"
    p.write_text("f -4 -3 -2\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n")
    with pytest.raises(InvalidMeshError, match=r"first.obj line 1: face uses v -4, but no v "
                                                r"record comes before it \(a negative index "
                                                r"counts back from the v records before the "
                                                r"face\)"):
        load_mesh(str(p))


def test_a_later_vertex_may_be_named_before_it_is_read(tmp_path):
    # positive indices are resolved against the whole file, as bd-uv read them before
    p = tmp_path / "fwd.obj"
    p.write_text("v 0 0 0\nf 1 2 3\nv 1 0 0\nv 0 1 0\n")
    assert load_mesh(str(p)).F.tolist() == [[0, 1, 2]]


def test_a_utf8_byte_order_mark_does_not_hide_the_first_record(tmp_path):
    # Windows tools write UTF-8 with a BOM; the first record ("v ...") was read as "\ufeffv"
    # and dropped, so every face named the vertex after the one meant
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 1\nf 1 2 3\nf 2 4 3\n"
    (tmp_path / "bom.obj").write_bytes(b"\xef\xbb\xbf" + text.encode())
    (tmp_path / "plain.obj").write_text(text)
    bom, plain = load_mesh(str(tmp_path / "bom.obj")), load_mesh(str(tmp_path / "plain.obj"))
    assert np.array_equal(bom.V, plain.V) and np.array_equal(bom.F, plain.F)
