"""One glTF primitive patched with new UVs: its vertices split wherever the new UVs differ,
every attribute and morph target's deltas copied for each split vertex in its own component type,
the UVs appended as a float32 ``TEXCOORD_n`` and tangents a normal map reads through that set
dropped with a warning (``gltf.GltfScene.write``).
"""
import numpy as np

from .gltf_io import ARRAY_BUFFER, COMPONENT_TYPE, ELEMENT_ARRAY_BUFFER


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
    prim.pop("mode", None)   # a strip or fan is now the triangle list it drew (mode 4, default)
    return warnings


def _normal_map_set(doc, prim):
    """The TEXCOORD set the primitive's normal map reads, or None without a normal map."""
    try:
        nt = doc["materials"][prim["material"]].get("normalTexture")
    except (KeyError, IndexError, TypeError):
        return None
    return None if nt is None else nt.get("texCoord", 0)
