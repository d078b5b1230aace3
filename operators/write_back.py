"""Writing: the certified islands into each object's UV map, seams, packing, colours.

``write_back`` re-fetches each object, checks it did not change meanwhile and writes the
certified islands; ``pack`` runs Blender's own ``uv.pack_islands`` on them; ``mark_seams`` marks
the seams the core added or cut along; ``show_distortion`` colours the result.
"""
from __future__ import annotations

from dataclasses import dataclass

import bpy
import numpy as np

from . import mesh_data
from .display import write_distortion_attributes
from .gather import _unwrap_scale


def overlap_cuts(result):
    """(k,2) batch vertex pairs of the edges along which the core cut islands whose UVs lay over
    themselves (certified pieces only)."""
    cuts = [r.cut_edges for r in result.islands
            if r.status == "certified" and r.cut_edges is not None and len(r.cut_edges)]
    if not cuts:
        return np.zeros((0, 2), dtype=np.int64)
    return np.unique(np.sort(np.concatenate(cuts), axis=1), axis=0)


def mark_seams(batch, written, added):
    """Mark the seams ``added`` (k,2) vertex pairs of the batch on each written object's mesh
    (Object Mode); objects skipped by ``write_back`` or with nothing written are left alone.

    Returns
    -------
    int, edges newly marked as seams over all objects
    """
    added = np.asarray(added, dtype=np.int64).reshape(-1, 2)
    total, offset = 0, 0
    for part, w in zip(batch.parts, written):
        nv = len(part.arrays.V)
        mine = added[((added >= offset) & (added < offset + nv)).all(axis=1)] - offset
        offset += nv
        if w.skipped or not w.faces.any() or not len(mine):
            continue
        ob = bpy.data.objects.get(part.object_name)
        total += int(mesh_data.mark_seams(ob.data, part.arrays.vertices[mine]).sum())
    return total


@dataclass
class Written:
    """What ``write_back`` wrote for one object."""

    object_name: str
    faces: np.ndarray          # (m_i,) bool: triangles written (and kept after the re-check)
    pack_polygons: np.ndarray  # (P,) bool: polygons to pack (written, not merely-unselected-pinned)
    skipped: str = ""          # why nothing was written, when so
    created_map: str = ""      # name of the UV map write_back created (the mesh had none)
    initial_uv: np.ndarray = None  # (L,2) float32: what the created map held before writing


def write_back(batch, result):
    """Write the certified islands of ``result`` into each object's active UV map (Object Mode).

    Each object is looked up again by name and re-read: an object that was deleted or renamed, or
    whose mesh, selection, UVs, pins or object scale changed since ``gather`` is skipped, not
    written (the result is certified for the shape it was solved for only). An object with
    nothing certified is not touched at all (no UV map is created for it); when a map is created,
    what it held before writing is kept so :func:`verify_written` can restore it exactly.
    """
    good = np.isfinite(result.corner_uv).all(axis=(1, 2))
    island_of_face = result.face_island
    n_islands = len(result.islands)
    island_ok = np.array([r.status == "certified" for r in result.islands], dtype=bool)
    face_ok = good & island_ok[island_of_face] if n_islands else good
    # Islands holding a pin that only comes from unselected UVs must not move when packing.
    soft_pinned = np.zeros(n_islands, dtype=bool)
    for part in batch.parts:
        soft = part.pinned_faces & ~part.blender_pinned_faces
        soft_pinned[island_of_face[part.faces][soft]] = True

    written = []
    for part in batch.parts:
        ob = bpy.data.objects.get(part.object_name)
        if ob is None or ob.type != 'MESH':
            written.append(Written(part.object_name, np.zeros(0, bool), np.zeros(0, bool),
                                   "deleted or renamed while solving"))
            continue
        now = mesh_data.mesh_arrays(ob, selected_only=True, uv_name=part.arrays.uv_name,
                                    scale=_unwrap_scale(ob, part.use_object_scale),
                                    pin_unselected_uvs=part.pin_unselected_uvs)
        if now.topology_key != part.arrays.topology_key:
            written.append(Written(part.object_name, np.zeros(0, bool), np.zeros(0, bool),
                                   "changed while solving"))
            continue
        faces = face_ok[part.faces]
        pack_polygons = np.zeros(len(ob.data.polygons), dtype=bool)
        if not faces.any():
            written.append(Written(part.object_name, faces, pack_polygons))
            continue
        created, initial = "", None
        if part.arrays.uv_name is None:
            layer = ob.data.uv_layers.new(name="UVMap")
            if layer is None:
                raise RuntimeError(f"cannot add a UV map to {ob.data.name!r}")
            created, initial = layer.name, mesh_data.loop_uvs(ob.data, layer.name)
        mesh_data.write_corner_uvs(ob.data, created or part.arrays.uv_name,
                                   part.arrays.tri_loops, result.corner_uv[part.faces], faces)
        pack_faces = faces & ~soft_pinned[island_of_face[part.faces]]
        pack_polygons[part.arrays.tri_poly[pack_faces]] = True
        written.append(Written(part.object_name, faces, pack_polygons, "", created, initial))
    return written


def pack(context, written, margin, shape='AABB'):
    """Blender's ``uv.pack_islands`` on the written islands; islands with pins stay put.

    ``shape`` is its ``shape_method``: 'AABB' (default) packs 15k faces in ~2 ms, as fast as
    Blender's own Unwrap; 'CONCAVE' took 1-2.5 s on the same mesh (bpy 5.0.1, 2 cores).

    Needs the objects in Edit Mode. The mesh selection is temporarily set to the polygons to pack
    (in face select mode, with UV sync selection, so exactly those islands are packed) and
    restored afterwards; pinned islands are locked (``pin=True, pin_method='LOCKED'``).
    """
    todo = [w for w in written if w.pack_polygons.any()]
    if not todo:
        return
    tool = context.scene.tool_settings
    saved_sync, saved_mode = tool.use_uv_select_sync, tuple(tool.mesh_select_mode)
    saved = {}
    from .editmode import object_mode
    options = dict(margin=margin, shape_method=shape, pin=True, pin_method='LOCKED')
    with object_mode(context) as objects:
        for ob in objects:
            saved[ob.name] = mesh_data.selection(ob.data)
            w = next((w for w in todo if w.object_name == ob.name), None)
            mesh_data.select_polygons(ob.data, w.pack_polygons if w is not None
                                      else np.zeros(len(ob.data.polygons), bool))
        tool.use_uv_select_sync = True
        tool.mesh_select_mode = (False, False, True)
    try:
        if bpy.ops.uv.pack_islands.poll():
            bpy.ops.uv.pack_islands(**options)
        else:
            # E.g. an Image Editor in View mode: pack_islands polls for a UV editor or none.
            with context.temp_override(area=None, region=None, space_data=None):
                bpy.ops.uv.pack_islands(**options)
    finally:
        with object_mode(context) as objects:
            for ob in objects:
                if ob.name in saved:
                    mesh_data.set_selection(ob.data, *saved[ob.name])
            tool.use_uv_select_sync = saved_sync
            tool.mesh_select_mode = saved_mode


def show_distortion(context, written, bound):
    """Distortion attributes on every object that was written (Object Mode inside)."""
    from .editmode import object_mode
    with object_mode(context):
        for w in written:
            ob = bpy.data.objects.get(w.object_name)
            if ob is not None and w.faces.any():
                write_distortion_attributes(ob.data, bound)
