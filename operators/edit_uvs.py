"""UVs of a mesh in Edit Mode through BMesh, for a tool that writes them every frame.

``mesh_data`` works in Object Mode (in Blender 5.0 a mesh in Edit Mode has empty UV collections);
a live tool stays in Edit Mode so the UV editor shows each frame, so it reads and writes the
BMesh's loops. The loops' UVs are float32: what is read is written back bit for bit.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import bmesh

__all__ = ["EditUVs", "read_edit_uvs", "write_loop_uvs"]


@dataclass
class EditUVs:
    """One mesh's triangles and UVs read from its BMesh.

    Attributes
    ----------
    bm : bmesh.types.BMesh (the edit mesh's; valid while Edit Mode lasts)
    layer : the active UV layer
    V : (n,3) float64, F : (m,3) int64, loop triangles (the faces the UV editor shows)
    corner_uv : (m,3,2) float64 (float32 values), pinned, selected : (m,3) bool
    tri_loops : list of (BMLoop, BMLoop, BMLoop), one per row of F
    """
    bm: object
    layer: object
    V: np.ndarray
    F: np.ndarray
    corner_uv: np.ndarray
    pinned: np.ndarray
    selected: np.ndarray
    tri_loops: list


def _uv_selected(loop, layer, sync):
    if sync:
        return loop.vert.select
    if hasattr(loop, "uv_select_vert"):           # Blender 5.0+
        return loop.uv_select_vert
    return loop[layer].select                      # 4.2 to 4.5


def read_edit_uvs(obj, sync):
    """Read the loop triangles the UV editor shows of ``obj`` (a mesh in Edit Mode): the
    selected faces, or with sync selection every visible face.

    Parameters
    ----------
    obj : bpy.types.Object in Edit Mode with a UV map
    sync : bool, UV sync selection (then the mesh selection is the UV selection)

    Returns
    -------
    EditUVs, or None when the mesh has no UV map
    """
    bm = bmesh.from_edit_mesh(obj.data)
    layer = bm.loops.layers.uv.active
    if layer is None:
        return None
    bm.verts.ensure_lookup_table()
    V = np.array([v.co[:] for v in bm.verts], dtype=np.float64).reshape(-1, 3)
    # The UV editor shows the selected faces, or every visible face with sync selection.
    tri_loops = [t for t in bm.calc_loop_triangles()
                 if not t[0].face.hide and (sync or t[0].face.select)]
    F = np.array([[lp.vert.index for lp in t] for t in tri_loops], dtype=np.int64).reshape(-1, 3)
    uv = np.array([[lp[layer].uv[:] for lp in t] for t in tri_loops],
                  dtype=np.float32).reshape(-1, 3, 2).astype(np.float64)
    pinned = np.array([[lp[layer].pin_uv for lp in t] for t in tri_loops],
                      dtype=bool).reshape(-1, 3)
    selected = np.array([[_uv_selected(lp, layer, sync) for lp in t] for t in tri_loops],
                        dtype=bool).reshape(-1, 3)
    return EditUVs(bm, layer, V, F, uv, pinned, selected, tri_loops)


def write_loop_uvs(obj, data, faces, corner_uv):
    """Write ``corner_uv`` (k,3,2) to the loops of the triangles ``faces`` (k,) of ``data`` and
    refresh the edit mesh (the UV editor redraws it)."""
    layer = data.layer
    values = np.asarray(corner_uv, dtype=np.float64).reshape(-1, 3, 2).tolist()
    for f, uvs in zip(faces.tolist(), values):
        for lp, uv in zip(data.tri_loops[f], uvs):
            lp[layer].uv = uv
    bmesh.update_edit_mesh(obj.data, loop_triangles=False, destructive=False)
