"""OFF and PLY files whose exporter split vertices (assimp's Wuson.ply: 11,184 vertices at 2,117
positions, every face its own three; Blender's PLY exporter splits wherever a normal or UV
differs). Read as they were, each face was an island of its own: 3,732 one-face islands. Now
their vertices at equal positions are welded for the unwrap (never where faces only touch at a
point), the file's own UVs still mark its seams, and the OBJ written keeps the file's vertices
and faces."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from bd_uv.meshio import load_mesh
from bd_uv.mesh.weld import welded_in_place
from helpers import grid, reference_distortion
from overlap_shapes import overlapping_triangle_pairs
from test_repair import REPO, written_corner_uv


def soup(V, F):
    """The mesh written face by face: three vertices of its own per face."""
    return V[F].reshape(-1, 3), np.arange(3 * len(F)).reshape(-1, 3)


def ply_text(V, F, uv=None):
    props = "property float x\nproperty float y\nproperty float z\n"
    props += "property float s\nproperty float t\n" if uv is not None else ""
    rows = V if uv is None else np.column_stack([V, uv])
    return (f"ply\nformat ascii 1.0\nelement vertex {len(V)}\n{props}element face {len(F)}\n"
            "property list uchar int vertex_indices\nend_header\n"
            + "".join(" ".join(repr(float(x)) for x in r) + "\n" for r in rows)
            + "".join(f"3 {a} {b} {c}\n" for a, b, c in F))


def off_text(V, F):
    rows = V.tolist()        # Python floats: numpy 2's scalars repr as np.float64(...)
    return (f"OFF\n{len(V)} {len(F)} 0\n" + "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in rows)
            + "".join(f"3 {a} {b} {c}\n" for a, b, c in F))


def faces_joined(F):
    """Number of edge-connected components of the faces (islands, without seams)."""
    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import connected_components
    e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    face = np.tile(np.arange(len(F)), 3)
    _, edge = np.unique(e, axis=0, return_inverse=True)
    edge = edge.reshape(-1)
    g = coo_array((np.ones(len(face)), (face, len(F) + edge)), shape=(len(F) + edge.max() + 1,) * 2)
    return connected_components(g, directed=False)[0]


@pytest.mark.parametrize("suffix", [".ply", ".off"])
def test_a_triangle_soup_is_read_as_one_surface(tmp_path, suffix):
    V0, F0 = grid(6, 5, z=lambda x, y: 0.3 * x * y)
    V, F = soup(V0, F0)
    p = tmp_path / ("m" + suffix)
    p.write_text(ply_text(V, F) if suffix == ".ply" else off_text(V, F))
    m = load_mesh(str(p))
    assert np.array_equal(m.V, V.astype(np.float32) if suffix == ".ply" else V)
    assert np.array_equal(m.file_F, F)                # the file's faces, kept to be written
    assert faces_joined(m.F) == 1 and faces_joined(F) == len(F)
    # each corner now names the least file vertex at its position: the grid's topology
    first = {}
    for c, v in enumerate(F.ravel()):
        first.setdefault(F0.ravel()[c], v)
    assert np.array_equal(m.F, np.vectorize(first.get)(F0))
    assert m.welded == len(V) - len(V0)


def test_faces_that_only_touch_at_a_point_are_not_joined():
    # two triangles with a vertex each at the origin, written twice: a point contact (bow-tie)
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 0, 0], [-1, 0, 0], [-1, -1, 0]], float)
    F = np.array([[0, 1, 2], [3, 4, 5]])
    assert np.array_equal(welded_in_place(V, F), F)
    # and joined through an edge they are welded: vertex 3 and 4 lie on 0 and 2
    V2 = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    assert np.array_equal(welded_in_place(V2, F), [[0, 1, 2], [0, 2, 5]])


def test_the_files_own_uvs_mark_its_seams(tmp_path):
    # two squares side by side, written face by face: within each square the split vertices
    # carry equal UVs (as a split normal leaves them), across the middle line they differ
    V0, F0 = grid(3, 2)
    V, F = soup(V0, F0)
    uv = V[:, :2].copy()
    left = V0[F0][:, :, 0].mean(axis=1) < 0.5
    moved = np.repeat(~left, 3)
    uv[moved] += [2.0, 0.0]                        # the right square elsewhere in the file's UVs
    p = tmp_path / "m.ply"
    p.write_text(ply_text(V, F, uv))
    m = load_mesh(str(p))
    assert faces_joined(m.F) == 1
    seams = {tuple(sorted(e)) for e in m.uv_seams().tolist()}
    mid = {tuple(sorted(m.V[list(e)][:, 0].round(6))) for e in seams}
    assert mid == {(0.5, 0.5)}                     # only the middle line, x = 0.5 at both ends
    assert np.allclose(m.corner_uv, uv[F].astype(np.float32))


def test_the_command_line_writes_the_files_vertices_and_faces(tmp_path):
    V0, F0 = grid(7, 6, z=lambda x, y: 0.4 * x * x)
    V, F = soup(V0, F0)
    src = tmp_path / "soup.ply"
    src.write_text(ply_text(V, F))
    before = src.read_bytes()
    out, rep = tmp_path / "out.obj", tmp_path / "r.json"
    r = subprocess.run([sys.executable, "-m", "bd_uv", "unwrap", str(src), "-o", str(out),
                        "--report", str(rep)], capture_output=True, text=True, cwd=REPO)
    assert r.returncode == 0, r.stderr
    assert src.read_bytes() == before
    assert f"{len(V) - len(V0)} of the file's vertices lie where another does" in r.stdout
    report = json.loads(rep.read_text())
    assert report["welded_vertices"] == len(V) - len(V0)
    assert len(report["islands"]) == 1 and report["islands"][0]["status"] == "certified"
    lines = out.read_text().splitlines()
    Vw = np.array([[float(t) for t in ln.split()[1:4]] for ln in lines if ln.startswith("v ")])
    Fw = np.array([[int(t.split("/")[0]) - 1 for t in ln.split()[1:]]
                   for ln in lines if ln.startswith("f ")])
    assert np.allclose(Vw, V.astype(np.float32)) and np.array_equal(Fw, F)
    cuv = written_corner_uv(out)
    D, flipped = reference_distortion(Vw, Fw, cuv)
    assert not flipped.any()
    assert D.max() <= report["islands"][0]["bound_certified"] * (1 + 1e-6)
    assert len(overlapping_triangle_pairs(cuv)) == 0
    # one island: corners at one position carry one UV (the weld made the surface whole)
    pos = {}
    for c, (x, y) in zip(Vw[Fw].reshape(-1, 3).round(6).tolist(), cuv.reshape(-1, 2).tolist()):
        pos.setdefault(tuple(c), set()).add((round(x, 9), round(y, 9)))
    assert max(len(s) for s in pos.values()) == 1


def stl_text(V, F):
    """An ASCII STL: every face its three corners written out (no shared vertices)."""
    rows = ["solid part"]
    for f in F:
        rows += ["  facet normal 0 0 1", "    outer loop"]
        rows += [f"      vertex {x!r} {y!r} {z!r}" for x, y, z in V[f].tolist()]
        rows += ["    endloop", "  endfacet"]
    return "\n".join(rows + ["endsolid part"]) + "\n"


def test_an_stl_written_as_obj_is_read_without_blender(tmp_path):
    V0, F0 = grid(6, 5, z=lambda x, y: 0.2 * y * y)
    src = tmp_path / "part.stl"
    src.write_text(stl_text(V0, F0))
    out, rep = tmp_path / "part.obj", tmp_path / "r.json"
    r = subprocess.run([sys.executable, "-m", "bd_uv", "unwrap", str(src), "-o", str(out),
                        "--report", str(rep)], capture_output=True, text=True, cwd=REPO)
    assert r.returncode == 0, r.stderr
    report = json.loads(rep.read_text())
    assert report["welded_vertices"] == 3 * len(F0) - len(V0)
    assert [e["status"] for e in report["islands"]] == ["certified"]
    lines = out.read_text().splitlines()
    Vw = np.array([[float(t) for t in ln.split()[1:4]] for ln in lines if ln.startswith("v ")])
    Fw = np.array([[int(t.split("/")[0]) - 1 for t in ln.split()[1:]]
                   for ln in lines if ln.startswith("f ")])
    assert len(Vw) == 3 * len(F0) and np.allclose(Vw[Fw], V0[F0], atol=1e-6)
    D, flipped = reference_distortion(Vw, Fw, written_corner_uv(out))
    assert not flipped.any() and D.max() <= report["islands"][0]["bound_certified"] * (1 + 1e-6)
    # to any other format an STL still goes through Blender, and the message names both ways
    r = subprocess.run([sys.executable, "-m", "bd_uv", "unwrap", str(src), "-o",
                        str(tmp_path / "part.blend")], capture_output=True, text=True, cwd=REPO)
    assert r.returncode == 2 and "blender -b --python" in r.stderr
    assert "give -o an .obj path" in r.stderr and not (tmp_path / "part.blend").exists()


def test_a_batch_writes_its_stl_files_as_obj_without_blender(tmp_path):
    V0, F0 = grid(6, 5, z=lambda x, y: 0.2 * y * y)
    folder = tmp_path / "in"
    folder.mkdir()
    (folder / "part.stl").write_text(stl_text(V0, F0))
    before = (folder / "part.stl").read_bytes()
    out = tmp_path / "out"
    # no bpy, no Blender on the PATH: the batch must not need them for an STL
    env = {k: v for k, v in os.environ.items() if k != "BD_UV_BLENDER"}
    env["PATH"] = os.path.dirname(sys.executable)
    r = subprocess.run([sys.executable, "-m", "bd_uv", "batch", str(folder), "-o", str(out),
                        "--jobs", "1"], capture_output=True, text=True, cwd=REPO, env=env)
    assert r.returncode == 0, r.stdout + r.stderr
    assert (folder / "part.stl").read_bytes() == before
    assert sorted(p.name for p in out.iterdir()) == ["part.obj", "report.json"]
    [entry] = json.loads((out / "report.json").read_text())["items"]
    assert entry["status"] == "certified" and entry["welded_vertices"] == 3 * len(F0) - len(V0)
    written = out / "part.obj"
    lines = written.read_text().splitlines()
    Vw = np.array([[float(t) for t in ln.split()[1:4]] for ln in lines if ln.startswith("v ")])
    Fw = np.array([[int(t.split("/")[0]) - 1 for t in ln.split()[1:]]
                   for ln in lines if ln.startswith("f ")])
    assert np.allclose(Vw[Fw], V0[F0], atol=1e-6)
    cuv = written_corner_uv(written)
    D, flipped = reference_distortion(Vw, Fw, cuv)
    assert not flipped.any() and D.max() <= entry["bound_certified"] * (1 + 1e-6)
    assert len(overlapping_triangle_pairs(cuv)) == 0


def test_an_obj_soup_is_welded_within_each_object_only(tmp_path):
    # two bent grids written face by face (three.js's OBJ exporter on unindexed geometry), as
    # two objects that share the line x = 1 exactly: each is welded whole, never to the other
    V0, F0 = grid(5, 4, z=lambda x, y: 0.2 * x * y)
    V1 = V0 + [1.0, 0.0, 0.0]
    V1[:, 2] = 0.2 * (2.0 - V1[:, 0]) * V1[:, 1]      # the same positions along x = 1
    Va, Fa = soup(V0, F0)
    Vb, Fb = soup(V1, F0)
    rows = [f"v {x!r} {y!r} {z!r}" for x, y, z in np.concatenate([Va, Vb]).tolist()]
    rows += ["o left"] + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in Fa]
    rows += ["o right"] + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in Fb + len(Va)]
    p = tmp_path / "two.obj"
    p.write_text("\n".join(rows) + "\n")
    m = load_mesh(str(p))
    assert np.array_equal(m.file_F, np.concatenate([Fa, Fb + len(Va)]))
    left, right = m.F[:len(Fa)], m.F[len(Fa):]
    assert faces_joined(left) == 1 and faces_joined(right) == 1 and faces_joined(m.F) == 2
    assert not set(left.ravel()) & set(right.ravel())
    assert m.welded == 2 * (len(Va) - len(V0))
    # without objects the shared line joins them (one surface)
    p.write_text("\n".join(r for r in rows if not r.startswith("o ")) + "\n")
    assert faces_joined(load_mesh(str(p)).F) == 1


def test_an_obj_without_split_vertices_is_read_as_it_is(tmp_path):
    V0, F0 = grid(4, 3)
    p = tmp_path / "m.obj"
    p.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in V0.tolist())
                 + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F0))
    m = load_mesh(str(p))
    assert m.file_F is None and m.welded == 0 and np.array_equal(m.F, F0)


def _grid_with_a_flat_face():
    """A bent grid and one more face on three corners of its bottom row (0, 1, 2 on a line):
    zero area, sharing the grid's two bottom edges, wound with it."""
    V, F = grid(6, 5, z=lambda x, y: 0.3 * x * y)
    return V, np.vstack([F, [[1, 0, 2]]])


