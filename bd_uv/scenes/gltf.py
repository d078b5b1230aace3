"""glTF 2.0 scenes: every triangle primitive unwrapped once per mesh, the document patched.

Reading: each mesh's triangle primitives (lists, strips and fans: modes 4, 5, 6) become one
unwrap problem in the mesh's own space (a mesh used by several nodes is unwrapped once); their
positions are welded by exact value, so the file's vertex splits (hard normals, old seams) do not
cut the surface (parts that only touch at a point stay apart: ``weld.py``); the UVs already in
the file (the set written, else ``TEXCOORD_0``) give the seams, as an OBJ's ``vt`` do. Lines and
points pass through unchanged; a strip or fan given new UVs is written as the triangle list it
draws (mode 4: its split vertices no longer follow one another).

Writing: a glTF vertex carries one UV, so a vertex is split wherever the new UVs differ; every
attribute of the primitive (POSITION, NORMAL, COLOR_n, JOINTS_n/WEIGHTS_n, other TEXCOORD_n,
custom ``_NAME``) and every morph target's deltas are copied for each split vertex, value for
value in their own component type. The new UVs go to ``TEXCOORD_<uv_set>`` as float32 with v
running downwards (``v_gltf = 1 - v``). Tangents that a normal map reads through the rewritten
set are dropped with a warning (a viewer then derives MikkTSpace tangents, as glTF specifies).
New accessors are appended; everything else in the document is kept as read.
"""
import os
from urllib.parse import quote, unquote

import numpy as np

from ..certificate import certify_islands
from ..errors import SceneFileError
from ..scheduling.atomic import atomic_path
from .model import SceneMesh
from .gltf_io import BufferWriter, read_gltf, rebase_uris, write_glb, write_gltf_json
from .gltf_mesh import _copies_readable, _mesh_arrays, _refusal
from .gltf_patch import _patch_primitive

TRIANGLES = 4
SURFACE_MODES = (TRIANGLES, 5, 6)   # triangle lists, strips and fans
MODE_NAMES = {0: "points", 1: "lines", 2: "line loop", 3: "line strip"}


def _holds_instead(doc):
    """What a glTF document without a triangle primitive holds instead, for its error message
    ("" when it has no mesh at all)."""
    modes = [p.get("mode", TRIANGLES) for m in doc.get("meshes", [])
             for p in m.get("primitives", [])]
    if not modes:
        return ""
    said = ", ".join(f"{MODE_NAMES.get(k, f'mode {k}')}: {modes.count(k)}"
                     for k in sorted(set(modes)))
    return (f"its {len(modes)} primitive(s) draw points or lines, not faces ({said}); only "
            "triangles, triangle strips and triangle fans (modes 4, 5, 6) can be unwrapped")


def node_paths(doc):
    """{mesh index: ["/parent/child", ...]} for every node that instances a mesh."""
    nodes = doc.get("nodes", [])
    parent = {}
    for i, n in enumerate(nodes):
        for c in n.get("children", []):
            parent[c] = i
    out = {}
    for i, n in enumerate(nodes):
        if "mesh" not in n:
            continue
        names, j, seen = [], i, set()
        while j is not None and j not in seen:
            seen.add(j)
            names.append(nodes[j].get("name") or f"node{j}")
            j = parent.get(j)
        out.setdefault(n["mesh"], []).append("/" + "/".join(reversed(names)))
    return out


