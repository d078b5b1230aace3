"""Checking: every written island certified again from the UVs as stored (float32, packed);
those that fail get their previous UVs back."""
from __future__ import annotations

import dataclasses
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
    moved_tiles: int = 0       # put back moved right by this many whole tiles, off the atlas


@dataclass
class Verified:
    """What :func:`verify_written` found: every written island as stored, and the overlaps
    between islands of each object's stored layout."""

    islands: list                                   # of Checked
    overlaps: dict = field(default_factory=dict)    # object name -> island pairs (k,2), or None
    moved: dict = field(default_factory=dict)       # object name -> whole tiles its faces not
                                                    # written (new map) were moved right by


def _restore(ob, part, w, undo):
    """Give the triangles ``undo`` (m_i,) bool of ``part`` back the UVs they had; remove the map
    ``write_back`` created when nothing written is left on it.

    When the UVs put back would lie over the islands kept (a new map's default squares, or old
    UVs under the packed atlas) they go back moved right by whole tiles, beside the atlas.

    Returns
    -------
    int, the whole tiles the UVs put back were moved right by (0: exactly as they were)
    """
    mesh = ob.data
    kept = w.faces & ~undo
    name = w.created_map or part.arrays.uv_name
    if w.created_map:
        layer = mesh.uv_layers.get(w.created_map)
        if layer is None:
            return 0
        if not kept.any():
            mesh.uv_layers.remove(layer)
            mesh.update()
            return 0
    now = mesh_data.loop_uvs(mesh, name)
    back = part.arrays.tri_loops[undo].ravel()
    old = (w.initial_uv[back] if w.created_map
           else np.asarray(part.arrays.corner_uv, np.float64)[undo].reshape(-1, 2))
    tiles = stored.tiles_off(now[part.arrays.tri_loops[kept].ravel()], old)
    if not w.created_map:
        shifted = np.asarray(part.arrays.corner_uv, np.float64) + np.array([tiles, 0.0])
        mesh_data.write_corner_uvs(mesh, part.arrays.uv_name, part.arrays.tri_loops,
                                   shifted if tiles else part.arrays.corner_uv, undo)
        return tiles
    now[back] = old + np.array([tiles, 0.0], dtype=now.dtype)
    layer.uv.foreach_set("vector", now.ravel())
    mesh.update()
    return tiles


def _twins(result, part):
    """(m_i,) int64: for each triangle of ``part`` left out of the solve as a duplicate
    (``UnwrapResult.duplicate_of``), its twin's index in ``part``; -1 for the others."""
    m = part.faces.stop - part.faces.start
    dup_of = getattr(result, "duplicate_of", None)
    if dup_of is None:
        return np.full(m, -1, dtype=np.int64)
    twin = np.asarray(dup_of, dtype=np.int64)[part.faces]
    return np.where(twin >= 0, twin - part.faces.start, -1)


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
    checked, overlaps, moved = [], {}, {}
    for part, w in zip(batch.parts, written):
        if w.skipped or not w.faces.any():
            continue
        never = ~w.faces          # not written at all (failed islands, zero-area faces)
        ob = bpy.data.objects.get(part.object_name)
        uv_name = w.created_map or part.arrays.uv_name
        uv = mesh_data.loop_uvs(ob.data, uv_name)[part.arrays.tri_loops].astype(np.float64)
        islands = result.face_island[part.faces]
        twin = _twins(result, part)
        dup = twin >= 0      # duplicate faces: stored with their twin's UVs, checked through it
        labels = np.where(w.faces & ~dup, islands, -1)
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
        undo[dup] = undo[twin[dup]] & w.faces[dup]   # a duplicate goes back with its twin
        checked.extend(Checked(part.object_name, int(island_polygons[c.island]),
                               float(island_area[c.island]), c, not c.certified)
                       for c in checks)
        if undo.any():
            tiles = _restore(ob, part, w, undo)
            if tiles:
                checked[-len(checks):] = [dataclasses.replace(c, moved_tiles=tiles)
                                          if c.put_back else c for c in checked[-len(checks):]]
            w.faces = w.faces & ~undo
            labels = np.where(w.faces & ~dup, islands, -1)
        if w.created_map and w.faces.any() and never.any():
            tiles = _move_off_atlas(ob.data, w, part, never)
            if tiles:
                moved[part.object_name] = tiles
        if len(np.unique(labels[labels >= 0])) > 1:
            overlaps[part.object_name] = stored.layout_overlaps(uv, labels, part.arrays.F)
    return Verified(checked, overlaps, moved)


def _move_off_atlas(mesh, w, part, never):
    """On a map ``write_back`` created, the triangles ``never`` (m_i,) bool that were not
    written hold the new map's default squares, all over the written islands: move their loops
    (those no written triangle shares) right by whole tiles (``stored.tiles_off``).

    Returns
    -------
    int, the tiles moved (0: nothing lay over the written islands)
    """
    uv = mesh_data.loop_uvs(mesh, w.created_map)
    kept = part.arrays.tri_loops[w.faces].ravel()
    back = np.setdiff1d(part.arrays.tri_loops[never].ravel(), kept)
    tiles = stored.tiles_off(uv[kept], uv[back])
    if tiles:
        uv[back] += np.array([tiles, 0.0], dtype=uv.dtype)
        mesh.uv_layers[w.created_map].uv.foreach_set("vector", uv.ravel())
        mesh.update()
    return tiles
