"""What the operators read and set on a mesh besides its UVs: the selection, seams, vertex
positions, and per polygon its material and corner count."""
import numpy as np

from .arrays import _get, _require_object_mode


def selection(mesh):
    """Selection flags of ``mesh`` (Object Mode).

    Returns
    -------
    vert : (n,) bool, edge : (e,) bool, poly : (P,) bool
    """
    _require_object_mode(mesh)
    return (_get(mesh.vertices, "select", bool, len(mesh.vertices)),
            _get(mesh.edges, "select", bool, len(mesh.edges)),
            _get(mesh.polygons, "select", bool, len(mesh.polygons)))


def set_selection(mesh, vert, edge, poly):
    """Set the selection flags of ``mesh`` (Object Mode), as returned by :func:`selection`."""
    _require_object_mode(mesh)
    mesh.vertices.foreach_set("select", np.asarray(vert, dtype=bool))
    mesh.edges.foreach_set("select", np.asarray(edge, dtype=bool))
    mesh.polygons.foreach_set("select", np.asarray(poly, dtype=bool))
    mesh.update()


def select_polygons(mesh, poly_mask, select_mode=(False, False, True)):
    """Select the polygons in the (P,) bool ``poly_mask``, with their edges and vertices, as
    Blender's Edit Mode will show them in ``select_mode`` (the tool settings' vertex, edge, face
    flags).

    In vertex select mode Edit Mode also selects every other visible face whose vertices are all
    selected (in edge select mode: whose edges are), as its own selection tools do; those faces
    are selected here too, so the returned mask is what the user sees.

    Returns
    -------
    (P,) bool
        The polygons selected.
    """
    _require_object_mode(mesh)
    poly_mask = np.asarray(poly_mask, dtype=bool)
    n_poly = len(mesh.polygons)
    total = _get(mesh.polygons, "loop_total", np.int32, n_poly)
    loop_selected = np.repeat(poly_mask, total)
    loop_vert = _get(mesh.loops, "vertex_index", np.int32, len(mesh.loops))
    loop_edge = _get(mesh.loops, "edge_index", np.int32, len(mesh.loops))
    vert = np.zeros(len(mesh.vertices), dtype=bool)
    vert[loop_vert[loop_selected]] = True
    edge = np.zeros(len(mesh.edges), dtype=bool)
    edge[loop_edge[loop_selected]] = True
    if n_poly and (select_mode[0] or select_mode[1]):  # vertex mode wins when several are on
        start = _get(mesh.polygons, "loop_start", np.int32, n_poly)
        order = np.argsort(start, kind="stable")
        # Loops of one polygon are contiguous from its loop_start.
        flag = vert[loop_vert] if select_mode[0] else edge[loop_edge]
        closed = np.zeros(n_poly, dtype=bool)
        closed[order] = np.logical_and.reduceat(flag, start[order]) & (total[order] > 0)
        hidden = _get(mesh.polygons, "hide", bool, n_poly)
        poly_mask = poly_mask | (closed & ~hidden)
        if select_mode[0]:
            edge = edge | (vert[_get(mesh.edges, "vertices", np.int32, len(mesh.edges),
                                     2)].all(axis=1))
    set_selection(mesh, vert, edge, poly_mask)
    return poly_mask


def mark_seams(mesh, vertex_pairs):
    """Mark the edges joining the (k,2) Blender vertex pairs as seams (Object Mode).

    Pairs that are no edge of ``mesh`` are left out (never a polygon's diagonal). One bulk
    ``foreach_get`` / ``foreach_set`` of ``use_seam``.

    Returns
    -------
    (e,) bool
        The edges that were not seams before and are now.
    """
    _require_object_mode(mesh)
    n_edge, n = len(mesh.edges), max(len(mesh.vertices), 1)
    pairs = np.sort(np.asarray(vertex_pairs, dtype=np.int64).reshape(-1, 2), axis=1)
    ends = np.sort(_get(mesh.edges, "vertices", np.int32, n_edge, 2).astype(np.int64), axis=1)
    seam = _get(mesh.edges, "use_seam", bool, n_edge)
    hit = np.isin(ends[:, 0] * n + ends[:, 1], pairs[:, 0] * n + pairs[:, 1])
    new = hit & ~seam
    if new.any():
        mesh.edges.foreach_set("use_seam", seam | hit)
        mesh.update()
    return new


def vertex_positions(mesh):
    """(n,3) float32 positions of every vertex of ``mesh`` (Object Mode)."""
    _require_object_mode(mesh)
    return _get(mesh.vertices, "co", np.float32, len(mesh.vertices), 3)


def set_vertex_positions(mesh, vertices, co):
    """Set the positions of the (k,) Blender ``vertices`` to (k,3) ``co`` (stored as float32);
    every other vertex keeps its position bit for bit (Object Mode)."""
    _require_object_mode(mesh)
    all_co = vertex_positions(mesh)
    all_co[np.asarray(vertices, dtype=np.int64)] = np.asarray(co, dtype=np.float64).reshape(-1, 3)
    mesh.vertices.foreach_set("co", all_co.ravel())
    mesh.update()


def polygon_materials(ob):
    """Each polygon's material: (P,) int64 index into the returned names (the material in the
    polygon's slot; None for an empty slot or no slots; an index past the last slot reads the last
    one, as Blender draws it)."""
    me = ob.data
    index = _get(me.polygons, "material_index", np.int32, len(me.polygons)).astype(np.int64)
    names = [s.material.name if s.material is not None else None for s in ob.material_slots]
    names = names or [None]
    return np.clip(index, 0, len(names) - 1), names


def polygon_sizes(mesh):
    """(P,) int: corners of each polygon (3 for a triangle)."""
    return _get(mesh.polygons, "loop_total", np.int32, len(mesh.polygons)).astype(np.int64)


def vertices_of_polygons(mesh, poly_mask):
    """(n,) bool: vertices used by a polygon in the (P,) bool ``poly_mask`` (Object Mode)."""
    _require_object_mode(mesh)
    loop_vert = _get(mesh.loops, "vertex_index", np.int32, len(mesh.loops))
    out = np.zeros(len(mesh.vertices), dtype=bool)
    out[loop_vert[np.repeat(np.asarray(poly_mask, bool), polygon_sizes(mesh))]] = True
    return out
