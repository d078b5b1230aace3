"""``uv.bd_deform``: move pinned UVs, run it, and the rest of each UV island follows within C.

Per UV island of the selected faces, the pinned UVs (and the UVs the selection shares with
unselected faces, so the island does not tear) are handles kept exactly where they are and the
other UVs are re-solved by ``bd_uv.deform`` (Lipman 2012, section 6.1) so that every face
keeps its conformal distortion against the current layout within C with no flip (the rest shape
and what is refused: :mod:`.uv_deform`). Only islands certified again from the UVs as stored are
kept: 0 flipped faces, max distortion <= C against the rest shape, an overlap-free boundary and
every pinned UV bit for bit where it was; any other island gets its UVs back. One undo step.
"""
import re
from dataclasses import dataclass

import numpy as np

import bpy
from bpy.props import EnumProperty, FloatProperty

from .. import bd_uv
from . import gather, mesh_data, uv_deform
from .background import BackgroundSolve
from .editmode import edit_mesh_objects, object_mode
from .report import _down, _up

_METHODS = (
    ('arap', "BD-ARAP", "As-rigid-as-possible: keeps lengths and areas of the current layout "
     "as far as the pins allow"),
    ('lscm', "BD-LSCM (ASAP)", "As-similar-as-possible: keeps angles; islands may grow or shrink "
     "locally"),
    ('dirichlet', "BD-Dirichlet", "Smoothest map (harmonic energy) within C"),
    ('biharmonic', "BD-Biharmonic", "Smoothest in the second derivatives (Lipman 2012, eq. 6.1): "
     "the pins' moves spread furthest"),
)
_FRAMES = (
    ('rest', "From Rest Shape", "Frames of the current layout with the pins put back (Lipman "
     "2012, constant frames of the rest shape)"),
    ('current', "From Current UVs", "Frames of the UVs as they are now, moved pins included "
     "(eq. 4.21): the previous solution, for small moves after a deformation; fails when moved "
     "pins have flipped faces"),
)
METHOD_LABELS = {m[0]: m[1].split(" ")[0] for m in _METHODS}


class UV_OT_bd_deform(BackgroundSolve, bpy.types.Operator):
    """Re-solve the selected UV islands around their pinned UVs with a certified bound on
    conformal distortion and no flipped face: move pins, deform, the layout follows"""

    bl_idname = "uv.bd_deform"
    bl_label = "Bounded Distortion Deform"
    bl_options = {'REGISTER', 'UNDO'}
    JOB = "Bounded Distortion deform"

    method: EnumProperty(name="Method", items=_METHODS, default='arap')
    bound: FloatProperty(name="Bound C", default=5.0, min=1.0001, soft_min=1.05, soft_max=50.0,
                         description="Largest conformal distortion of any face against the "
                         "current layout")
    frames: EnumProperty(name="Frames", items=_FRAMES, default='rest')

    @classmethod
    def poll(cls, context):
        if edit_mesh_objects(context):
            return True
        cls.poll_message_set("Needs a mesh in Edit Mode with UVs: pin UVs in the UV editor, "
                             "move them and deform")
        return False

    def _prepare(self, context):
        try:
            with object_mode(context) as objects:
                for ob in objects:
                    if ob.data.uv_layers.active is None:
                        raise gather.UserError(f"{ob.name} has no UV map to deform: unwrap it "
                                               "first")
                batch = gather.gather(objects, need_uvs=True)
                # UVs the selection shares with unselected faces are held, or the island tears.
                held = [_shared_corners(bpy.data.objects[p.object_name], p.arrays)
                        + 3 * p.faces.start for p in batch.parts]
        except gather.UserError as error:
            self.report({'WARNING'}, str(error))
            return None
        pins = np.union1d(batch.pin_corners, np.concatenate(held)).astype(np.int64)
        kwargs = dict(method=self.method, bound=float(self.bound), frames=self.frames)
        state = (batch, pins, batch.initial_uv.reshape(-1, 2)[pins])
        return state, uv_deform.deform_islands, (batch.V, batch.F, batch.initial_uv, pins), kwargs

    def _finish(self, context, state, result, seconds):
        batch, pins, pin_uv = state
        with object_mode(context):
            written, skipped = _write(batch, result)
            checks = _verify(batch, result, written, pins, pin_uv)
        message, level = _summary(batch, result, written, skipped, checks, seconds)
        self.report({level}, message)
        kept = any(w.any() for w in written)
        last = context.window_manager.bd_uv_last_result
        ok = [c for c in checks if c.certified]
        last.valid = kept
        last.method = f"{METHOD_LABELS[result.method]} deform"
        last.islands, last.faces = len(ok), batch.face_count
        last.failed = sum(r.status != "certified" for r in result.islands)
        last.max_distortion = max((c.max_distortion for c in ok), default=0.0)
        last.mean_distortion = 0.0
        last.flipped = sum(c.flipped for c in ok)
        last.bound_certified = result.bound if ok else 0.0
        last.raised = last.overlaps = 0
        last.put_back = sum(not c.certified for c in checks)
        last.seconds = seconds
        last.report = message
        return {'FINISHED'} if kept else {'CANCELLED'}