def _check_filled(V, F, path, bound):
    """Every face written with vt; the flat face's corners the vt of their vertices in the
    grid's faces (no seam); the grid's faces certified, recomputed from the file."""
    lines = path.read_text().splitlines()
    ft = [[int(t.split("/")[1]) for t in ln.split()[1:]] for ln in lines if ln.startswith("f ")]
    assert len(ft) == len(F) and all(len(f) == 3 for f in ft)
    ft = np.array(ft)
    for k in range(3):
        assert ft[-1, k] in ft[:-1][F[:-1] == F[-1, k]]
    cuv = written_corner_uv(path)
    D, flipped = reference_distortion(V, F[:-1], cuv[:-1])
    assert not flipped.any() and D.max() <= bound * (1 + 1e-6)
    assert len(overlapping_triangle_pairs(cuv[:-1])) == 0


def test_zero_area_faces_alone_do_not_fail_a_mesh_file(tmp_path):
    # as a scene writes them: every face with an area certified, the flat one given its
    # neighbours' UVs and counted; exit 0 from the command line, "certified" in a batch
    V, F = _grid_with_a_flat_face()
    src = tmp_path / "in" / "part.obj"
    src.parent.mkdir()
    src.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in V.tolist())
                   + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F.tolist()))
    out, rep = tmp_path / "out.obj", tmp_path / "r.json"
    r = subprocess.run([sys.executable, "-m", "bd_uv", "unwrap", str(src), "-o", str(out),
                        "--report", str(rep)], capture_output=True, text=True, cwd=REPO)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "1 face(s) of zero area" in r.stdout and "error" not in r.stderr
    report = json.loads(rep.read_text())
    assert report["zero_area_faces"] == 1
    bound = max(e["bound_certified"] for e in report["islands"] if e["status"] == "certified")
    _check_filled(V, F, out, bound)
    r = subprocess.run([sys.executable, "-m", "bd_uv", "batch", str(src.parent), "-o",
                        str(tmp_path / "b"), "--jobs", "1"], capture_output=True, text=True,
                       cwd=REPO)
    assert r.returncode == 0, r.stdout + r.stderr
    [entry] = json.loads((tmp_path / "b" / "report.json").read_text())["items"]
    assert entry["status"] == "certified" and entry["zero_area_faces"] == 1
    assert any("zero area" in w for w in entry["warnings"])
    _check_filled(V, F, tmp_path / "b" / "part.obj", entry["bound_certified"])
