"""One unwrap of the meshes in Edit Mode, shared by the synchronous and the background paths.

``gather`` copies every object's selected faces into one concatenated problem (islands never span
objects, so one ``bd_uv.unwrap`` call solves them all), ``write_back`` re-fetches each object,
checks it did not change meanwhile and writes the certified islands, ``pack`` runs Blender's own
``uv.pack_islands`` on them, ``verify_written`` certifies every written island again from the UVs
as stored and puts back those that fail, and ``summarise`` turns what is stored into the report
line (in Blender's terms: faces are polygons).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import bpy
import numpy as np

from .. import bd_uv
from . import mesh_data, stored
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
        """Faces as the user counts them: Blender polygons (the core gets their triangles)."""
        return int(sum(len(np.unique(p.arrays.tri_poly)) for p in self.parts))

    def polygons(self, tris):
        """{object name: sorted polygon indices} of the batch's triangles ``tris`` (k,) int."""
        tris = np.asarray(tris, dtype=np.int64).reshape(-1)
        out = {}
        for part in self.parts:
            mine = tris[(tris >= part.faces.start) & (tris < part.faces.stop)] - part.faces.start
            if len(mine):
                out[part.object_name] = np.unique(part.arrays.tri_poly[mine])
        return out


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


@dataclass(frozen=True)
class Checked:
    """The post-write check of one written island (``stored.StoredIsland``) and its owner."""

    object_name: str
    polygons: int              # its faces as the user counts them
    area: float                # 3D area (weights the mean)
    stored: object             # stored.StoredIsland
    put_back: bool


@dataclass
class Verified:
    """What :func:`verify_written` found: every written island as stored, and the overlaps
    between islands of each object's stored layout."""

    islands: list                                   # of Checked
    overlaps: dict = field(default_factory=dict)    # object name -> island pairs (k,2), or None


def _restore(ob, part, w, undo):
    """Give the triangles ``undo`` (m_i,) bool of ``part`` back the UVs they had; remove the map
    ``write_back`` created when nothing written is left on it."""
    mesh = ob.data
    if not w.created_map:
        mesh_data.write_corner_uvs(mesh, part.arrays.uv_name, part.arrays.tri_loops,
                                   part.arrays.corner_uv, undo)
        return
    layer = mesh.uv_layers.get(w.created_map)
    if layer is None:
        return
    if not (w.faces & ~undo).any():
        mesh.uv_layers.remove(layer)
        mesh.update()
        return
    uv = mesh_data.loop_uvs(mesh, w.created_map)
    loops = part.arrays.tri_loops[undo].ravel()
    uv[loops] = w.initial_uv[loops]
    layer.uv.foreach_set("vector", uv.ravel())
    mesh.update()


def verify_written(batch, result, written):
    """Re-certify what is stored now (float32 UVs, after packing) and put back what fails.

    Each written island is certified again from the UV map as Blender holds it, with its own
    bound, by :func:`stored.check_stored` (the core's one certificate). An island that fails
    gets its previous UVs back; on a mesh that had no UV map the created map is removed when
    nothing is left on it. Object Mode.

    Returns
    -------
    Verified
    """
    checked, overlaps = [], {}
    for part, w in zip(batch.parts, written):
        if w.skipped or not w.faces.any():
            continue
        ob = bpy.data.objects.get(part.object_name)
        uv_name = w.created_map or part.arrays.uv_name
        uv = mesh_data.loop_uvs(ob.data, uv_name)[part.arrays.tri_loops].astype(np.float64)
        islands = result.face_island[part.faces]
        labels = np.where(w.faces, islands, -1)
        checks = stored.check_stored(part.arrays.V, part.arrays.F, uv, labels, result.islands,
                                     solved_uv=result.corner_uv[part.faces])
        P = part.arrays.V[part.arrays.F]
        area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
        n = len(result.islands)
        on = labels >= 0
        island_area = np.bincount(labels[on], weights=area[on], minlength=n)
        pairs = np.unique(np.stack([labels[on], part.arrays.tri_poly[on]], 1), axis=0)
        island_polygons = np.bincount(pairs[:, 0], minlength=n)
        failed = np.zeros(n + 1, dtype=bool)  # the last entry: faces not written (label -1)
        failed[[c.island for c in checks if not c.certified]] = True
        undo = failed[labels]
        checked.extend(Checked(part.object_name, int(island_polygons[c.island]),
                               float(island_area[c.island]), c, not c.certified)
                       for c in checks)
        if undo.any():
            _restore(ob, part, w, undo)
            w.faces = w.faces & ~undo
            labels = np.where(w.faces, islands, -1)
        if len(np.unique(labels[labels >= 0])) > 1:
            overlaps[part.object_name] = stored.layout_overlaps(uv, labels, part.arrays.F)
    return Verified(checked, overlaps)


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


