"""glTF 2.0 scenes: every triangle primitive unwrapped once per mesh, the document patched.

Reading: each mesh's triangle primitives (mode 4) become one unwrap problem in the mesh's own
space (a mesh used by several nodes is unwrapped once); their positions are welded by exact value,
so the file's vertex splits (hard normals, old seams) do not cut the surface (parts that only touch
at a point stay apart: ``weld.py``); the UVs already in
the file (the set written, else ``TEXCOORD_0``) give the seams, as an OBJ's ``vt`` do. Lines,
points, strips and fans pass through unchanged.

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
from ..meshio import Mesh
from ..scheduling.atomic import atomic_path
from .model import SceneMesh
from .weld import welded
from .gltf_io import (ARRAY_BUFFER, COMPONENT_TYPE, ELEMENT_ARRAY_BUFFER, BufferWriter,
                      read_gltf, rebase_uris, write_glb, write_gltf_json)

TRIANGLES = 4
DRACO = "KHR_draco_mesh_compression"


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


def _as_float(values, acc):
    """Accessor values as float64, normalised integers mapped to [0,1] or [-1,1]."""
    v = values.astype(np.float64)
    if acc.get("normalized") and values.dtype.kind in "iu":
        info = np.iinfo(values.dtype)
        v = v / info.max if values.dtype.kind == "u" else np.maximum(v / info.max, -1.0)
    return v


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
                     if p.get("mode", TRIANGLES) == TRIANGLES]
            warnings = [f"{label}: primitive {j} (mode {p['mode']}) is not a triangle list; "
                        "left as it is" for j, p in enumerate(mesh.get("primitives", []))
                        if p.get("mode", TRIANGLES) not in (TRIANGLES, 0, 1, 2, 3)]
            if not prims:
                continue
            names = paths.get(mi) or [label]
            info = {"mesh": mesh.get("name"), "mesh_index": mi, "nodes": paths.get(mi, []),
                    "primitives": [j for j, _ in prims]}
            try:   # a malformed mesh is refused by name, the file's other meshes unwrapped
                refused = _refusal(gf, label, prims)
                if not refused:
                    m, part = _mesh_arrays(gf, label, prims, uv_set, names[0])
            except SceneFileError as exc:
                refused = str(exc).removeprefix(f"{gf.path}: ")   # the entry names the file
            if refused:
                meshes.append(SceneMesh(", ".join(names), None, info, refused, None, warnings))
                parts.append(None)
                continue
            meshes.append(SceneMesh(", ".join(names), m, info, None, None, warnings))
            parts.append(part)
        return cls(gf, uv_set, meshes, parts)

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


def _refusal(gf, label, prims):
    for j, p in prims:
        if DRACO in p.get("extensions", {}):
            return (f"{label} primitive {j} is Draco-compressed ({DRACO}); bd-uv does not "
                    "decode Draco: decompress the file first (e.g. gltf-transform copy IN OUT)")
        for name, acc in list(p.get("attributes", {}).items()) + [("indices", p.get("indices"))]:
            if acc is None:
                continue
            try:
                view = gf.doc["accessors"][acc].get("bufferView")
                ext = gf.doc["bufferViews"][view].get("extensions", {}) if view is not None else {}
            except (IndexError, KeyError, TypeError):
                raise SceneFileError(f"{gf.path}: {label} primitive {j} {name}: accessor {acc} "
                                     "does not exist")
            if "EXT_meshopt_compression" in ext or "KHR_meshopt_compression" in ext:
                return (f"{label} primitive {j} is meshopt-compressed (EXT_meshopt_compression); "
                        "bd-uv does not decode it: decompress the file first "
                        "(e.g. gltf-transform copy IN OUT)")
    return None


def _mesh_arrays(gf, label, prims, uv_set, name):
    """One welded triangle mesh of a glTF mesh's triangle primitives, and how to write back."""
    Vs, Fs, UVs, part, offset, lo = [], [], [], [], 0, 0
    for j, p in prims:
        where = f"{label} primitive {j}"
        attrs = p.get("attributes", {})
        if "POSITION" not in attrs:
            raise SceneFileError(f"{gf.path}: {where} has no POSITION")
        acc = gf.doc["accessors"][attrs["POSITION"]]
        V = _as_float(gf.accessor(attrs["POSITION"], where + " POSITION"), acc)
        if V.shape[1] != 3:
            raise SceneFileError(f"{gf.path}: {where}: POSITION is not VEC3")
        n = len(V)
        if "indices" in p:
            idx = gf.accessor(p["indices"], where + " indices")[:, 0].astype(np.int64)
        else:
            idx = np.arange(n, dtype=np.int64)
        if len(idx) % 3:
            raise SceneFileError(f"{gf.path}: {where}: {len(idx)} indices is not a whole "
                                 "number of triangles")
        if len(idx) and (idx.max() >= n or idx.min() < 0):   # signed types can go below 0
            bad = int(idx.min()) if idx.min() < 0 else int(idx.max())
            raise SceneFileError(f"{gf.path}: {where}: index {bad} is out of range "
                                 f"({n} vertices)")
        F = idx.reshape(-1, 3)
        key = f"TEXCOORD_{uv_set}" if f"TEXCOORD_{uv_set}" in attrs else "TEXCOORD_0"
        if UVs is not None and key in attrs:
            uv = _as_float(gf.accessor(attrs[key], f"{where} {key}"),
                           gf.doc["accessors"][attrs[key]])
            UVs.append(np.stack([uv[:, 0], 1.0 - uv[:, 1]], -1)[F])
        else:
            UVs = None
        Vs.append(V)
        Fs.append(F + offset)
        part.append((j, lo, lo + len(F), F))
        offset += n
        lo += len(F)
    V = np.concatenate(Vs)
    F = np.concatenate(Fs)
    if len(F) == 0:
        raise SceneFileError(f"{gf.path}: {label} has no triangles")
    W, G = welded(V, F)
    corner_uv = np.concatenate(UVs) if UVs else None
    # each face's material: its primitive's (-1: none); one glTF mesh is one object
    material = np.concatenate([np.full(len(Fj), prims[i][1].get("material", -1), np.int64)
                               for i, (_, _, _, Fj) in enumerate(part)])
    labels = {"material": material, "object": np.zeros(len(G), np.int64)}
    return Mesh(W, G, corner_uv, name, labels), part


