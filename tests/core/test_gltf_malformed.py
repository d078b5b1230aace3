"""glTF documents with the wrong JSON shape where bd-uv reads them, and bufferViews that reach
past their buffer (unseen22: assimp's ``test/models/glTF2/wrongTypes/badArray.gltf`` ended in
``AttributeError: 'str' object has no attribute 'get'``; tinygltf's
``BoundsChecking/integer-out-of-bounds.gltf``, a bufferView of byteLength 1e300, was unwrapped
and written back with it, unreadable to other tools). Each is refused in the schema's words
naming the place: exit 2, one line, no traceback, the input untouched, nothing written. A
bufferView that cannot be read refuses only the meshes reading it; the file's other meshes are
unwrapped and written (assimp's ``IncorrectVertexArrays/Cube.gltf``: 2 of its 4 meshes). That
holds for the accessors only the writer reads (other attributes, morph targets): on main they
stopped the whole write after the unwrap."""
import hashlib
import json

import numpy as np
import pytest

from bd_uv.cli import main
from bd_uv.errors import SceneFileError
from bd_uv.scenes import read_scene
from gltf_build import Builder, seamed_grid
from helpers import grid


def _scene(tmp_path):
    """Two meshes on one buffer: Rock (a seamed grid) under a parent node, and Leaf (a grid)."""
    b = Builder()
    meshes = []
    for name, (V, F) in (("Rock", seamed_grid(3, 3)[:2]), ("Leaf", grid(3, 4))):
        prim = {"attributes": {"POSITION": b.accessor(V.astype(np.float32), 5126, "VEC3",
                                                      minmax=True)},
                "indices": b.accessor(F.reshape(-1, 1), 5123, "SCALAR")}
        if name == "Rock":   # attributes the writer copies per split vertex, never unwrapped
            up = np.tile(np.float32([0, 0, 1]), (len(V), 1))
            prim["attributes"]["NORMAL"] = b.accessor(up, 5126, "VEC3")
            prim["targets"] = [{"POSITION": b.accessor(0.1 * up, 5126, "VEC3", minmax=True)}]
        meshes.append({"name": name, "primitives": [prim]})
    b.doc.update(meshes=meshes, nodes=[{"name": "Root", "children": [1]}, {"mesh": 0},
                                       {"mesh": 1}], scenes=[{"nodes": [0, 2]}], scene=0)
    path = tmp_path / "scene.gltf"
    b.write(str(path))
    return path, len(b.blob)


def _damage(doc, what, blob):
    prim = doc["meshes"][0]["primitives"][0]
    if what == "primitives an object":           # assimp wrongTypes/badArray.gltf
        doc["meshes"][0]["primitives"] = {"not an array": prim["attributes"]}
    elif what == "attributes an array":
        prim["attributes"] = [prim["attributes"]["POSITION"]]
    elif what == "children a number":
        doc["nodes"][0]["children"] = 1
    elif what == "node mesh out of range":
        doc["nodes"][1]["mesh"] = 3
    elif what == "meshes an object":
        doc["meshes"] = {"0": doc["meshes"][0]}
    elif what == "asset a string":
        doc["asset"] = "2.0"
    elif what == "image uri a number":
        doc["images"] = [{"uri": 7}]
    elif what == "byteLength 1e300":              # tinygltf integer-out-of-bounds.gltf
        doc["bufferViews"][prim["indices"]]["byteLength"] = 1e300
    elif what == "view past its buffer":
        doc["bufferViews"][prim["indices"]]["byteLength"] = blob + 4
    elif what == "morph target's view past its buffer":   # read only when written
        doc["bufferViews"][doc["accessors"][prim["targets"][0]["POSITION"]]["bufferView"]][
            "byteLength"] = blob + 4
    elif what == "more normals than their view holds":
        doc["accessors"][prim["attributes"]["NORMAL"]]["count"] = 1000
    elif what == "view on a buffer that is not there":
        doc["bufferViews"][prim["attributes"]["POSITION"]]["buffer"] = 1


