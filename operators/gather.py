"""Reading: the selected faces of every mesh in Edit Mode copied into one problem.

``gather`` concatenates every object's selected faces (islands never span objects, so one
``bd_uv.unwrap`` call solves them all); ``unwrap_arguments`` and ``auto_arguments`` turn the batch
into the core's arguments.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..bd_uv.errors import OptionError
from ..bd_uv.options import UnwrapOptions
from ..bd_uv.repair import stored_precision
from . import mesh_data


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
    tri_polygons: np.ndarray = field(default=None)  # (m,) polygon per triangle, unique over parts

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
    polygons, offset = [], 0
    for part in parts:
        polygons.append(part.arrays.tri_poly + offset)
        offset += int(part.arrays.tri_poly.max()) + 1
    return Batch(parts, V, F, np.concatenate(seams).reshape(-1, 2),
                 np.concatenate(pins), np.concatenate(pin_uv).reshape(-1, 2),
                 np.concatenate(uvs) if need_uvs else None, areas, np.concatenate(polygons))


def unwrap_arguments(batch, *, method, bound, minimise, raise_bound, bound_limit, frames,
                     overlap="cut", boundary="free", stretch=None):
    """Positional and keyword arguments of ``bd_uv.unwrap`` for ``batch`` (``stretch`` S: Limit
    Stretch, singular values within [1/S, S]): the mesh's data and its ``UnwrapOptions``.
    Blender stores positions in float32: faces it cannot tell from a line, side by side, refuse
    their island at once as zero-area faces (``precision``), not after minutes of solves that
    cannot certify it as stored.

    Raises
    ------
    UserError naming an option that cannot be used (``bd_uv.OptionError``)
    """
    options = _options(method=method, bound="auto" if minimise else float(bound), frames=frames,
                       raise_bound=bool(raise_bound), bound_limit=float(bound_limit),
                       overlap=overlap, boundary=boundary,
                       stretch=None if stretch is None else float(stretch))
    kwargs = dict(seams=batch.seams, options=options,
                  face_groups=batch.tri_polygons,  # an overlap cut never splits a polygon
                  precision=stored_precision(batch.V, batch.F, np.float32))
    if len(batch.pin_corners):
        kwargs.update(pin_corners=batch.pin_corners, pin_uv=batch.pin_uv)
    if frames == "input-uv":
        kwargs["initial_uv"] = batch.initial_uv
    return (batch.V, batch.F), kwargs


def polygon_ids(batch):
    """``tri_poly`` (m,) and ``tri_loops`` (m,3): each triangle's polygon and each corner's loop,
    numbered over the whole batch (objects one after another)."""
    tri_loops, offset = [], 0
    for part in batch.parts:
        tri_loops.append(part.arrays.tri_loops + offset)
        offset += int(part.arrays.tri_loops.max()) + 1
    return dict(tri_poly=batch.tri_polygons, tri_loops=np.concatenate(tri_loops))


def auto_arguments(batch, *, method, bound, minimise, stretch, frames, atlas_cuts=True):
    """Positional and keyword arguments of ``needed_seams.auto_repaired`` (Seams "Add
    Automatically"); ``atlas_cuts`` as ``UnwrapOptions.atlas_cuts`` (the operator's Atlas Cuts).
    Blender stores positions in float32: where faces it cannot tell from a line lie side by
    side, ``precision`` is float32 and the repair leaves them out as zero-area before the
    search (kept, their chart failed as stored or they were written unnamed).

    Raises
    ------
    UserError for what the automatic seams cannot do yet: Minimise (it needs a numeric C),
    From Current UVs, pinned UVs (its charts are not known before it runs, so it cannot keep
    pins in place).
    """
    if minimise:
        raise UserError("Add Where Needed seams need a bound C: turn off Minimise (or mark the "
                        "seams and minimise then)")
    if frames == "input-uv":
        raise UserError("Add Where Needed seams start from the conformal map: set Frames to "
                        "Auto (or mark the seams and unwrap From Current UVs)")
    if len(batch.pin_corners):
        raise UserError("Add Where Needed seams cannot keep pinned UVs in place: unpin them, "
                        "unwrap with Sync Selection on or from the 3D Viewport, or mark the "
                        "seams yourself")
    options = _options(seams_mode="auto", method=method, bound=float(bound),
                       stretch=float(stretch), frames=frames, atlas_cuts=bool(atlas_cuts))
    material = np.concatenate([p.arrays.material for p in batch.parts])
    kwargs = dict(**polygon_ids(batch),
                  face_groups=material if len(np.unique(material)) > 1 else None,
                  seams=batch.seams, method=options.method, bound=options.bound,
                  stretch=options.seams_stretch, frames=options.frames,
                  atlas_cuts=options.atlas_cuts,
                  precision=stored_precision(batch.V, batch.F, np.float32))
    return (batch.V, batch.F), kwargs


def needed_arguments(batch, *, method, bound, stretch, frames, overlap, limit_stretch,
                     atlas_cuts=True, minimise=False):
    """Positional and keyword arguments of :func:`needed_seams.solve` (Seams "Add Where
    Needed"): those of :func:`auto_arguments`, the Overlaps choice for the marked islands and,
    with Limit Stretch, its S for them too; with Minimise the bound "auto". Blender stores
    positions in float32: faces it cannot tell from a line, side by side, are left out as
    zero-area (``precision``; they fail their island as stored at any stretch, and trying costs
    minutes on OpenChessSet's bishops)."""
    args, kwargs = auto_arguments(batch, method=method, bound=bound, minimise=False,
                                  stretch=stretch, frames=frames, atlas_cuts=atlas_cuts)
    kwargs["overlap"] = overlap
    if minimise:        # each island and chart at its least C (``needed_seams.solve``)
        kwargs["bound"] = "auto"
    if limit_stretch:
        kwargs["marked_stretch"] = float(stretch)
    return args, kwargs


def _options(**values):
    """``UnwrapOptions(**values)``; an option out of range becomes a UserError naming it."""
    try:
        return UnwrapOptions(**values)
    except OptionError as exc:
        raise UserError(f"{exc.option}: {exc}") from None
