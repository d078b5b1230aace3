"""One unwrap of the meshes in Edit Mode, shared by the synchronous and the background paths.

``gather`` copies every object's selected faces into one concatenated problem (islands never span
objects, so one ``bd_uv.unwrap`` call solves them all), ``write_back`` re-fetches each object,
checks it did not change meanwhile and writes the certified islands, ``pack`` runs Blender's own
``uv.pack_islands`` on them, and ``summarise`` turns the result into the report line.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import bpy
import numpy as np

from .. import bd_uv
from . import mesh_data
from .display import write_distortion_attributes

METHOD_LABELS = {"lscm": "BD-LSCM", "arap": "BD-ARAP"}


class UserError(Exception):
    """A problem with the user's input that the operator reports instead of solving."""


@dataclass
class Part:
    """One object's share of the concatenated problem."""

    object_name: str
    arrays: mesh_data.MeshArrays
    faces: slice                      # its rows of the concatenated F
    scale: tuple
    pin_unselected_uvs: bool
    pinned_faces: np.ndarray          # (m_i,) bool: triangles holding a pinned corner
    blender_pinned_faces: np.ndarray  # (m_i,) bool: ... pinned in Blender, not merely unselected
    use_object_scale: bool = True


@dataclass
class Batch:
    parts: list
    V: np.ndarray
    F: np.ndarray
    seams: np.ndarray
    pin_corners: np.ndarray
    pin_uv: np.ndarray
    initial_uv: np.ndarray | None
    areas: np.ndarray = field(default=None)  # (m,) 3D area of each triangle

    @property
    def face_count(self):
        return len(self.F)


