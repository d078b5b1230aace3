"""One glTF mesh read as arrays: its triangle primitives' positions (normalised integers mapped
to floats), indices checked, the UVs already in the file as seams, welded by exact value into one
``meshio.Mesh`` with each face's material (strips and fans as the triangles they draw);
primitives bd-uv cannot decode (Draco, meshopt) are named for the refusal
(``gltf.GltfScene.read``).
"""
import numpy as np

from ..errors import SceneFileError
from ..meshio import Mesh
from ..mesh.weld import welded

DRACO = "KHR_draco_mesh_compression"
TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN = 4, 5, 6


def strip_or_fan_triangles(idx, mode):
    """(m,3) triangles of a TRIANGLE_STRIP (5) or TRIANGLE_FAN (6) index list, in the glTF
    specification's order and winding (strip: odd triangles swap their first two corners; fan:
    every triangle ends at the first index); triangles that repeat an index (a strip's joins)
    are dropped: they have no area and no UV to give."""
    k = np.arange(max(len(idx) - 2, 0))
    if mode == TRIANGLE_STRIP:
        odd = (k % 2).astype(bool)
        F = np.stack([np.where(odd, idx[k + 1], idx[k]), np.where(odd, idx[k], idx[k + 1]),
                      idx[k + 2]], 1)
    else:
        F = np.stack([idx[k + 1], idx[k + 2], np.full(len(k), idx[0] if len(idx) else 0)], 1)
    keep = (F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])
    return F[keep].astype(np.int64)


def _as_float(values, acc):
    """Accessor values as float64, normalised integers mapped to [0,1] or [-1,1]."""
    v = values.astype(np.float64)
    if acc.get("normalized") and values.dtype.kind in "iu":
        info = np.iinfo(values.dtype)
        v = v / info.max if values.dtype.kind == "u" else np.maximum(v / info.max, -1.0)
    return v


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


def _copies_readable(gf, label, prims):
    """Read every accessor the writer copies per split vertex (the attributes besides POSITION,
    which ``_mesh_arrays`` reads, and the morph targets' deltas), so that one that cannot be read
    refuses its mesh here, by name, instead of stopping the whole write after the unwrap
    (``gltf_patch._patch_primitive``). Raises SceneFileError."""
    for j, p in prims:
        where = f"{label} primitive {j}"
        for key, acc in p.get("attributes", {}).items():
            if key != "POSITION":
                gf.accessor(acc, f"{where} {key}")
        for t, target in enumerate(p.get("targets", [])):
            for key, acc in target.items():
                gf.accessor(acc, f"{where} target {t} {key}")


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
        mode = p.get("mode", TRIANGLES)
        if mode == TRIANGLES and len(idx) % 3:
            raise SceneFileError(f"{gf.path}: {where}: {len(idx)} indices is not a whole "
                                 "number of triangles")
        if len(idx) and (idx.max() >= n or idx.min() < 0):   # signed types can go below 0
            bad = int(idx.min()) if idx.min() < 0 else int(idx.max())
            raise SceneFileError(f"{gf.path}: {where}: index {bad} is out of range "
                                 f"({n} vertices)")
        F = idx.reshape(-1, 3) if mode == TRIANGLES else strip_or_fan_triangles(idx, mode)
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