CASES = {
    "primitives an object": "meshes[0].primitives is an object, where glTF requires an array",
    "attributes an array": "meshes[0].primitives[0].attributes is an array, where glTF requires "
                           "an object",
    "children a number": "nodes[0].children is an integer, where glTF requires an array",
    "node mesh out of range": "nodes[1].mesh is 3, but the document has 2 meshes (0..1)",
    "meshes an object": "meshes is an object, where glTF requires an array",
    "asset a string": "not a glTF 2.0 document (asset.version is not 2.x)",
    "image uri a number": "images[0].uri is an integer, where glTF requires a string",
}
VIEW_CASES = {
    "byteLength 1e300": "its byteLength is 1e+300, where glTF requires a whole number",
    "view past its buffer": "reaches past the end of buffer 0",
    "view on a buffer that is not there": "buffer 1 does not exist (1 buffers)",
    "morph target's view past its buffer": "primitive 0 target 0 POSITION: accessor 3 cannot be "
                                           "read (ValueError: bufferView 3 reaches past the end "
                                           "of buffer 0",
    "more normals than their view holds": "primitive 0 NORMAL: accessor 2 cannot be read "
                                          "(ValueError: bufferView 2 is too short for 1000 "
                                          "elements)",
}


def _damaged(tmp_path, what):
    """The scene written with damage ``what``: (its path, each file's sha1 before a run)."""
    path, blob = _scene(tmp_path)
    doc = json.loads(path.read_text())
    _damage(doc, what, blob)
    path.write_text(json.dumps(doc))
    return path, {p.name: hashlib.sha1(p.read_bytes()).hexdigest() for p in tmp_path.iterdir()}


@pytest.mark.parametrize("what", list(CASES))
def test_a_malformed_document_is_refused_naming_the_place(tmp_path, capsys, what):
    path, before = _damaged(tmp_path, what)
    with pytest.raises(SceneFileError) as err:
        read_scene(str(path))
    assert CASES[what] in str(err.value) and str(err.value).startswith(str(path))
    out = tmp_path / "out" / "o.gltf"
    out.parent.mkdir()
    capsys.readouterr()
    assert main(["unwrap", str(path), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert CASES[what] in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert list(out.parent.iterdir()) == []
    assert before == {p.name: hashlib.sha1(p.read_bytes()).hexdigest()
                      for p in tmp_path.iterdir() if p.is_file()}


@pytest.mark.parametrize("what", list(VIEW_CASES))
def test_a_view_that_cannot_be_read_refuses_only_the_meshes_reading_it(tmp_path, capsys, what):
    path, before = _damaged(tmp_path, what)
    scene = read_scene(str(path))
    assert VIEW_CASES[what] in scene.meshes[0].refused
    assert scene.meshes[0].refused.startswith("mesh 0 'Rock'")
    assert scene.meshes[1].refused is None
    out = tmp_path / "out" / "o.gltf"
    out.parent.mkdir()
    capsys.readouterr()
    assert main(["unwrap", str(path), "-o", str(out)]) == 1      # one mesh of two refused
    captured = capsys.readouterr()
    assert VIEW_CASES[what] in captured.out + captured.err
    assert "Traceback" not in captured.err
    assert before == {p.name: hashlib.sha1(p.read_bytes()).hexdigest()
                      for p in tmp_path.iterdir() if p.is_file()}
    written = json.loads(out.read_text())
    # Rock is kept as read (its damaged view too: it is the file's, not bd-uv's); Leaf has UVs
    doc = json.loads(path.read_text())
    assert written["meshes"][0]["primitives"] == doc["meshes"][0]["primitives"]
    assert "TEXCOORD_0" in written["meshes"][1]["primitives"][0]["attributes"]
    leaf = [m for m in read_scene(str(out)).meshes if m.info["mesh_index"] == 1][0]
    assert leaf.mesh.corner_uv is not None and np.isfinite(leaf.mesh.corner_uv).all()


def test_the_same_scene_undamaged_is_unwrapped(tmp_path):
    path, _ = _scene(tmp_path)
    out = tmp_path / "o.gltf"
    assert main(["unwrap", str(path), "-o", str(out), "-q"]) == 0
    for m in read_scene(str(out)).meshes:
        assert m.mesh.corner_uv is not None and np.isfinite(m.mesh.corner_uv).all()
