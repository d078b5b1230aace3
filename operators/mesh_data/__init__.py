"""The one place where Blender mesh data becomes numpy arrays and back.

Everything goes through exact-dtype ``foreach_get`` / ``foreach_set`` (float32 positions and UVs,
int32 indices, bool flags); there is no Python loop over vertices, faces or loops. The rest of the
add-on (operators, the batch tool) works on the arrays only.

Both directions need the mesh outside Edit Mode (they raise otherwise): in Edit Mode the UV and
attribute layers live in the edit-mesh and their ``Mesh`` collections are empty, and loops written
to the ``Mesh`` would be overwritten from the edit-mesh when leaving Edit Mode. The operators leave
Edit Mode around these calls (``operators/editmode.py``).

- ``arrays``: the arrays an unwrap reads and the UVs it writes;
- ``edits``: the selection, seams and positions the operators set, and what they read per
  polygon.
"""
from .arrays import (MeshArrays, face_mask_of_polygons, loop_uvs, mesh_arrays, uv_selection,
                     write_corner_uvs)
from .edits import (mark_seams, polygon_materials, polygon_sizes, select_polygons, selection,
                    set_selection, set_vertex_positions, vertex_positions, vertices_of_polygons)

__all__ = [
    "MeshArrays",
    "mesh_arrays",
    "write_corner_uvs",
    "loop_uvs",
    "uv_selection",
    "face_mask_of_polygons",
    "selection",
    "set_selection",
    "select_polygons",
    "mark_seams",
    "vertex_positions",
    "set_vertex_positions",
    "polygon_materials",
    "polygon_sizes",
    "vertices_of_polygons",
]