def _pinned_faces(arrays):
    faces = np.zeros(len(arrays.F), dtype=bool)
    faces[arrays.pin_corners // 3] = True
    return faces


def _unwrap_scale(ob, use_object_scale):
    """The scale the positions are unwrapped at: magnitudes only, as a negative (mirroring)
    scale must not flip the UVs of the mesh data."""
    return tuple(abs(c) for c in ob.scale) if use_object_scale else (1.0, 1.0, 1.0)


def gather(objects, *, pin_unselected_uvs=False, use_object_scale=True, need_uvs=False):
    """Copy the selected faces of ``objects`` (Object Mode) into one problem.

    Raises
    ------
    UserError when no face is selected, or ``need_uvs`` and a mesh has no UV map.
    """
    parts, offset_v, offset_f = [], 0, 0
    Vs, Fs, seams, pins, pin_uv, uvs = [], [], [], [], [], []
    for ob in objects:
        scale = _unwrap_scale(ob, use_object_scale)
        arrays = mesh_data.mesh_arrays(ob, selected_only=True, scale=scale,
                                       pin_unselected_uvs=pin_unselected_uvs)
        m = len(arrays.F)
        if m == 0:
            continue
        if not all(np.isfinite(c) and c > 0 for c in scale):
            # Otherwise the core blames "zero-area faces" on a mesh that has none.
            raise UserError(f"{ob.name} has scale ({', '.join(f'{c:g}' for c in ob.scale)}), "
                            "which flattens it: give it a non-zero scale or turn off "
                            "Use Object Scale")
        if need_uvs and arrays.corner_uv is None:
            raise UserError(f"{ob.name} has no UV map to take frames from")
        blender_pins = (mesh_data.mesh_arrays(ob, selected_only=True, scale=scale)
                        if pin_unselected_uvs else arrays)
        parts.append(Part(ob.name, arrays, slice(offset_f, offset_f + m), scale,
                          pin_unselected_uvs, _pinned_faces(arrays), _pinned_faces(blender_pins),
                          use_object_scale))
        Vs.append(arrays.V)
        Fs.append(arrays.F + offset_v)
        seams.append(arrays.seams + offset_v)
        pins.append(arrays.pin_corners + 3 * offset_f)
        pin_uv.append(arrays.pin_uv)
        uvs.append(arrays.corner_uv if arrays.corner_uv is not None else np.zeros((m, 3, 2)))
        offset_v += len(arrays.V)
        offset_f += m
    if not parts:
        raise UserError("No faces selected: select the faces to unwrap in Edit Mode")
    V, F = np.concatenate(Vs), np.concatenate(Fs)
    P = V[F]
    areas = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    return Batch(parts, V, F, np.concatenate(seams).reshape(-1, 2),
                 np.concatenate(pins), np.concatenate(pin_uv).reshape(-1, 2),
                 np.concatenate(uvs) if need_uvs else None, areas)


def unwrap_arguments(batch, *, method, bound, minimise, raise_bound, bound_limit, frames):
    """Positional and keyword arguments of ``bd_uv.unwrap`` for ``batch``."""
    kwargs = dict(seams=batch.seams, method=method, bound="auto" if minimise else float(bound),
                  frames=frames, raise_bound=raise_bound, bound_limit=float(bound_limit))
    if len(batch.pin_corners):
        kwargs.update(pin_corners=batch.pin_corners, pin_uv=batch.pin_uv)
    if frames == "input-uv":
        kwargs["initial_uv"] = batch.initial_uv
    return (batch.V, batch.F), kwargs


@dataclass
class Written:
    """What ``write_back`` wrote for one object."""

    object_name: str
    faces: np.ndarray          # (m_i,) bool: triangles written
    pack_polygons: np.ndarray  # (P,) bool: polygons to pack (written, not merely-unselected-pinned)
    skipped: str = ""          # why nothing was written, when so


def write_back(batch, result):
    """Write the certified islands of ``result`` into each object's active UV map (Object Mode).

    Each object is looked up again by name and re-read: an object that was deleted or renamed, or
    whose mesh, selection, UVs, pins or object scale changed since ``gather`` is skipped, not
    written (the result is certified for the shape it was solved for only).
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
        mesh_data.write_corner_uvs(ob.data, part.arrays.uv_name, part.arrays.tri_loops,
                                   result.corner_uv[part.faces], faces)
        pack_faces = faces & ~soft_pinned[island_of_face[part.faces]]
        pack_polygons = np.zeros(len(ob.data.polygons), dtype=bool)
        pack_polygons[part.arrays.tri_poly[pack_faces]] = True
        written.append(Written(part.object_name, faces, pack_polygons))
    return written


def verify_written(batch, result, written):
    """Re-certify what is stored now (float32 UVs, after packing) and undo what no longer passes.

    Each written island is measured again from the UV map as Blender holds it; an island whose
    stored UVs flip a face or exceed its certified bound (e.g. packing shrank it to float32's
    resolution) gets its previous UVs back. Returns one message per island put back. Object Mode.
    """
    messages = []
    for part, w in zip(batch.parts, written):
        if w.skipped or not w.faces.any():
            continue
        ob = bpy.data.objects.get(part.object_name)
        now = mesh_data.mesh_arrays(ob, selected_only=True, uv_name=part.arrays.uv_name,
                                    scale=_unwrap_scale(ob, part.use_object_scale),
                                    pin_unselected_uvs=part.pin_unselected_uvs)
        D = bd_uv.conformal_distortion(part.arrays.V, part.arrays.F, now.corner_uv)
        islands = result.face_island[part.faces]
        undo = np.zeros(len(islands), dtype=bool)
        for i in np.unique(islands[w.faces]):
            r = result.islands[i]
            mine = (islands == i) & w.faces
            worst = float(np.max(D[mine]))
            if not worst <= r.bound_certified * (1 + 1e-6):
                undo |= mine
                messages.append(f"island {i} of {part.object_name} put back as it was: its stored "
                                f"UVs measure {worst:.4g} > {r.bound_certified:.4g} (packing "
                                "shrank it too far); unwrap it without packing")
        if undo.any() and part.arrays.corner_uv is not None:
            mesh_data.write_corner_uvs(ob.data, part.arrays.uv_name, part.arrays.tri_loops,
                                       part.arrays.corner_uv, undo)
            w.faces = w.faces & ~undo
    return messages


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
            mesh_data.select_polygons(
                ob.data, w.pack_polygons if w is not None else np.zeros(len(ob.data.polygons), bool))
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


@dataclass(frozen=True)
class Summary:
    message: str
    level: str          # 'INFO' | 'WARNING' | 'ERROR'
    written: bool       # something was written
    islands: int
    failed: int
    max_distortion: float
    mean_distortion: float
    flipped: int
    bound_certified: float
    seconds: float
    method: str


def summarise(batch, result, written, seconds):
    """The report line, e.g. ``BD-LSCM: 3 islands, max distortion 2.31 ≤ 5, 0 flipped, 1.8 s``."""
    label = METHOD_LABELS.get(result.method, result.method)
    good = [r for r in result.islands if r.status == "certified"]
    failed = [r for r in result.islands if r.status != "certified"]
    names = {}
    for part in batch.parts:
        for i in np.unique(result.face_island[part.faces]):
            names[int(i)] = part.object_name
    max_d = max((r.max_distortion for r in good), default=float("nan"))
    weights = np.array([batch.areas[r.faces].sum() for r in good])
    means = np.array([r.mean_distortion for r in good])
    mean_d = float((weights * means).sum() / weights.sum()) if good and weights.sum() > 0 else (
        float(np.mean(means)) if good else float("nan"))
    flips = int(sum(r.flipped for r in good))
    bound_c = max((r.bound_certified for r in good if r.bound_certified is not None),
                  default=float("nan"))
    parts = []
    if good:
        parts.append(f"{label}: {len(good)} island{'s' if len(good) != 1 else ''}, "
                     f"max distortion {max_d:.2f} \u2264 {bound_c:.3g}, {flips} flipped, "
                     f"{seconds:.1f} s")
    else:
        parts.append(f"{label}: nothing unwrapped")
    for r in failed:
        message = re.sub(rf"^island {r.index}:\s*", "", r.message)  # the core's own prefix
        parts.append(f"island {r.index} of {names.get(r.index, '?')} ({len(r.faces)} faces) "
                     f"left as it was: {message}")
    for w in written:
        if w.skipped:
            parts.append(f"{w.object_name} not written: {w.skipped}")
    wrote = any(w.faces.any() for w in written)
    level = 'INFO' if wrote and not failed and not any(w.skipped for w in written) else (
        'WARNING' if wrote else 'ERROR')
    return Summary("; ".join(parts), level, wrote, len(good), len(failed), float(max_d), mean_d,
                   flips, float(bound_c), float(seconds), label)


def store(window_manager, summary, faces):
    """Keep ``summary`` in the window manager's ``bd_uv_last_result`` for the panel."""
    last = window_manager.bd_uv_last_result
    last.valid = summary.written
    last.method = summary.method
    last.islands = summary.islands
    last.failed = summary.failed
    last.faces = faces
    last.max_distortion = summary.max_distortion if np.isfinite(summary.max_distortion) else 0.0
    last.mean_distortion = summary.mean_distortion if np.isfinite(summary.mean_distortion) else 0.0
    last.flipped = summary.flipped
    last.bound_certified = summary.bound_certified if np.isfinite(summary.bound_certified) else 0.0
    last.seconds = summary.seconds
    last.report = summary.message
