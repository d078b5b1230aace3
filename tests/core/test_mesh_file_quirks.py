"""Mesh files as real tools and hand-written assets write them (found in unseen21 on
github.com/kovacsv/Online3DViewer's test files, MIT): blank and ``comment`` lines inside an ASCII
PLY's body and a comment after an OBJ record. Each is read as the
clean file it stands for; a file no reader can parse is an ``InvalidMeshError`` naming the file,
never a traceback."""
import numpy as np
import pytest

import bd_uv.meshio
from bd_uv.errors import InvalidMeshError
from bd_uv.meshio import load_mesh

PLY_HEAD = ("ply\nformat ascii 1.0\n{comment}element vertex 5\nproperty float x\nproperty float y\n"
            "property float z\nelement face 2\nproperty list uchar int vertex_index\nend_header\n")
PLY_VERTS = ["0 0 0", "1 0 0", "1 1 0", "0 1 0", "2 0.5 0"]
PLY_FACES = ["4 0 1 2 3", "3 1 4 2"]            # a quad and a triangle: 3 triangles


@pytest.mark.parametrize("body", [
    PLY_VERTS + PLY_FACES,                                          # clean
    [""] + PLY_VERTS + [""] + PLY_FACES,                            # blank lines
    PLY_VERTS[:1] + ["comment between records", "", "  comment indented"] + PLY_VERTS[1:]
    + PLY_FACES,                                                    # comment lines in the body
])
def test_ascii_ply_body_with_blank_and_comment_lines(tmp_path, body):
    p = tmp_path / "m.ply"
    p.write_text(PLY_HEAD.format(comment="comment header comment\n") + "\n".join(body) + "\n")
    m = load_mesh(str(p))
    assert np.array_equal(m.V, np.array([[float(c) for c in v.split()] for v in PLY_VERTS]))
    # the quad's two triangles and the triangle, as sets of corners (trimesh's split of the quad)
    assert len(m.F) == 3
    tris = sorted(map(sorted, m.F.tolist()))
    assert tris[-1] == [1, 2, 4]
    assert set(np.ravel(tris[:2])) == {0, 1, 2, 3}


def test_unreadable_files_are_invalid_mesh_errors_naming_the_file(tmp_path, monkeypatch):
    p = tmp_path / "bad.ply"
    p.write_text("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\nfoo\n")
    with pytest.raises(InvalidMeshError, match="bad.ply: cannot read the mesh as PLY"):
        load_mesh(str(p))

    def broken(*a, **k):                   # any exception of the loader, e.g. trimesh 4.8.3's
        raise UnboundLocalError("faces")   # UnboundLocalError on a comment line in a PLY body
    monkeypatch.setattr("trimesh.load", broken)
    (tmp_path / "m.off").write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    with pytest.raises(InvalidMeshError, match=r"m.off: cannot read the mesh as OFF "
                                               r"\(UnboundLocalError: faces\)"):
        bd_uv.meshio.load_mesh(str(tmp_path / "m.off"))


def test_obj_comment_after_a_record(tmp_path):
    lines = ["v 0 0 0", "v 1 0 0", "v 1 1 0", "v 0 1 0", "vt 0 0", "vt 1 0", "vt 1 1", "vt 0 1",
             "usemtl Red", "f 1/1 2/2 3/3 4/4", "usemtl Green#2", "f 1/1 3/3 4/4"]
    (tmp_path / "a.obj").write_text("\n".join(lines) + "\n")
    noted = [ln + (" # note" if i % 2 else "\t# note") for i, ln in enumerate(lines)]
    (tmp_path / "b.obj").write_text("\n".join(noted) + "\n")
    a, b = load_mesh(str(tmp_path / "a.obj")), load_mesh(str(tmp_path / "b.obj"))
    assert np.array_equal(a.F, b.F) and np.array_equal(a.corner_uv, b.corner_uv)
    assert a.F.tolist() == [[0, 1, 2], [0, 2, 3], [0, 2, 3]]
    assert b.labels["material"].tolist() == [0, 0, 1]    # "Green#2": a '#' inside a name stays
