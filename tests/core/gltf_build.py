"""Small glTF scenes built in the tests, and an accessor reader written apart from bd_uv's.

``skinned_scene`` holds, in one mesh instanced by two nodes: POSITION, NORMAL, TANGENT,
TEXCOORD_0 (split along a seam), TEXCOORD_1, COLOR_0 (normalised ubyte), JOINTS_0, WEIGHTS_0, a
custom ``_HEAT`` attribute, a morph target with a sparse POSITION accessor, a skin, a material
with a base colour texture and a normal map, an animation, extras and an unknown extension.
"""
import base64
import json
import os
import struct

import numpy as np

from helpers import grid

DT = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


class Builder:
    def __init__(self):
        self.blob = bytearray()
        # buffers after the blob's (index 1, 2, ...): e.g. a meshopt fallback buffer, no bytes
        self.extra_buffers = []
        self.doc = {"asset": {"version": "2.0", "generator": "bd-uv tests", "extras": {"k": 1}},
                    "buffers": [], "bufferViews": [], "accessors": []}

    def view(self, data):
        self.blob += b"\0" * ((-len(self.blob)) % 4)
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": len(self.blob),
                                        "byteLength": len(data)})
        self.blob += data
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, arr, ctype, atype, normalized=False, minmax=False):
        arr = np.ascontiguousarray(arr, dtype=DT[ctype]).reshape(len(arr), -1)
        acc = {"bufferView": self.view(arr.tobytes()), "componentType": ctype,
               "count": len(arr), "type": atype}
        if normalized:
            acc["normalized"] = True
        if minmax:
            acc["min"], acc["max"] = arr.min(0).tolist(), arr.max(0).tolist()
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def write(self, path, glb=False, data_uri=False):
        doc = json.loads(json.dumps(self.doc))
        blob = bytes(self.blob) + b"\0" * ((-len(self.blob)) % 4)
        if glb:
            doc["buffers"] = [{"byteLength": len(blob)}] + self.extra_buffers
            js = json.dumps(doc).encode()
            js += b" " * ((-len(js)) % 4)
            body = (struct.pack("<II", len(js), 0x4E4F534A) + js
                    + struct.pack("<II", len(blob), 0x004E4942) + blob)
            with open(path, "wb") as fh:
                fh.write(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)
            return
        if data_uri:
            uri = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
        else:
            uri = os.path.splitext(os.path.basename(path))[0] + " data.bin"
            with open(os.path.join(os.path.dirname(path), uri), "wb") as fh:
                fh.write(blob)
            uri = uri.replace(" ", "%20")
        doc["buffers"] = [{"uri": uri, "byteLength": len(blob)}] + self.extra_buffers
        with open(path, "w") as fh:
            json.dump(doc, fh)


def seamed_grid(nx=7, ny=6):
    """A curved grid whose vertices are split along its middle column (an old UV seam):
    (V (n,3), F (m,3), uv (n,2)) with the two halves' UVs apart."""
    V, F = grid(nx, ny, z=lambda x, y: 0.3 * (x - 0.5) ** 2 + 0.1 * y * x)
    mid = nx // 2
    col = np.arange(len(V)) % nx
    dup = np.flatnonzero(col == mid)
    right = (col[F] > mid).any(1)
    new = len(V) + np.arange(len(dup))
    remap = np.arange(len(V))
    remap[dup] = new
    F = F.copy()
    F[right] = remap[F[right]]
    V = np.concatenate([V, V[dup]])
    uv = V[:, :2].copy()
    uv[new, 0] += 0.25
    uv[(np.arange(len(V)) % nx > mid) & (np.arange(len(V)) < nx * ny), 0] += 0.25
    return V, F, uv