class GltfScene:
    """A glTF file read for unwrapping; ``meshes`` one :class:`SceneMesh` per glTF mesh with
    triangles."""

    # its v runs downwards: the UVs stored are 1 - v (``layout.as_stored`` certifies them so)
    V_DOWN = True

    def __init__(self, gf, uv_set, meshes, parts):
        self.gf, self.uv_set, self.meshes, self._parts = gf, uv_set, meshes, parts

    @classmethod
    def read(cls, path, uv_set=0):
        gf = read_gltf(path)
        doc = gf.doc
        paths = node_paths(doc)
        meshes, parts = [], []
        for mi, mesh in enumerate(doc.get("meshes", [])):
            label = f"mesh {mi}" + (f" {mesh['name']!r}" if mesh.get("name") else "") + (
                f" (node {', '.join(paths[mi])})" if paths.get(mi) else "")
            prims = [(j, p) for j, p in enumerate(mesh.get("primitives", []))
                     if p.get("mode", TRIANGLES) in SURFACE_MODES]
            warnings = [f"{label}: primitive {j} (mode {p['mode']}) is not a triangle list; "
                        "left as it is" for j, p in enumerate(mesh.get("primitives", []))
                        if p.get("mode", TRIANGLES) not in SURFACE_MODES + (0, 1, 2, 3)]
            if not prims:
                continue
            names = paths.get(mi) or [label]
            info = {"mesh": mesh.get("name"), "mesh_index": mi, "nodes": paths.get(mi, []),
                    "primitives": [j for j, _ in prims]}
            try:   # a malformed mesh is refused by name, the file's other meshes unwrapped
                refused = _refusal(gf, label, prims)
                if not refused:
                    m, part = _mesh_arrays(gf, label, prims, uv_set, names[0])
                    _copies_readable(gf, label, prims)
            except SceneFileError as exc:
                refused = str(exc).removeprefix(f"{gf.path}: ")   # the entry names the file
            if refused:
                meshes.append(SceneMesh(", ".join(names), None, info, refused, None, warnings))
                parts.append(None)
                continue
            meshes.append(SceneMesh(", ".join(names), m, info, None, None, warnings))
            parts.append(part)
        scene = cls(gf, uv_set, meshes, parts)
        scene.holds = "" if meshes else _holds_instead(doc)
        return scene

    def write(self, path, charts):
        """Patch the document with ``charts`` ({mesh position in ``meshes``: Charts}) and write
        it to ``path`` (``.gltf`` or ``.glb``); meshes not in ``charts`` stay as read.

        Returns
        -------
        dict {mesh position: (list of Certificate of the UVs as stored, list of warnings)}
        """
        gf, doc = self.gf, self.gf.doc
        out_dir = os.path.dirname(os.path.abspath(path))
        inputs = input_files(doc, gf.path)
        rebase_uris(doc, os.path.dirname(os.path.abspath(gf.path)), out_dir)
        glb_out = path.lower().endswith(".glb")
        buffers = doc.setdefault("buffers", [])
        stem = os.path.splitext(os.path.basename(path))[0]
        extra_files = {}
        if glb_out:
            if not buffers or "uri" in buffers[0]:   # the GLB-stored buffer must come first
                buffers.insert(0, {"byteLength": 0})
                gf.buffers.insert(0, b"")
                for v in doc.get("bufferViews", []):
                    v["buffer"] += 1
            writer = BufferWriter(doc, 0, gf.buffers[0])
        else:
            for i, b in enumerate(buffers):   # a GLB's own buffer becomes a file beside the .gltf
                if "uri" not in b:
                    b["uri"] = quote(f"{stem}.bd-uv-{i}.bin")
                    extra_files[b["uri"]] = gf.buffers[i]
            buffers.append({"uri": quote(f"{stem}.bd-uv.bin"), "byteLength": 0})
            writer = BufferWriter(doc, len(buffers) - 1)
        written = [path] + [os.path.join(out_dir, unquote(name)) for name in extra_files] + (
            [] if glb_out else [os.path.join(out_dir, unquote(buffers[-1]["uri"]))])
        clash = [w for w in written if os.path.realpath(w) in inputs]
        if clash:
            raise SceneFileError(f"{clash[0]} would overwrite a file {gf.path} uses; choose "
                                 "another output name or folder")
        out = {}
        for k, ch in charts.items():
            out[k] = self._patch(k, ch, writer)
        if not any(all(c.certified for c in certs) for certs, _ in out.values()):
            return out   # nothing certified as stored: no file at ``path`` that looks like one
        data = writer.finish()
        if glb_out:
            with atomic_path(path) as tmp:
                write_glb(tmp, doc, data)
        else:
            extra_files[buffers[-1]["uri"]] = data
            for name, blob in extra_files.items():
                with atomic_path(os.path.join(out_dir, unquote(name))) as tmp:
                    with open(tmp, "wb") as fh:
                        fh.write(blob)
            with atomic_path(path) as tmp:
                write_gltf_json(tmp, doc)
        return out

    def _patch(self, k, ch, writer):
        """Certify the stored UVs of mesh ``k``; if they pass, rewrite its primitives."""
        sm, part = self.meshes[k], self._parts[k]
        uv32 = np.stack([ch.corner_uv[..., 0], 1.0 - ch.corner_uv[..., 1]], -1).astype(np.float32)
        back = np.stack([uv32[..., 0].astype(np.float64), 1.0 - uv32[..., 1].astype(np.float64)], -1)
        certs = certify_islands(sm.mesh.V, sm.mesh.F, back, ch.face_island, ch.bounds)
        if not all(c.certified for c in certs):
            return certs, ["the UVs as stored in glTF (float32, v downwards) do not certify; "
                           "the mesh is left as it was"]
        warnings = []
        doc = self.gf.doc
        mesh = doc["meshes"][sm.info["mesh_index"]]
        for (j, lo, hi, corner_vertex) in part:
            warnings += _patch_primitive(self.gf, mesh, j, corner_vertex, uv32[lo:hi],
                                         self.uv_set, writer, sm.name)
        return certs, warnings


def input_files(doc, path):
    """Real paths of the file read and of every file its buffers and images name."""
    folder = os.path.dirname(os.path.abspath(path))
    out = {os.path.realpath(path)}
    for key in ("buffers", "images"):
        for item in doc.get(key, []):
            uri = item.get("uri")
            if uri and not uri.startswith("data:") and "://" not in uri:
                out.add(os.path.realpath(os.path.join(folder, unquote(uri))))
    return out
