"""A mesh's arrays read for an unwrap (``mesh_arrays``: positions, triangles, seams, pins, the UV
map per corner, each triangle's polygon and loops) and UVs written back (``write_corner_uvs``)."""
from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

import bpy


@dataclass(frozen=True)
class MeshArrays:
    """Triangulated copy of a Blender mesh, ready for ``bd_uv.unwrap``.

    Attributes
    ----------
    V : (n,3) float64
        Positions (object scale applied) of the vertices used by ``F``.
    F : (m,3) int64
        Triangles from ``mesh.loop_triangles`` (quads and n-gons triangulated by Blender), indices
        into ``V``.
    tri_loops : (m,3) int64
        Blender loop index of each triangle corner.
    tri_poly : (m,) int64
        Blender polygon index of each triangle.
    seams : (s,2) int64
        Vertex pairs (into ``V``) of the edges marked as seams that are edges of ``F``.
    corner_uv : (m,3,2) float64 or None
        UV of each triangle corner from the UV map (None when the mesh has no UV map).
    pin_corners : (p,) int64
        Flat corner indices (``3*face + corner``) whose UV must stay: pinned loops, and with
        ``pin_unselected_uvs`` the unselected UVs of the selected faces.
    pin_uv : (p,2) float64
        The UV of each pinned corner (exactly the stored float32 values).
    vertices : (n,) int64
        Blender vertex index of each row of ``V``.
    uv_name : str or None
        The UV map read (None when the mesh has none).
    topology_key : tuple
        Fingerprint of everything the solve depends on (counts, connectivity, positions, seams,
        selection, UVs and pins); compare before writing back.
    material : (m,) int64 or None
        Material slot index of each triangle's polygon (automatic seams prefer material
        boundaries).
    """

    V: np.ndarray
    F: np.ndarray
    tri_loops: np.ndarray
    tri_poly: np.ndarray
    seams: np.ndarray
    corner_uv: np.ndarray | None
    pin_corners: np.ndarray
    pin_uv: np.ndarray
    vertices: np.ndarray
    uv_name: str | None
    topology_key: tuple
    material: np.ndarray | None = None


def _get(collection, attr, dtype, count, width=1):
    """``collection.foreach_get(attr)`` into a fresh array of the exact dtype, shape (count, width)."""
    out = np.empty(count * width, dtype=dtype)
    if count:
        collection.foreach_get(attr, out)
    return out.reshape(count, width) if width > 1 else out


def _mesh_of(obj_or_mesh):
    if isinstance(obj_or_mesh, bpy.types.Object):
        if obj_or_mesh.type != 'MESH':
            raise TypeError(f"{obj_or_mesh.name!r} is not a mesh object")
        mesh = obj_or_mesh.data
    elif isinstance(obj_or_mesh, bpy.types.Mesh):
        mesh = obj_or_mesh
    else:
        raise TypeError(f"expected a mesh object or a Mesh, got {type(obj_or_mesh).__name__}")
    _require_object_mode(mesh)
    return mesh


def _require_object_mode(mesh):
    if mesh.is_editmode:
        raise RuntimeError(f"mesh {mesh.name!r} is in Edit Mode; leave it first (its UV layers "
                           "cannot be read or written in bulk there)")


def _uv_layer(mesh, uv_name):
    if uv_name is None:
        return mesh.uv_layers.active
    return mesh.uv_layers.get(uv_name)


def loop_uvs(mesh, uv_name=None):
    """UV of every loop of ``mesh``.

    Returns
    -------
    uv : (L,2) float32 or None
        None when the mesh has no such UV map.
    """
    layer = _uv_layer(mesh, uv_name)
    if layer is None:
        return None
    return _get(layer.uv, "vector", np.float32, len(mesh.loops), 2)


