"""glTF scenes in and out whole: per corner every input value survives, the new UVs are certified
from the file as written, the input is untouched, bad files get errors naming the mesh."""
import hashlib
import json
import os
import shutil

import numpy as np
import pytest

from bd_uv.cli import main
from bd_uv.errors import SceneFileError
from bd_uv.scenes import read_scene
from gltf_build import Builder, Reader, seamed_grid, skinned_scene
from helpers import reference_distortion, relpath_across_drives
from overlap_shapes import overlapping_triangle_pairs

UNTOUCHED = ("asset", "scene", "scenes", "nodes", "skins", "materials", "textures", "samplers",
             "cameras", "animations", "extensionsUsed")


def _digest(folder):
    return {f: hashlib.sha256(open(os.path.join(folder, f), "rb").read()).hexdigest()
            for f in sorted(os.listdir(folder))}


def _corners(reader, prim, name):
    """Per face corner values of attribute ``name`` (or of a morph target dict entry)."""
    idx = reader.accessor(prim["indices"])[:, 0] if "indices" in prim else None
    acc = reader.accessor(prim["attributes"][name] if isinstance(name, str) else name[1])
    return acc if idx is None else acc[idx]


def _check_uvs(reader, prim, uv_key, report_mesh):
    """Certify the UVs as the file stores them, recomputed here: 0 flips, max <= the reported
    bound, no two triangles overlapping."""
    P = _corners(reader, prim, "POSITION").astype(np.float64).reshape(-1, 3, 3)
    uv = _corners(reader, prim, uv_key).astype(np.float64).reshape(-1, 3, 2)
    uv = np.stack([uv[..., 0], 1.0 - uv[..., 1]], -1)           # glTF's v runs downwards
    V, F = P.reshape(-1, 3), np.arange(3 * len(P)).reshape(-1, 3)
    D, flipped = reference_distortion(V, F, uv)
    assert not flipped.any()
    assert D.max() <= report_mesh["bound_certified"] * (1 + 1e-9)
    assert len(overlapping_triangle_pairs(uv)) == 0
    return D