@dataclass(frozen=True)
class Summary:
    """The report line and the figures the panel shows: those of the post-write check."""

    message: str
    level: str          # 'INFO' | 'WARNING' | 'ERROR'
    written: bool       # something was written and kept
    islands: int        # islands written and kept
    failed: int         # islands the core could not unwrap
    max_distortion: float
    mean_distortion: float
    flipped: int
    bound_certified: float
    seconds: float
    method: str
    raised: int = 0     # islands certified at a C above the one asked for
    put_back: int = 0   # islands put back by the post-write check
    overlaps: int = 0   # pairs of islands overlapping in the stored layouts


LISTED = 8  # islands named one by one in the report line; the rest are counted


def _more(n):
    return f", ... ({n} islands in all)" if n > LISTED else ""


def _some(values, k=8):
    values = [int(v) for v in values]
    text = ", ".join(str(v) for v in values[:k])
    return text + (f", ... ({len(values)} in all)" if len(values) > k else "")


def _up(x, digits=4):
    """``x`` rounded up to ``digits`` significant digits, as text (a bound shown never below
    the truth)."""
    if not np.isfinite(x) or x <= 0:
        return f"{x:g}"
    step = 10.0 ** (np.floor(np.log10(x)) - digits + 1)
    return f"{np.ceil(x / step - 1e-9) * step:.{digits}g}"


def _down(x, digits=4):
    """``x`` rounded down to ``digits`` significant digits (a measure shown never above it)."""
    if not np.isfinite(x) or x <= 0:
        return f"{x:g}"
    step = 10.0 ** (np.floor(np.log10(x)) - digits + 1)
    return f"{np.floor(x / step + 1e-9) * step:.{digits}g}"


_FACE_LIST = re.compile(r"\bfaces (\d+(?:, \d+)*(?:, \.\.\. \(\d+ in all\))?)")


def failure_text(r, polygons):
    """Why island ``r`` (a failed IslandResult) was not unwrapped, in Blender's terms: the
    core's message without its own "island N (k faces)" prefix (the caller names the island),
    with triangle counts and indices replaced by the polygons they belong to.

    Parameters
    ----------
    r : IslandResult
    polygons : callable
        ``polygons(tris)`` -> {object name: sorted polygon indices} of (k,) triangle indices
        (``Batch.polygons``).
    """
    text = re.sub(rf"^island {r.index}(?: \(\d+ faces\))?:?\s*", "", r.message or "")
    tris = getattr(r.error, "faces", None)
    if tris is not None and len(tris):
        where = polygons(tris)
        n = sum(len(p) for p in where.values())
        listed = "; ".join(f"{name} faces {_some(p)}" if len(where) > 1 else f"faces {_some(p)}"
                           for name, p in where.items())
        text = _FACE_LIST.sub(lambda _: listed, text, count=1)
        text = re.sub(rf"\b{len(tris)} (zero-area )?face(\(s\)|s)\b",
                      lambda m: f"{n} {m.group(1) or ''}face{'s' if n != 1 else ''}", text,
                      count=1)
    return text


def _name(batch, result, i, names):
    """``island 3 of Cube (6 faces)``: an island named once, counted in polygons."""
    r = result.islands[i]
    where = batch.polygons(r.faces)
    n = sum(len(p) for p in where.values())
    return f"island {i} of {names.get(i, '?')} ({n} face{'s' if n != 1 else ''})"


