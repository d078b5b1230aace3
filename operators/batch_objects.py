"""``scripts/bd_uv_batch.py``'s objects: which mesh objects of the file are unwrapped (linked
duplicates once, linked library meshes refused by name), why a file has none, and each object
unwrapped by ``bd_uv.batch.unwrap_job`` with its certified islands written into its UV map
(``Written``), failures named in Blender's polygons.
"""
import os
import re

import bpy
import numpy as np

from ..bd_uv import batch
from ..bd_uv.meshio import uv_seams
from . import mesh_data
from .report import failure_text


def mesh_objects(names):
    """(objects to unwrap, report entries for names that are not usable mesh objects)."""
    missing = []
    if names:
        objects = []
        for name in names:
            ob = bpy.data.objects.get(name)
            if ob is None or ob.type != 'MESH':
                what = "no object" if ob is None else f"a {ob.type.lower()} object, not a mesh,"
                missing.append((name, f"there is {what} named {name!r} in the file"))
            else:
                objects.append(ob)
    else:
        objects = sorted((ob for ob in bpy.data.objects
                          if ob.type == 'MESH' and len(ob.data.polygons)),
                         key=lambda ob: ob.name)
    seen, unique = {}, []
    for ob in objects:  # linked duplicates share one mesh: unwrap it once
        if ob.data.name in seen:
            print(f"skipped {ob.name}: shares its mesh with {seen[ob.data.name]}")
        elif ob.data.library is not None:
            missing.append((ob.name, f"{ob.name}'s mesh is linked from {ob.data.library.filepath}"
                                     " and cannot be written here"))
        else:
            seen[ob.data.name] = ob.name
            unique.append(ob)
    return unique, missing


def nothing_to_unwrap():
    """Why a file has no mesh object to unwrap: linked libraries that are missing, collection
    instances (their meshes are in another file, or need making real)."""
    text = "the file holds no mesh object with faces"
    empty = [ob.name for ob in bpy.data.objects if ob.type == 'MESH' and not len(ob.data.polygons)]
    if empty:
        text += (f"; mesh object(s) {', '.join(empty[:3])}{' ...' if len(empty) > 3 else ''} "
                 "have edges or points only")
    lost = [lib.filepath for lib in bpy.data.libraries
            if not os.path.exists(bpy.path.abspath(lib.filepath))]
    if lost:
        text += (f"; {len(lost)} linked librar{'y is' if len(lost) == 1 else 'ies are'} "
                 f"missing ({', '.join(lost[:3])}), so their meshes could not be read")
    inst = [ob.name for ob in bpy.data.objects
            if ob.instance_type == 'COLLECTION' and ob.instance_collection is not None]
    if inst:
        text += (f"; collection instances ({', '.join(inst[:3])}) are not unwrapped: unwrap the "
                 "file they link, or make them real (Object > Apply > Make Instances Real)")
    return text


def leave_edit_mode(objects):
    view_layer = bpy.context.view_layer
    for ob in objects:
        if ob.mode != 'OBJECT' and ob.name in view_layer.objects:
            view_layer.objects.active = ob
            bpy.ops.object.mode_set(mode='OBJECT')


def file_name(text):
    return re.sub(r'[\\/:*?"<>|\s]+', "_", text).strip("._") or "object"


def in_polygons(entry, result, name, arrays):
    """Each island entry gains ``polygons`` (its faces as Blender counts them), and a failed
    island's message names polygons, not the triangles the core was given."""
    def polygons(tris):
        return {name: np.unique(arrays.tri_poly[np.asarray(tris, dtype=np.int64)])}
    for isl in entry["islands"]:
        r = result.islands[isl["island"]]
        isl["polygons"] = int(len(np.unique(arrays.tri_poly[r.faces])))
        if r.status != "certified":
            isl["message"] = (f"island {r.index} ({isl['polygons']} faces): "
                              f"{failure_text(r, polygons)}")
    bad = [i for i in entry["islands"] if i["status"] != "certified"]
    if bad:
        more = f" (and {len(bad) - 1} more failed island(s))" if len(bad) > 1 else ""
        entry["message"] = bad[0]["message"] + more


def unwrap_objects(objects, args, options, source):
    """Unwrap each object and write its certified islands into its UV map.

    Returns
    -------
    items : list of report entries, one per object
    written : list of Written, one per object with something written
    """
    items, written = [], []
    for ob in objects:
        try:
            scale = (1.0, 1.0, 1.0) if args.no_object_scale else tuple(abs(c) for c in ob.scale)
            arrays = mesh_data.mesh_arrays(ob, uv_name=args.uv_map, scale=scale)
            seams = arrays.seams
            if args.seams == "none":
                seams = None
            elif args.seams == "uv":
                if arrays.corner_uv is None:
                    raise ValueError(f"{ob.name} has no UV map, so --seams uv has nothing to "
                                     "cut along")
                seams = uv_seams(arrays.F, arrays.corner_uv)
            job = batch.Job(ob.name, arrays.V, arrays.F, seams=seams,
                            pin_corners=arrays.pin_corners, pin_uv=arrays.pin_uv,
                            corner_uv=arrays.corner_uv, face_groups=arrays.tri_poly,
                            uv_dtype=np.float32, position_dtype=np.float32)
            result = batch.unwrap_job(job, options)
            entry = {"input": source, "object": ob.name, "output": None, "uv_map": None,
                     "polygons": int(len(np.unique(arrays.tri_poly))), **result.entry}
            if result.result is not None:
                in_polygons(entry, result.result, ob.name, arrays)
            ok = np.isfinite(result.corner_uv).all(axis=(1, 2))
            if ok.any():
                name = args.uv_map or arrays.uv_name
                initial = None
                if arrays.corner_uv is None:  # a new map: keep what it holds before writing
                    layer = ob.data.uv_layers.new(name=name or "UVMap")
                    name, initial = layer.name, mesh_data.loop_uvs(ob.data, layer.name)
                entry["uv_map"] = mesh_data.write_corner_uvs(
                    ob.data, name, arrays.tri_loops, result.corner_uv, ok)
                written.append(Written(entry, ob, arrays, ok, result.result, initial))
        except Exception as exc:  # one object never stops the others
            entry = batch.failed_entry(ob.name, type(exc).__name__, f"{ob.name}: {exc}",
                                       input=source, object=ob.name, output=None, uv_map=None)
        items.append(entry)
    return items, written


class Written:
    """One object's written islands: its report entry, the object, its MeshArrays, the (m,) bool
    triangles written (and kept), the UnwrapResult, and for a map created here what it held
    before writing ((L,2) float32; None when the map existed)."""

    def __init__(self, entry, ob, arrays, ok, result, initial_uv=None):
        self.entry, self.ob, self.arrays, self.ok = entry, ob, arrays, ok
        self.result, self.initial_uv = result, initial_uv