@pytest.fixture
def scene(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    b, arrays = skinned_scene()
    (src / "tex ture.png").write_bytes(b"\x89PNG not really")
    b.write(str(src / "scene.gltf"))
    b.write(str(src / "scene.glb"), glb=True)
    b.write(str(src / "inline.gltf"), data_uri=True)
    return src, b, arrays


@pytest.mark.parametrize("name,out_name", [("scene.gltf", "o.gltf"), ("scene.glb", "o.glb"),
                                           ("inline.gltf", "o.gltf"), ("scene.glb", "o.gltf")])
def test_round_trip_keeps_every_value(scene, tmp_path, name, out_name):
    src, b, arrays = scene
    before = _digest(src)
    out = tmp_path / "elsewhere" / "deeper" / out_name
    rc = main(["unwrap", str(src / name), "-o", str(out), "--bound", "3",
               "--report", str(tmp_path / "r.json")])
    assert rc == 0
    assert _digest(src) == before                                  # the input is untouched
    report = json.loads((tmp_path / "r.json").read_text())
    (entry,) = report["meshes"]
    assert entry["name"] == "/Root/Left, /Root/Right"               # node paths, mesh once
    assert entry["nodes"] == ["/Root/Left", "/Root/Right"] and entry["mesh"] == "Sheet"
    assert any("TANGENT dropped" in w for w in entry["warnings"])

    r_in, r_out = Reader(str(src / name)), Reader(str(out))
    for key in UNTOUCHED:                                            # value for value
        assert r_out.doc[key] == r_in.doc[key], key
    # the image resolves from the output folder to the same file
    img = os.path.join(os.path.dirname(str(out)), r_out.doc["images"][0]["uri"].replace("%20", " "))
    assert os.path.samefile(img, src / "tex ture.png")
    # the skin's and the animation's accessors still hold their values
    for acc in (r_in.doc["skins"][0]["inverseBindMatrices"],
                r_in.doc["animations"][0]["samplers"][0]["output"]):
        assert np.array_equal(r_out.accessor(acc), r_in.accessor(acc))

    p_in, p_out = r_in.doc["meshes"][0]["primitives"][0], r_out.doc["meshes"][0]["primitives"][0]
    assert p_out["extras"] == p_in["extras"] and p_out["material"] == p_in["material"]
    assert r_out.doc["meshes"][0]["weights"] == [0.5]
    assert "TANGENT" not in p_out["attributes"]
    kept = set(p_in["attributes"]) - {"TEXCOORD_0", "TANGENT"}
    assert set(p_out["attributes"]) == kept | {"TEXCOORD_0"}
    for key in kept:                                                  # per corner, bit for bit
        a, c = _corners(r_in, p_in, key), _corners(r_out, p_out, key)
        assert a.dtype == c.dtype and np.array_equal(a, c), key
    assert np.array_equal(_corners(r_in, p_in, "COLOR_0"), arrays["COLOR_0"][
        r_in.accessor(p_in["indices"])[:, 0]])
    for t_in, t_out in zip(p_in["targets"], p_out["targets"]):       # morph deltas per corner
        assert set(t_in) == set(t_out)
        for key in t_in:
            assert np.array_equal(_corners(r_in, p_in, (key, t_in[key])),
                                  _corners(r_out, p_out, (key, t_out[key])))
    acc = r_out.doc["accessors"][p_out["attributes"]["POSITION"]]
    pos = r_out.accessor(p_out["attributes"]["POSITION"])
    assert acc["min"] == pos.min(0).tolist() and acc["max"] == pos.max(0).tolist()
    D = _check_uvs(r_out, p_out, "TEXCOORD_0", entry)
    assert len(D) == len(_corners(r_in, p_in, "POSITION")) // 3
    # the vertices are split only where the new UVs differ: one output vertex per (vertex, UV)
    idx = r_out.accessor(p_out["indices"])[:, 0]
    assert len(np.unique(idx)) == r_out.doc["accessors"][p_out["attributes"]["POSITION"]]["count"]


def test_lightmap_set_keeps_the_artists_uvs_and_tangents(scene, tmp_path):
    src, b, arrays = scene
    out = tmp_path / "o.glb"
    assert main(["unwrap", str(src / "scene.glb"), "-o", str(out), "--bound", "2",
                 "--uv-set", "1", "--report", str(tmp_path / "r.json")]) == 0
    (entry,) = json.loads((tmp_path / "r.json").read_text())["meshes"]
    r_in, r_out = Reader(str(src / "scene.glb")), Reader(str(out))
    p_in, p_out = r_in.doc["meshes"][0]["primitives"][0], r_out.doc["meshes"][0]["primitives"][0]
    for key in ("TEXCOORD_0", "TANGENT", "NORMAL", "_HEAT"):          # the normal map reads set 0
        assert np.array_equal(_corners(r_in, p_in, key), _corners(r_out, p_out, key)), key
    assert not _corners(r_in, p_in, "TEXCOORD_1").tolist() == _corners(r_out, p_out, "TEXCOORD_1").tolist()
    assert entry["warnings"] == []
    _check_uvs(r_out, p_out, "TEXCOORD_1", entry)


def test_lines_pass_through_and_seams_follow_the_files_uvs(tmp_path):
    b = Builder()
    V, F, uv = seamed_grid()
    pos = b.accessor(V.astype(np.float32), 5126, "VEC3", minmax=True)
    tri = {"attributes": {"POSITION": pos, "TEXCOORD_0": b.accessor(uv, 5126, "VEC2")},
           "indices": b.accessor(F.reshape(-1, 1), 5125, "SCALAR")}
    lines = {"attributes": {"POSITION": pos}, "mode": 1,
             "indices": b.accessor(np.array([[0], [1], [1], [2]]), 5123, "SCALAR")}
    b.doc["meshes"] = [{"primitives": [tri, lines]}]
    b.doc["nodes"] = [{"mesh": 0}]
    b.write(str(tmp_path / "a.gltf"))
    (sm,) = read_scene(str(tmp_path / "a.gltf")).meshes
    assert len(sm.mesh.uv_seams()) == 5                  # the old seam, on the welded mesh
    assert len(sm.mesh.V) == len(np.unique(V, axis=0))
    assert main(["unwrap", str(tmp_path / "a.gltf"), "-o", str(tmp_path / "b.gltf")]) == 0
    r = Reader(str(tmp_path / "b.gltf"))
    assert r.doc["meshes"][0]["primitives"][1] == lines
    assert r.doc["meshes"][0]["primitives"][0]["indices"] != tri["indices"]


def test_a_file_of_points_and_lines_says_what_it_holds(tmp_path, capsys):
    # glTF-Asset-Generator's Mesh_PrimitiveMode_00-03 and 07-10: no faces to unwrap, and the
    # error names what the primitives draw instead
    b = Builder()
    V, _, _ = seamed_grid()
    pos = b.accessor(V.astype(np.float32), 5126, "VEC3", minmax=True)
    b.doc["meshes"] = [{"primitives": [{"attributes": {"POSITION": pos}, "mode": 0},
                                       {"attributes": {"POSITION": pos}, "mode": 3},
                                       {"attributes": {"POSITION": pos}, "mode": 0}]}]
    b.doc["nodes"] = [{"mesh": 0}]
    b.write(str(tmp_path / "p.gltf"))
    before = (tmp_path / "p.gltf").read_bytes()
    assert main(["unwrap", str(tmp_path / "p.gltf"), "-o", str(tmp_path / "q.gltf")]) == 2
    err = capsys.readouterr().err
    assert "holds no triangle or polygon mesh" in err
    assert "3 primitive(s) draw points or lines" in err
    assert "points: 2, line strip: 1" in err
    assert not (tmp_path / "q.gltf").exists()
    assert (tmp_path / "p.gltf").read_bytes() == before


def _one_mesh(tmp_path, name="bad.gltf", **prim_extra):
    b = Builder()
    V, F, _ = seamed_grid()
    prim = {"attributes": {"POSITION": b.accessor(V.astype(np.float32), 5126, "VEC3",
                                                   minmax=True)},
            "indices": b.accessor(F.reshape(-1, 1), 5123, "SCALAR"), **prim_extra}
    b.doc["meshes"] = [{"name": "Rock", "primitives": [prim]}]
    b.doc["nodes"] = [{"name": "RockNode", "mesh": 0}]
    return b, prim


def test_draco_primitive_is_refused_by_name(tmp_path, capsys):
    b, _ = _one_mesh(tmp_path, extensions={"KHR_draco_mesh_compression": {"bufferView": 0}})
    b.write(str(tmp_path / "d.gltf"))
    assert main(["unwrap", str(tmp_path / "d.gltf"), "-o", str(tmp_path / "o.gltf")]) == 1
    err = capsys.readouterr().err
    assert "RockNode" in err and "'Rock'" in err and "Draco" in err
    assert not (tmp_path / "o.gltf").exists()   # no mesh certified: nothing written at -o


def test_meshopt_fallback_buffer_without_bytes_is_refused_by_name(tmp_path, capsys):
    # EXT_meshopt_compression's fallback buffer has no uri and no bytes by design (gltf-transform
    # writes BoxMeshopt.gltf so): the file is read, and the primitive is refused in the user's
    # terms, not as "buffer 1 has no uri".
    b, prim = _one_mesh(tmp_path)
    b.write(str(tmp_path / "m.gltf"))
    doc = json.loads((tmp_path / "m.gltf").read_text())
    view = doc["accessors"][prim["indices"]]["bufferView"]
    length = doc["bufferViews"][view]["byteLength"]
    doc["buffers"].append({"byteLength": length,
                           "extensions": {"EXT_meshopt_compression": {"fallback": True}}})
    doc["bufferViews"][view].update(buffer=len(doc["buffers"]) - 1, byteOffset=0, extensions={
        "EXT_meshopt_compression": {"buffer": 0, "byteOffset": 0, "byteLength": 4,
                                    "mode": "TRIANGLES", "byteStride": 2, "count": 3}})
    doc["extensionsUsed"] = doc["extensionsRequired"] = ["EXT_meshopt_compression"]
    (tmp_path / "m.gltf").write_text(json.dumps(doc))
    before = (tmp_path / "m.gltf").read_bytes()
    assert main(["unwrap", str(tmp_path / "m.gltf"), "-o", str(tmp_path / "o.gltf")]) == 1
    err = capsys.readouterr().err
    assert "RockNode" in err and "'Rock'" in err and "meshopt" in err and "no uri" not in err
    assert not (tmp_path / "o.gltf").exists()
    assert (tmp_path / "m.gltf").read_bytes() == before


@pytest.mark.parametrize("breakage,words", [
    (lambda d: d["accessors"][1].update(count=10**6),
     ["'Rock'", "node /RockNode", "primitive 0", "indices"]),
    (lambda d: d["meshes"][0]["primitives"][0]["attributes"].update(POSITION=99),
     ["'Rock'", "node /RockNode", "primitive 0", "accessor 99"]),
    # a corrupted count on a zero-filled accessor: named, not allocated (12 TB: a traceback of
    # numpy's MemoryError before; a count of a few GB would have filled the memory)
    (lambda d: (d["accessors"][0].pop("bufferView"), d["accessors"][0].update(count=10**12)),
     ["'Rock'", "node /RockNode", "primitive 0", "accessor 0", "no bufferView"]),
])
def test_malformed_file_names_the_mesh(tmp_path, capsys, breakage, words):
    """A malformed mesh is refused by name (exit 1, as a Draco one); being the only mesh,
    nothing is written."""
    b, _ = _one_mesh(tmp_path)
    breakage(b.doc)
    b.write(str(tmp_path / "bad.gltf"))
    before = _digest(tmp_path)
    assert main(["unwrap", str(tmp_path / "bad.gltf"), "-o", str(tmp_path / "o.gltf")]) == 1
    err = capsys.readouterr().err
    assert all(w in err for w in words), err
    assert "Traceback" not in err
    assert _digest(tmp_path) == before                            # nothing written
    scene = read_scene(str(tmp_path / "bad.gltf"))
    assert [m.mesh for m in scene.meshes] == [None] and "primitive 0" in scene.meshes[0].refused


@pytest.mark.parametrize("breakage", ["indices count", "position accessor"])
def test_a_malformed_mesh_leaves_the_others_unwrapped(tmp_path, capsys, breakage):
    """A production scene with one broken mesh is not refused whole: the broken one is named
    and kept as read (its primitive's JSON unchanged in the output), the good one is certified
    and written (exit 1: not every mesh certified)."""
    b = Builder()
    V, F, _ = seamed_grid()
    prims = [{"attributes": {"POSITION": b.accessor(V.astype(np.float32), 5126, "VEC3",
                                                    minmax=True)},
              "indices": b.accessor(F.reshape(-1, 1), 5123, "SCALAR")} for _ in range(2)]
    b.doc["meshes"] = [{"name": "Rock", "primitives": [prims[0]]},
                       {"name": "Moss", "primitives": [prims[1]]}]
    b.doc["nodes"] = [{"name": "RockNode", "mesh": 0}, {"name": "MossNode", "mesh": 1}]
    b.doc.update(scenes=[{"nodes": [0, 1]}], scene=0)
    if breakage == "indices count":
        b.doc["accessors"][prims[1]["indices"]]["count"] = 10 ** 6
    else:
        prims[1]["attributes"]["POSITION"] = 99
    b.write(str(tmp_path / "two.gltf"))
    doc_in = json.loads((tmp_path / "two.gltf").read_text())
    out, rep = tmp_path / "o.gltf", tmp_path / "r.json"
    assert main(["unwrap", str(tmp_path / "two.gltf"), "-o", str(out), "--report",
                 str(rep)]) == 1
    err = capsys.readouterr().err
    assert "MossNode" in err and "'Moss'" in err and "Traceback" not in err
    assert "RockNode" not in err
    entries = {e["name"]: e for e in json.loads(rep.read_text())["meshes"]}
    assert entries["/MossNode"]["status"] == "failed"
    assert entries["/MossNode"]["error"] == "SceneFileError"
    assert entries["/RockNode"]["status"] == "certified"
    doc_out = json.loads(out.read_text())
    assert doc_out["meshes"][1] == doc_in["meshes"][1]            # the broken mesh as read
    assert doc_out["meshes"][0] != doc_in["meshes"][0]            # the good one has new UVs
    reader = Reader(str(out))
    _check_uvs(reader, doc_out["meshes"][0]["primitives"][0], "TEXCOORD_0", entries["/RockNode"])


def test_not_gltf_and_blender_only_formats(tmp_path, capsys):
    (tmp_path / "x.glb").write_bytes(b"glTF\x01\x00\x00\x00")
    assert main(["unwrap", str(tmp_path / "x.glb"), "-o", str(tmp_path / "y.glb")]) == 2
    assert "not a glTF 2.0 file" in capsys.readouterr().err
    (tmp_path / "a.fbx").write_bytes(b"")
    assert main(["unwrap", str(tmp_path / "a.fbx"), "-o", str(tmp_path / "b.fbx")]) == 2
    assert "blender -b --python scripts/bd_uv_batch.py" in capsys.readouterr().err


def test_a_missing_usd_extra_is_one_line_naming_it(tmp_path, monkeypatch, capsys):
    import sys
    monkeypatch.setitem(sys.modules, "pxr", None)          # as if usd-core were not installed
    (tmp_path / "a.usda").write_text("#usda 1.0\n")
    assert main(["unwrap", str(tmp_path / "a.usda"), "-o", str(tmp_path / "b.usda")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pip install 'bd-uv[usd]'" in err[0]


def test_core_imports_no_format_package(tmp_path):
    import subprocess
    import sys
    code = ("import sys, bd_uv, bd_uv.cli, bd_uv.scenes, bd_uv.scenes.gltf; "
            "print(sorted(m for m in ('pxr', 'bpy', 'pygltflib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=os.path.dirname(os.path.dirname(os.path.dirname(__file__))))
    assert out.stdout.strip() == "[]", out.stderr


def test_weld_joins_split_vertices_but_not_point_contacts():
    from bd_uv.mesh.weld import welded
    # two triangles sharing an edge, its vertices split (as an exporter does at a UV seam) ...
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.]])
    F = np.array([[0, 1, 2], [3, 5, 4]])
    W, G = welded(V, F)
    assert len(W) == 4 and G[0, 1] == G[1, 0] and G[0, 2] == G[1, 2]
    assert np.array_equal(W[G], V[F])                     # every corner keeps its position
    # ... and a third triangle touching the first only at a point stays apart there
    V2 = np.vstack([V, [[-1, 0, 0], [0, -1, 0]]])
    F2 = np.vstack([F, [[0, 6, 7]]])
    W2, G2 = welded(V2, F2)
    assert G2[2, 0] != G2[0, 0] and np.array_equal(W2[G2], V2[F2])
    assert len(W2) == 4 + 3


def test_never_overwrites_a_file_the_input_uses(scene, tmp_path, capsys):
    src, _, _ = scene
    out = tmp_path / "out"
    assert main(["unwrap", str(src / "scene.glb"), "-o", str(out / "o.gltf")]) == 0
    assert sorted(os.listdir(out)) == ["o.bd-uv-0.bin", "o.bd-uv.bin", "o.gltf"]
    shutil.copy(out / "o.gltf", out / "p.gltf")             # p.gltf uses o's .bin files
    before = _digest(out)
    assert main(["unwrap", str(out / "p.gltf"), "-o", str(out / "o.gltf")]) == 2
    assert "o.bd-uv.bin would overwrite a file" in capsys.readouterr().err
    assert _digest(out) == before


def test_scene_options_are_never_ignored(scene, tmp_path, capsys):
    src, _, _ = scene
    obj = tmp_path / "a.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    assert main(["unwrap", str(obj), "-o", str(tmp_path / "b.obj"), "--uv-set", "1"]) == 2
    assert "--uv-set applies to glTF" in capsys.readouterr().err
    assert main(["unwrap", str(src / "scene.glb"), "-o", str(tmp_path / "b.glb"),
                 "--uv-name", "uv2"]) == 2
    assert "--uv-name applies to USD" in capsys.readouterr().err
    assert main(["batch", str(obj), "-o", str(tmp_path / "out"), "--uv-set", "2"]) == 2
    assert not (tmp_path / "b.glb").exists()


def test_primitives_sharing_accessors_unwrap_as_one_mesh(tmp_path):
    """Two materials' primitives over one POSITION accessor: one welded surface, one chart
    across both, each primitive rewritten on its own, every corner's position kept."""
    b = Builder()
    V, F, _ = seamed_grid()
    pos = b.accessor(V.astype(np.float32), 5126, "VEC3", minmax=True)
    half = len(F) // 2
    prims = [{"attributes": {"POSITION": pos}, "material": k,
              "indices": b.accessor(part.reshape(-1, 1), 5123, "SCALAR")}
             for k, part in enumerate((F[:half], F[half:]))]
    b.doc["meshes"] = [{"name": "Two", "primitives": prims}]
    b.doc["nodes"] = [{"name": "N", "mesh": 0}]
    b.doc["materials"] = [{"name": "a"}, {"name": "b"}]
    b.write(str(tmp_path / "two.gltf"))
    assert main(["unwrap", str(tmp_path / "two.gltf"), "-o", str(tmp_path / "o.glb"),
                 "--seams", "none", "--report", str(tmp_path / "r.json")]) == 0
    (entry,) = json.loads((tmp_path / "r.json").read_text())["meshes"]
    r_in, r_out = Reader(str(tmp_path / "two.gltf")), Reader(str(tmp_path / "o.glb"))
    p_out = r_out.doc["meshes"][0]["primitives"]
    assert p_out[0]["attributes"]["POSITION"] != p_out[1]["attributes"]["POSITION"]
    P, U = [], []
    for p_i, p_o in zip(r_in.doc["meshes"][0]["primitives"], p_out):
        assert np.array_equal(_corners(r_in, p_i, "POSITION"), _corners(r_out, p_o, "POSITION"))
        P.append(_corners(r_out, p_o, "POSITION").astype(float))
        U.append(_corners(r_out, p_o, "TEXCOORD_0").astype(float))
    assert len(entry["islands"]) == 1          # welded (the split column too): one chart
    P, U = np.concatenate(P).reshape(-1, 3, 3), np.concatenate(U).reshape(-1, 3, 2)
    U[..., 1] = 1 - U[..., 1]
    D, flipped = reference_distortion(P.reshape(-1, 3), np.arange(3 * len(P)).reshape(-1, 3), U)
    assert not flipped.any() and D.max() <= entry["bound_certified"] * (1 + 1e-9)
    assert len(overlapping_triangle_pairs(U)) == 0


@pytest.mark.parametrize("damage", ["padding", "alphabet", "uri not text"])
def test_a_damaged_data_uri_is_a_scene_error(tmp_path, capsys, damage):
    """Issue 22 (scene contract, seed 7): a .gltf whose buffer is a base64 data URI with one
    byte changed ended in binascii.Error out of read_scene ("Incorrect padding"); a character
    outside base64 was dropped silently (the buffer decoded to other bytes). Now a
    SceneFileError naming the buffer, exit 2, the file untouched, nothing written."""
    b = Builder()
    V, F, _ = seamed_grid(3, 3)
    prim = {"attributes": {"POSITION": b.accessor(V.astype(np.float32), 5126, "VEC3",
                                                  minmax=True)},
            "indices": b.accessor(F.reshape(-1, 1), 5123, "SCALAR")}
    b.doc.update(meshes=[{"name": "Rock", "primitives": [prim]}], nodes=[{"mesh": 0}],
                 scenes=[{"nodes": [0]}], scene=0)
    path = tmp_path / "scene.gltf"
    b.write(str(path), data_uri=True)
    doc = json.loads(path.read_text())
    uri = doc["buffers"][0]["uri"]
    doc["buffers"][0]["uri"] = {"padding": uri[:-1], "alphabet": uri[:-8] + "*" + uri[-7:],
                                "uri not text": 5}[damage]
    path.write_text(json.dumps(doc))
    raw = path.read_bytes()
    with pytest.raises(SceneFileError, match="buffer 0"):
        read_scene(str(path))
    assert main(["unwrap", str(path), "-o", str(tmp_path / "o.gltf")]) == 2
    err = capsys.readouterr().err
    assert "buffer 0" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert path.read_bytes() == raw and not (tmp_path / "o.gltf").exists()


def test_equal_meshes_are_unwrapped_once_and_each_certified_as_written(tmp_path):
    """A scene exported with every copy of a part as its own mesh (glTF-Transform's
    many-cubes.gltf: 501 equal meshes took 234 s) solves each distinct mesh once: the copy's
    entry says ``same_as``, its written UVs are the first's, and each is certified from the
    file as written, recomputed here."""
    b = Builder()
    meshes = []
    for name, (nx, ny) in (("Rock", (7, 6)), ("RockCopy", (7, 6)), ("Moss", (5, 4))):
        V, F, _ = seamed_grid(nx, ny)
        prim = {"attributes": {"POSITION": b.accessor(V.astype(np.float32), 5126, "VEC3",
                                                      minmax=True)},
                "indices": b.accessor(F.reshape(-1, 1), 5123, "SCALAR")}
        meshes.append({"name": name, "primitives": [prim]})
    b.doc["meshes"] = meshes
    b.doc["nodes"] = [{"name": f"{m['name']}Node", "mesh": i} for i, m in enumerate(meshes)]
    b.doc.update(scenes=[{"nodes": [0, 1, 2]}], scene=0)
    b.write(str(tmp_path / "s.gltf"))
    out, rep = tmp_path / "o.gltf", tmp_path / "r.json"
    assert main(["unwrap", str(tmp_path / "s.gltf"), "-o", str(out), "--report", str(rep)]) == 0
    entries = json.loads(rep.read_text())["meshes"]
    assert [e["name"] for e in entries] == ["/RockNode", "/RockCopyNode", "/MossNode"]
    assert "same_as" not in entries[0] and "same_as" not in entries[2]
    assert entries[1]["same_as"] == "/RockNode"
    assert all(e["status"] == "certified" and e["output"] for e in entries)
    reader = Reader(str(out))
    doc = json.loads(out.read_text())
    uvs = [_corners(reader, m["primitives"][0], "TEXCOORD_0") for m in doc["meshes"]]
    assert np.array_equal(uvs[0], uvs[1]) and len(uvs[2]) != len(uvs[0])
    for m, e in zip(doc["meshes"], entries):
        _check_uvs(reader, m["primitives"][0], "TEXCOORD_0", e)


def test_a_file_on_another_drive_is_named_and_nothing_written(scene, tmp_path, monkeypatch,
                                                                capsys):
    # Windows: os.path.relpath raises ValueError across drives (C: to D:), and a glTF can only
    # refer to its image by a relative URI: a clear error, no traceback, no output written
    src, b, arrays = scene
    monkeypatch.setattr(os.path, "relpath", relpath_across_drives("tex ture.png"))
    out = tmp_path / "other" / "o.gltf"
    rc = main(["unwrap", str(src / "scene.gltf"), "-o", str(out)])
    err = capsys.readouterr().err
    assert rc != 0 and "Traceback" not in err
    assert "'tex%20ture.png'" in err or "'tex ture.png'" in err
    assert "another drive" in err and not out.exists()