def summarise(batch, result, written, seconds, verified=None, packed=False):
    """The report line, from the post-write check of what is stored.

    E.g. ``BD-LSCM: 3 islands, max distortion 2.31 ≤ 5, 0 flipped, 1.8 s``, followed by what
    did not go as asked: islands whose C was raised (to what), islands the core could not
    unwrap (named once, in polygons), islands put back by the post-write check, overlaps
    between islands of a stored layout, objects not written.
    """
    label = METHOD_LABELS.get(result.method, result.method)
    names = {}
    for part in batch.parts:
        for i in np.unique(result.face_island[part.faces]):
            names[int(i)] = part.object_name
    checked = verified.islands if verified is not None else []
    kept = [c for c in checked if not c.put_back]
    back = [c for c in checked if c.put_back]
    failed = [r for r in result.islands if r.status != "certified"]
    max_d = max((c.stored.max_distortion for c in kept), default=float("nan"))
    weights = np.array([c.area for c in kept])
    means = np.array([c.stored.mean_distortion for c in kept])
    mean_d = (float((weights * means).sum() / weights.sum()) if kept and weights.sum() > 0
              else float("nan"))
    flips = int(sum(c.stored.flipped for c in kept))
    bound_c = max((c.stored.bound for c in kept), default=float("nan"))
    minimised = any(result.islands[c.stored.island].bound_requested == "auto" for c in kept)

    raised = []
    for c in kept:
        r = result.islands[c.stored.island]
        asked = r.bound_requested
        if isinstance(asked, (int, float)) and (
                "bound_raised" in r.flags or c.stored.bound > float(asked) * (1 + 1e-9)):
            raised.append((c, float(asked)))

    parts = []
    if kept:
        parts.append(f"{label}: {len(kept)} island{'s' if len(kept) != 1 else ''}, "
                     f"max distortion {_down(max_d)} \u2264 {_up(bound_c)}"
                     f"{' (minimised)' if minimised else ''}, {flips} flipped, {seconds:.1f} s")
    else:
        parts.append(f"{label}: nothing unwrapped")
    if raised:
        asked = sorted({a for _, a in raised})
        listed = [f"{_name(batch, result, c.stored.island, names)} to {_up(c.stored.bound)}"
                  for c, _ in raised[:LISTED]]
        parts.append(f"C raised from {', '.join(f'{a:g}' for a in asked)}: "
                     + ", ".join(listed) + _more(len(raised)))
    for r in failed[:LISTED]:
        text = failure_text(r, batch.polygons)
        parts.append(f"{_name(batch, result, r.index, names)} {text}; left as it was"
                     if re.match(r"(is|has) ", text) else
                     f"{_name(batch, result, r.index, names)} left as it was: {text}")
    if len(failed) > LISTED:
        parts.append(f"{len(failed) - LISTED} more islands left as they were")
    for c in back[:LISTED]:
        why = c.stored.reason or "it no longer passes"
        if c.stored.failed_as_solved:  # the solve's own certificate did not check this
            text = f"its UVs fail the certificate ({why}) as solved already"
        else:
            text = (f"its stored UVs fail the certificate ({why}); " + (
                "packing shrank or moved it too far: unwrap it without packing" if packed
                else "float32 storage changed it"))
        parts.append(f"{_name(batch, result, c.stored.island, names)} put back as it was: {text}")
    if len(back) > LISTED:
        parts.append(f"{len(back) - LISTED} more islands put back as they were")
    n_overlaps = 0
    for object_name, pairs in (verified.overlaps.items() if verified is not None else ()):
        if pairs is None or not len(pairs):
            continue
        pairs = np.asarray(pairs).reshape(-1, 2)
        n_overlaps += len(pairs)
        listed = ", ".join(f"{a} and {b}" for a, b in pairs[:6]) + (
            f", ... ({len(pairs)} pairs in all)" if len(pairs) > 6 else "")
        parts.append(f"islands overlap in {object_name}'s UV map: {listed}"
                     + ("" if packed else "; turn on Pack Islands to lay them apart"))
    for w in written:
        if w.skipped:
            parts.append(f"{w.object_name} not written: {w.skipped}")
    wrote = bool(kept)
    clean = not failed and not back and not n_overlaps and not any(w.skipped for w in written)
    # An ERROR makes a scripted bpy.ops call raise: only when nothing was written because the
    # scene changed under a background solve. Islands that cannot be unwrapped are a WARNING,
    # as with Blender's own Unwrap, so a script looping over objects carries on.
    level = 'INFO' if wrote and clean else (
        'ERROR' if not wrote and any(w.skipped for w in written) else 'WARNING')
    return Summary("; ".join(parts), level, wrote, len(kept), len(failed), float(max_d), mean_d,
                   flips, float(bound_c), float(seconds), label, len(raised), len(back),
                   n_overlaps)


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
    last.raised = summary.raised
    last.put_back = summary.put_back
    last.overlaps = summary.overlaps
    last.report = summary.message
