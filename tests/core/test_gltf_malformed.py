"""glTF documents with the wrong JSON shape where bd-uv reads them, and bufferViews that reach
past their buffer (unseen22: assimp's ``test/models/glTF2/wrongTypes/badArray.gltf`` ended in
``AttributeError: 'str' object has no attribute 'get'``; tinygltf's
``BoundsChecking/integer-out-of-bounds.gltf``, a bufferView of byteLength 1e300, was unwrapped
and written back with it, unreadable to other tools). Each is refused in the schema's words
naming the place: exit 2, one line, no traceback, the input untouched, nothing written."""
import hashlib
import json

import numpy as np
import pytest

from bd_uv.cli import main
from bd_uv.errors import SceneFileError
from bd_uv.scenes import read_scene
from gltf_build import Builder, seamed_grid


def _scene(tmp_path):
    b = Builder()
    V, F, _ = seamed_grid(3, 3)
    prim = {"attributes": {"POSITION": b.accessor(V.astype(np.float32), 5126, "VEC3",
                                                  minmax=True)},
            "indices": b.accessor(F.reshape(-1, 1), 5123, "SCALAR")}
    b.doc.update(meshes=[{"name": "Rock", "primitives": [prim]}],
                 nodes=[{"name": "Root", "children": [1]}, {"mesh": 0}],
                 scenes=[{"nodes": [0]}], scene=0)
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
    elif what == "view on a buffer that is not there":
        doc["bufferViews"][0]["buffer"] = 1


CASES = {
    "primitives an object": "meshes[0].primitives is an object, where glTF requires an array",
    "attributes an array": "meshes[0].primitives[0].attributes is an array, where glTF requires "
                           "an object",
    "children a number": "nodes[0].children is an integer, where glTF requires an array",
    "node mesh out of range": r"nodes[1].mesh is 3, but the document has 1 meshes (0..0)",
    "meshes an object": "meshes is an object, where glTF requires an array",
    "asset a string": "not a glTF 2.0 document (asset.version is not 2.x)",
    "image uri a number": "images[0].uri is an integer, where glTF requires a string",
    "byteLength 1e300": ".byteLength is a float, where glTF requires an integer",
    "view past its buffer": "reaches past the end of buffer 0",
    "view on a buffer that is not there": "bufferViews[0].buffer is 1, but the document has 1 "
                                          "buffers (0..0)",
}


@pytest.mark.parametrize("what", list(CASES))
def test_a_malformed_document_is_refused_naming_the_place(tmp_path, capsys, what):
    path, blob = _scene(tmp_path)
    doc = json.loads(path.read_text())
    _damage(doc, what, blob)
    path.write_text(json.dumps(doc))
    before = {p.name: hashlib.sha1(p.read_bytes()).hexdigest() for p in tmp_path.iterdir()}
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


def test_the_same_scene_undamaged_is_unwrapped(tmp_path):
    path, _ = _scene(tmp_path)
    out = tmp_path / "o.gltf"
    assert main(["unwrap", str(path), "-o", str(out), "-q"]) == 0
    scene = read_scene(str(out))
    cuv = scene.meshes[0].mesh.corner_uv
    assert cuv is not None and np.isfinite(cuv).all()