def skinned_scene():
    """Builder of the scene described in the module docstring, and its arrays by name."""
    b = Builder()
    V, F, uv = seamed_grid()
    n = len(V)
    rng = np.random.default_rng(7)
    arrays = {
        "POSITION": (V.astype(np.float32), 5126, "VEC3", False),
        "NORMAL": (np.tile([0, 0, 1.0], (n, 1)).astype(np.float32), 5126, "VEC3", False),
        "TANGENT": (np.tile([1.0, 0, 0, 1], (n, 1)).astype(np.float32), 5126, "VEC4", False),
        "TEXCOORD_0": (np.stack([uv[:, 0], 1 - uv[:, 1]], 1), 5126, "VEC2", False),
        "TEXCOORD_1": (rng.random((n, 2)), 5126, "VEC2", False),
        "COLOR_0": (rng.integers(0, 256, (n, 4)), 5121, "VEC4", True),
        "JOINTS_0": (np.tile([0, 1, 0, 0], (n, 1)) ^ (np.arange(n)[:, None] % 2
                                                         * [1, 1, 0, 0]), 5121, "VEC4", False),
        "WEIGHTS_0": (np.tile([0.75, 0.25, 0, 0], (n, 1)), 5126, "VEC4", False),
        "_HEAT": (rng.random((n, 1)), 5126, "SCALAR", False),
    }
    attrs = {k: b.accessor(a, c, t, nz, minmax=k == "POSITION")
             for k, (a, c, t, nz) in arrays.items()}
    idx = b.accessor(F.reshape(-1, 1), 5123, "SCALAR")
    # a sparse morph target: three vertices move up
    moved = np.array([1, 5, n - 1], dtype=np.uint16)
    delta = np.array([[0, 0, 0.1], [0, 0, 0.2], [0, 0, 0.3]], np.float32)
    sparse = {"count": 3, "indices": {"bufferView": b.view(moved.tobytes()),
                                      "componentType": 5123},
              "values": {"bufferView": b.view(delta.tobytes())}}
    b.doc["accessors"].append({"componentType": 5126, "count": n, "type": "VEC3",
                               "sparse": sparse, "min": [0, 0, 0], "max": [0, 0, 0.3]})
    morph = len(b.doc["accessors"]) - 1
    nrm_d = b.accessor(rng.random((n, 3)) * 0.01, 5126, "VEC3")
    ibm = b.accessor(np.tile(np.eye(4).ravel(), (2, 1)), 5126, "MAT4")
    times = b.accessor(np.array([[0.0], [1.0]]), 5126, "SCALAR", minmax=True)
    moves = b.accessor(np.array([[0, 0, 0], [0, 1, 0.0]]), 5126, "VEC3")
    d = b.doc
    d["extensionsUsed"] = ["EXT_bd_uv_test_unknown"]
    d["scene"] = 0
    d["scenes"] = [{"name": "Scene", "nodes": [0], "extras": {"s": [1, 2]}}]
    d["nodes"] = [
        {"name": "Root", "children": [1, 2, 3, 4], "rotation": [0, 0, 0.3826834, 0.9238795]},
        {"name": "Left", "mesh": 0, "skin": 0, "translation": [-2, 0, 0],
         "extras": {"tag": "left"}},
        {"name": "Right", "mesh": 0, "skin": 0, "scale": [1, 2, 1],
         "extensions": {"EXT_bd_uv_test_unknown": {"x": 1}}},
        {"name": "Bone0"}, {"name": "Bone1", "translation": [0, 1, 0]}]
    d["skins"] = [{"joints": [3, 4], "inverseBindMatrices": ibm}]
    d["meshes"] = [{"name": "Sheet", "weights": [0.5], "primitives": [{
        "attributes": attrs, "indices": idx, "material": 0,
        "targets": [{"POSITION": morph, "NORMAL": nrm_d}], "extras": {"p": 1}}]}]
    d["materials"] = [{"name": "Paint", "pbrMetallicRoughness": {
        "baseColorTexture": {"index": 0, "texCoord": 1}}, "normalTexture": {"index": 0}}]
    d["textures"] = [{"source": 0, "sampler": 0}]
    d["images"] = [{"uri": "tex%20ture.png"}]
    d["samplers"] = [{"magFilter": 9729, "wrapS": 33648}]
    d["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}]
    d["animations"] = [{"channels": [{"sampler": 0, "target": {"node": 4, "path": "translation"}}],
                        "samplers": [{"input": times, "output": moves}]}]
    return b, {k: v[0] for k, v in arrays.items()}


class Reader:
    """A glTF reader for the tests (plain JSON + numpy, no bd_uv code)."""

    def __init__(self, path):
        with open(path, "rb") as fh:
            raw = fh.read()
        folder = os.path.dirname(path)
        if raw[:4] == b"glTF":
            n = struct.unpack_from("<I", raw, 12)[0]
            self.doc = json.loads(raw[20:20 + n])
            bin_ = raw[20 + n + 8:]
        else:
            self.doc = json.loads(raw)
            bin_ = None
        self.buffers = []
        for buf in self.doc.get("buffers", []):
            uri = buf.get("uri")
            if uri is None:
                self.buffers.append(bin_)
            elif uri.startswith("data:"):
                self.buffers.append(base64.b64decode(uri.split(",", 1)[1]))
            else:
                with open(os.path.join(folder, uri.replace("%20", " ")), "rb") as fh:
                    self.buffers.append(fh.read())

    def accessor(self, i):
        acc = self.doc["accessors"][i]
        dt = np.dtype(DT[acc["componentType"]])
        w = WIDTH[acc["type"]]
        out = np.zeros((acc["count"], w), dt)
        if "bufferView" in acc:
            v = self.doc["bufferViews"][acc["bufferView"]]
            stride = v.get("byteStride", dt.itemsize * w)
            data = self.buffers[v["buffer"]]
            start = v.get("byteOffset", 0) + acc.get("byteOffset", 0)
            for r in range(acc["count"]):
                out[r] = np.frombuffer(data, dt, w, start + r * stride)
        if "sparse" in acc:
            s = acc["sparse"]
            iv = self.doc["bufferViews"][s["indices"]["bufferView"]]
            ids = np.frombuffer(self.buffers[iv["buffer"]], DT[s["indices"]["componentType"]],
                                s["count"], iv.get("byteOffset", 0))
            vv = self.doc["bufferViews"][s["values"]["bufferView"]]
            out[ids] = np.frombuffer(self.buffers[vv["buffer"]], dt, s["count"] * w,
                                     vv.get("byteOffset", 0)).reshape(-1, w)
        return out