def _loop_pins(mesh, layer):
    """(L,) bool: loops pinned in ``layer`` (all False when the layer has no pin data)."""
    if len(layer.pin) != len(mesh.loops):
        return np.zeros(len(mesh.loops), dtype=bool)
    return _get(layer.pin, "value", bool, len(mesh.loops))


def uv_selection(mesh, layer=None):
    """(L,) bool: loops whose UV vertex is selected in the UV editor (all True when unknown).

    Blender 5.0 stores this as the mesh attribute ``.uv_select_vert``; 4.x per UV map as
    ``MeshUVLoopLayer.vertex_selection``.
    """
    n = len(mesh.loops)
    seq = getattr(layer, "vertex_selection", None) if layer is not None else None
    if seq is None:
        attr = mesh.attributes.get(".uv_select_vert")
        seq = attr.data if attr is not None and attr.domain == 'CORNER' else None
    if seq is None or len(seq) != n:
        return np.ones(n, dtype=bool)
    return _get(seq, "value", bool, n)


def face_mask_of_polygons(tri_poly, poly_mask):
    """(m,) bool: triangles whose polygon is in the (P,) bool ``poly_mask``."""
    return np.asarray(poly_mask, dtype=bool)[np.asarray(tri_poly, dtype=np.int64)]


def _digest(*arrays):
    h = hashlib.blake2b(digest_size=16)
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(str((a.dtype.str, a.shape)).encode())
        h.update(a.tobytes())
    return h.hexdigest()


