"""Checking: every written island certified again from the UVs as stored (float32, packed);
those that fail get their previous UVs back."""
from __future__ import annotations

from dataclasses import dataclass, field

import bpy
import numpy as np

from ..bd_uv.certificate import Certificate
from . import mesh_data, stored


@dataclass(frozen=True)
class Checked:
    """The post-write check of one written island (``bd_uv.Certificate`` of its stored UVs) and
    its owner."""

    object_name: str
    polygons: int              # its faces as the user counts them
    area: float                # 3D area (weights the mean)
    stored: Certificate        # of the UVs as stored (stored.check_stored)
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


def _normalized(part, islands, n):
    """(n,) bool: islands with fewer than two pinned vertices in ``part`` (the core scales those
    to their 3D area and measures their stretch at that scale)."""
    corners = part.arrays.pin_corners
    pairs = np.unique(np.stack([islands[corners // 3], part.arrays.F.ravel()[corners]], 1),
                      axis=0).reshape(-1, 2)
    return np.bincount(pairs[:, 0], minlength=n) < 2


def verify_written(batch, result, written, stretch=None):
    """Re-certify what is stored now (float32 UVs, after packing) and put back what fails.

    Each written island is certified again from the UV map as Blender holds it, with its own
    bound, by :func:`stored.check_stored` (the core's one certificate). An island that fails
    gets its previous UVs back; on a mesh that had no UV map the created map is removed when
    nothing is left on it. Object Mode. With ``stretch`` (Limit Stretch) an island is kept only
    with every face's singular values in [1/S, S] as stored.

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
        n = len(result.islands)
        checks = stored.check_stored(part.arrays.V, part.arrays.F, uv, labels, result.islands,
                                     solved_uv=result.corner_uv[part.faces], stretch=stretch,
                                     normalized=_normalized(part, islands, n))
        P = part.arrays.V[part.arrays.F]
        area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
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