def _write(batch, result):
    """Write the certified islands (Object Mode); objects changed meanwhile are skipped.

    Returns
    -------
    written : list of (m_i,) bool per part, skipped : list of object names
    """
    ok_island = np.array([r.status == "certified" for r in result.islands], dtype=bool)
    face_ok = ok_island[result.face_island] & np.isfinite(result.corner_uv).all(axis=(1, 2))
    written, skipped = [], []
    for part in batch.parts:
        faces = face_ok[part.faces]
        ob = bpy.data.objects.get(part.object_name)
        now = None if ob is None or ob.type != 'MESH' else mesh_data.mesh_arrays(
            ob, selected_only=True, uv_name=part.arrays.uv_name, scale=part.scale)
        if now is None or now.topology_key != part.arrays.topology_key:
            written.append(np.zeros_like(faces))
            skipped.append(part.object_name)
            continue
        if faces.any():
            mesh_data.write_corner_uvs(ob.data, part.arrays.uv_name, part.arrays.tri_loops,
                                       result.corner_uv[part.faces], faces)
        written.append(faces)
    return written, skipped


def _shared_corners(ob, arrays):
    """(k,) flat corner indices of ``arrays`` (the selected triangles) whose UV vertex (mesh
    vertex and UV) an unselected or hidden face of ``ob`` uses too (Object Mode)."""
    full = mesh_data.mesh_arrays(ob, uv_name=arrays.uv_name)
    other = ~np.isin(full.tri_poly, arrays.tri_poly)
    if not other.any():
        return np.zeros(0, dtype=np.int64)
    mine = np.column_stack([arrays.vertices[arrays.F].reshape(-1),
                            arrays.corner_uv.reshape(-1, 2)])
    theirs = np.column_stack([full.vertices[full.F[other]].reshape(-1),
                              full.corner_uv[other].reshape(-1, 2)])
    _, inverse = np.unique(np.vstack([mine, theirs]), axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    return np.flatnonzero(np.isin(inverse[:len(mine)], inverse[len(mine):])).astype(np.int64)


def _verify(batch, result, written, pins, pin_uv):
    """Certify every written island again from the UVs as stored, against its rest shape, and
    give the failing ones their UVs back (Object Mode).

    ``pins`` (p,) flat corner indices of the batch held where they were, ``pin_uv`` (p,2)
    their UVs: every one must be stored bit for bit.

    Returns
    -------
    list of _Check, one per written island
    """
    stored = np.full_like(result.corner_uv, np.nan)
    labels = np.full(len(batch.F), -1, dtype=np.int64)
    for part, w in zip(batch.parts, written):
        if w.any():
            ob = bpy.data.objects.get(part.object_name)
            uv = mesh_data.loop_uvs(ob.data, part.arrays.uv_name)[part.arrays.tri_loops]
            stored[part.faces] = uv.astype(np.float64)
            labels[part.faces] = np.where(w, result.face_island[part.faces], -1)
    ids = np.unique(labels[labels >= 0])
    if not len(ids):
        return []
    compact = np.searchsorted(ids, labels)
    compact[labels < 0] = -1
    # The rest shape per UV vertex, z = 0: distortion is measured against it.
    cv = result.corner_vertex
    rest = np.zeros((int(cv.max()) + 1, 3))
    on = labels >= 0
    rest[cv[on].ravel(), :2] = result.rest_uv[on].reshape(-1, 2)
    checks = bd_uv.certify_islands(rest, cv, stored, compact, np.full(len(ids), result.bound))
    # Every pinned UV where it was, bit for bit.
    moved = np.zeros(len(ids), dtype=bool)
    pin_faces = pins // 3
    on_pin = compact[pin_faces] >= 0
    off = (stored.reshape(-1, 2)[pins[on_pin]] != pin_uv[on_pin]).any(axis=1)
    moved[compact[pin_faces[on_pin]][off]] = True
    out = []
    for j, c in enumerate(checks):
        out.append(_Check(int(ids[j]), bool(c.certified and not moved[j]),
                          float(c.max_distortion), int(c.flipped),
                          c.reason or ("a pinned UV moved" if moved[j] else "")))
    failed = np.zeros(len(ids) + 1, dtype=bool)
    failed[[j for j, c in enumerate(out) if not c.certified]] = True
    undo = failed[compact]
    for part, w in zip(batch.parts, written):
        mine = undo[part.faces]
        if mine.any():
            ob = bpy.data.objects.get(part.object_name)
            mesh_data.write_corner_uvs(ob.data, part.arrays.uv_name, part.arrays.tri_loops,
                                       part.arrays.corner_uv, mine)
            w &= ~mine
    return out


@dataclass(frozen=True)
class _Check:
    """The post-write check of one island: its index in the result, and what the stored UVs
    prove (distortion against the rest shape)."""

    island: int
    certified: bool
    max_distortion: float
    flipped: int
    reason: str


def _summary(batch, result, written, skipped, checks, seconds):
    """The report line in Blender's terms (islands named by object and counted in polygons)."""
    def name(r):
        where = batch.polygons(r.faces)
        n = sum(len(p) for p in where.values())
        return f"island {r.index} of {', '.join(where)} ({n} face{'s' if n != 1 else ''})"

    label = METHOD_LABELS[result.method]
    ok = [c for c in checks if c.certified]
    back = [c for c in checks if not c.certified]
    parts = []
    if ok:
        worst = max(c.max_distortion for c in ok)
        handles = sum(result.islands[c.island].handles for c in ok)
        parts.append(f"{label} deform: {len(ok)} island{'s' if len(ok) != 1 else ''}, max "
                     f"distortion {_down(worst)} \u2264 {_up(result.bound)} against the current "
                     f"layout, 0 flipped, {handles} handles met, {seconds:.1f} s")
    else:
        parts.append(f"{label} deform: nothing deformed")
    refused = [r for r in result.islands if r.status != "certified"]
    unpinned = [r for r in refused if r.handles < 2]
    if len(unpinned) == 1:
        parts.append(f"{name(unpinned[0])} left as it was: {unpinned[0].message}")
    elif unpinned:  # one clause for them all: selecting every island is common
        listed = ", ".join(str(r.index) for r in unpinned[:8]) + (
            f", ... ({len(unpinned)} in all)" if len(unpinned) > 8 else "")
        parts.append(f"{len(unpinned)} islands with fewer than two pinned UVs left as they were "
                     f"(islands {listed}): pin at least two UVs per island, move them and deform "
                     "again")
    for r in [r for r in refused if r.handles >= 2][:8]:
        text = r.message
        if r.bad_faces is not None and len(r.bad_faces):  # triangles -> Blender's faces
            polys = np.concatenate(list(batch.polygons(r.bad_faces).values()))
            listed = ", ".join(str(int(p)) for p in polys[:8]) + (
                f", ... ({len(polys)} in all)" if len(polys) > 8 else "")
            text = re.sub(r"^\d+ flipped or zero-area faces",
                          f"{len(polys)} flipped or zero-area face{'s' if len(polys) != 1 else ''}"
                          f" (faces {listed})", text)
        parts.append(f"{name(r)} left as it was: {text}")
    for c in back:
        parts.append(f"{name(result.islands[c.island])} put back as it was: its stored UVs fail "
                     f"the certificate ({c.reason})")
    for object_name in skipped:
        parts.append(f"{object_name} not written: changed while solving")
    clean = all(r.status == "certified" for r in result.islands) and not back and not skipped
    level = 'INFO' if ok and clean else 'WARNING'
    return "; ".join(parts), level


classes = (UV_OT_bd_deform,)