def mesh_arrays(obj_or_mesh, *, selected_only=False, uv_name=None, scale=(1.0, 1.0, 1.0),
                pin_unselected_uvs=False):
    """Triangles, seams, UVs and pins of a Blender mesh as arrays.

    Parameters
    ----------
    obj_or_mesh : bpy.types.Object or bpy.types.Mesh
        Not in Edit Mode.
    selected_only : bool
        Keep only the triangles of selected, visible polygons.
    uv_name : str, optional
        UV map to read; the active one by default.
    scale : (3,) float
        Multiplies the positions (pass ``obj.scale`` to unwrap the object as it looks).
    pin_unselected_uvs : bool
        Also pin the corners whose UV is not selected (Blender's unwrap from the UV editor
        without sync selection).

    Returns
    -------
    MeshArrays
    """
    mesh = _mesh_of(obj_or_mesh)
    mesh.calc_loop_triangles()
    n_vert, n_edge = len(mesh.vertices), len(mesh.edges)
    n_loop, n_poly, n_tri = len(mesh.loops), len(mesh.polygons), len(mesh.loop_triangles)

    co = _get(mesh.vertices, "co", np.float32, n_vert, 3)
    tri_vert = _get(mesh.loop_triangles, "vertices", np.int32, n_tri, 3).astype(np.int64)
    tri_loops = _get(mesh.loop_triangles, "loops", np.int32, n_tri, 3).astype(np.int64)
    tri_poly = _get(mesh.loop_triangles, "polygon_index", np.int32, n_tri).astype(np.int64)
    edge_vert = _get(mesh.edges, "vertices", np.int32, n_edge, 2).astype(np.int64)
    seam = _get(mesh.edges, "use_seam", bool, n_edge)
    loop_vert = _get(mesh.loops, "vertex_index", np.int32, n_loop)
    poly_select = _get(mesh.polygons, "select", bool, n_poly)
    poly_hide = _get(mesh.polygons, "hide", bool, n_poly)
    poly_material = _get(mesh.polygons, "material_index", np.int32, n_poly).astype(np.int64)

    if selected_only:
        keep = face_mask_of_polygons(tri_poly, poly_select & ~poly_hide)
        tri_vert, tri_loops, tri_poly = tri_vert[keep], tri_loops[keep], tri_poly[keep]

    # Compact the vertices to those the triangles use (loose and unselected ones drop out).
    used = np.zeros(n_vert, dtype=bool)
    used[tri_vert.ravel()] = True
    vertices = np.flatnonzero(used).astype(np.int64)
    new_index = np.full(n_vert, -1, dtype=np.int64)
    new_index[vertices] = np.arange(len(vertices), dtype=np.int64)
    F = new_index[tri_vert].reshape(-1, 3)
    V = co[vertices].astype(np.float64) * np.asarray(scale, dtype=np.float64).reshape(1, 3)

    # Seams: marked edges that are edges of the kept triangles (never an n-gon's diagonal).
    s = np.sort(new_index[edge_vert[seam]], axis=1)
    s = s[(s >= 0).all(axis=1)]
    n = max(len(vertices), 1)
    tri_edges = np.sort(F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    s = s[np.isin(s[:, 0] * n + s[:, 1], tri_edges[:, 0] * n + tri_edges[:, 1])]
    seams = np.unique(s, axis=0).astype(np.int64).reshape(-1, 2)

    layer = _uv_layer(mesh, uv_name)
    if layer is None:
        corner_uv = None
        pin_corners = np.zeros(0, dtype=np.int64)
        pin_uv = np.zeros((0, 2), dtype=np.float64)
        uv_all = pins = np.zeros(0, dtype=np.float32)
        layer_name = None
    else:
        layer_name = layer.name
        uv_all = loop_uvs(mesh, layer_name)
        corner_uv = uv_all[tri_loops].astype(np.float64)
        pins = _loop_pins(mesh, layer)
        if pin_unselected_uvs:
            pins = pins | ~uv_selection(mesh, layer)
        pin_corners = np.flatnonzero(pins[tri_loops].ravel()).astype(np.int64)
        pin_uv = corner_uv.reshape(-1, 2)[pin_corners]

    key = (
        mesh.name, n_vert, n_edge, n_loop, n_poly, layer_name,
        _digest(co, loop_vert, tri_loops, edge_vert, seam, poly_select, poly_hide, uv_all, pins,
                np.asarray(scale, dtype=np.float64)),
    )
    return MeshArrays(V=V, F=F, tri_loops=tri_loops, tri_poly=tri_poly, seams=seams,
                      corner_uv=corner_uv, pin_corners=pin_corners, pin_uv=pin_uv,
                      vertices=vertices, uv_name=layer_name, topology_key=key,
                      material=poly_material[tri_poly])


def write_corner_uvs(mesh, uv_name, tri_loops, corner_uv, face_mask):
    """Write per-corner UVs of the masked triangles into a UV map.

    Parameters
    ----------
    mesh : bpy.types.Mesh
        Not in Edit Mode.
    uv_name : str or None
        UV map to write; None means the active one. A missing map is created (and made active
        when it is the mesh's first).
    tri_loops : (m,3) int
        Blender loop index of each triangle corner (``MeshArrays.tri_loops``).
    corner_uv : (m,3,2) float
        New UV of each corner; rows with non-finite values are never written.
    face_mask : (m,) bool
        Triangles to write; the loops of the other triangles keep their UVs bit for bit.

    Returns
    -------
    name : str
        The UV map written.
    """
    _require_object_mode(mesh)
    tri_loops = np.asarray(tri_loops, dtype=np.int64).reshape(-1, 3)
    corner_uv = np.asarray(corner_uv, dtype=np.float64).reshape(-1, 3, 2)
    mask = np.asarray(face_mask, dtype=bool) & np.isfinite(corner_uv).all(axis=(1, 2))
    layer = _uv_layer(mesh, uv_name)
    if layer is None:
        layer = mesh.uv_layers.new(name=uv_name or "UVMap")
        if layer is None:
            raise RuntimeError(f"cannot add a UV map to {mesh.name!r}")
    uv = loop_uvs(mesh, layer.name)
    uv[tri_loops[mask].ravel()] = corner_uv[mask].reshape(-1, 2).astype(np.float32)
    layer.uv.foreach_set("vector", uv.ravel())
    mesh.update()
    return layer.name