def _patch_primitive(gf, mesh, j, corner_vertex, uv32, uv_set, writer, name):
    """Split primitive ``j``'s vertices by their new UVs and point it at the new accessors."""
    doc = gf.doc
    prim = mesh["primitives"][j]
    where = f"{name} primitive {j}"
    keys = np.stack([corner_vertex.reshape(-1).astype(np.int64),
                     uv32.reshape(-1, 2).view(np.uint32)[:, 0].astype(np.int64),
                     uv32.reshape(-1, 2).view(np.uint32)[:, 1].astype(np.int64)], 1)
    uniq, first, inv = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    src = uniq[:, 0]                       # the input vertex each output vertex copies
    new_uv = uv32.reshape(-1, 2)[first]
    target = f"TEXCOORD_{uv_set}"
    warnings = []
    normal_set = _normal_map_set(doc, prim)
    drop_tangent = "TANGENT" in prim.get("attributes", {}) and (
        normal_set == uv_set or (normal_set is None and uv_set == 0))
    if drop_tangent:
        warnings.append(f"{where}: TANGENT dropped (it followed {target}, which was rewritten); "
                        "viewers derive MikkTSpace tangents from the new UVs")

    def copy(acc_index, label, bounds=False):
        acc = doc["accessors"][acc_index]
        vals = gf.accessor(acc_index, f"{where} {label}")[src]
        return writer.accessor(vals, acc["componentType"], acc["type"], ARRAY_BUFFER,
                               acc.get("normalized", False),
                               bounds=bounds or "min" in acc or "max" in acc)

    attrs = {}
    for key, acc in prim["attributes"].items():
        if key == target or (key == "TANGENT" and drop_tangent):
            continue
        attrs[key] = copy(acc, key, bounds=key == "POSITION")
    attrs[target] = writer.accessor(new_uv, COMPONENT_TYPE[np.dtype("<f4").str], "VEC2",
                                    ARRAY_BUFFER)
    if "targets" in prim:
        targets = []
        for t, tgt in enumerate(prim["targets"]):
            new_t = {}
            for key, acc in tgt.items():
                if key == target or (key == "TANGENT" and drop_tangent):
                    warnings.append(f"{where}: morph target {t} {key} deltas dropped "
                                    f"({target} was rewritten)")
                    continue
                new_t[key] = copy(acc, f"target {t} {key}", bounds=key == "POSITION")
            targets.append(new_t)
        prim["targets"] = targets
    prim["attributes"] = attrs
    nv = len(src)
    ctype = 5123 if nv <= 65535 else 5125     # the type's largest value is reserved (restart)
    prim["indices"] = writer.accessor(inv.reshape(-1, 1), ctype, "SCALAR", ELEMENT_ARRAY_BUFFER)
    return warnings


def _normal_map_set(doc, prim):
    """The TEXCOORD set the primitive's normal map reads, or None without a normal map."""
    try:
        nt = doc["materials"][prim["material"]].get("normalTexture")
    except (KeyError, IndexError, TypeError):
        return None
    return None if nt is None else nt.get("texCoord", 0)
