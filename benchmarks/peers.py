"""The unwrappers bd-uv is compared with: Blender's own (through the bpy module) and libigl's SLIM.

Each function takes ``V`` (n,3) float64 and ``F`` (m,3) int64 and returns ``(corner_uv, seconds,
note)`` with ``corner_uv`` (m,3,2) float64 in the order of ``F``. ``seconds`` covers only the
method's own work, as described per function; building inputs and reading results back is not timed.
"""
from __future__ import annotations

import time

import numpy as np

BLENDER_METHODS = {
    "blender-abf": "ANGLE_BASED",
    "blender-lscm": "CONFORMAL",
    "blender-minstretch": "MINIMUM_STRETCH",
}

_bpy_ready = False


def _bpy_setup():
    """Import bpy once, start from an empty scene and warm the unwrap operator up (untimed)."""
    global _bpy_ready
    import bpy

    if not _bpy_ready:
        bpy.ops.wm.read_factory_settings(use_empty=True)
        _bpy_ready = True
        V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.2]], dtype=np.float64)
        F = np.array([[0, 1, 2], [1, 3, 2]], dtype=np.int64)
        for method in BLENDER_METHODS.values():
            blender_unwrap(V, F, method)
    return bpy


def blender_unwrap(V: np.ndarray, F: np.ndarray, method: str) -> tuple[np.ndarray, float, str]:
    """Unwrap with ``bpy.ops.uv.unwrap(method=method, margin=0)`` on the whole mesh.

    The mesh is built with ``from_pydata`` (no seams: a disk is one chart), linked to an empty
    scene, put in edit mode with every face selected. Only the operator call is timed (it includes
    Blender's own island packing into the unit square, a uniform scale and translation that does
    not change conformal distortion). Other operator options keep their defaults
    (``fill_holes=False``, ``no_flip=False``, ``iterations=10`` for Minimum Stretch).

    Parameters
    ----------
    V : (n,3) float64
    F : (m,3) int64
    method : str
        ``"ANGLE_BASED"``, ``"CONFORMAL"`` or ``"MINIMUM_STRETCH"``.

    Returns
    -------
    corner_uv : (m,3,2) float64
    seconds : float
    note : str
    """
    return blender_operator(V, F, lambda bpy: bpy.ops.uv.unwrap(method=method, margin=0.0))


def blender_operator(V: np.ndarray, F: np.ndarray, operator) -> tuple[np.ndarray, float, str]:
    """Run one UV operator of Blender's on the mesh (every face selected, edit mode); only the
    call ``operator(bpy)`` is timed. Returns (corner_uv (m,3,2) float64, seconds, note)."""
    bpy = _bpy_setup()
    mesh = bpy.data.meshes.new("bench")
    mesh.from_pydata(V.tolist(), [], F.tolist())
    mesh.update()
    obj = bpy.data.objects.new("bench", mesh)
    bpy.context.scene.collection.objects.link(obj)
    try:
        bpy.context.view_layer.update()
        for other in bpy.context.scene.objects:
            other.select_set(other == obj)
        bpy.context.view_layer.objects.active = obj
        mesh.uv_layers.new(name="UVMap")
        bpy.ops.object.mode_set(mode="EDIT")
        bpy.ops.mesh.select_all(action="SELECT")
        t0 = time.perf_counter()
        result = operator(bpy)
        seconds = time.perf_counter() - t0
        bpy.ops.object.mode_set(mode="OBJECT")
        if result != {"FINISHED"}:
            raise RuntimeError(f"the Blender operator returned {result}")

        nl, npoly = len(mesh.loops), len(mesh.polygons)
        if npoly != len(F):
            raise RuntimeError(f"Blender built {npoly} polygons from {len(F)} triangles")
        loop_uv = np.empty(2 * nl, dtype=np.float32)
        mesh.uv_layers["UVMap"].data.foreach_get("uv", loop_uv)
        loop_vert = np.empty(nl, dtype=np.int32)
        mesh.loops.foreach_get("vertex_index", loop_vert)
        loop_start = np.empty(npoly, dtype=np.int32)
        mesh.polygons.foreach_get("loop_start", loop_start)
        corners = loop_start[:, None] + np.arange(3)[None, :]
        if not np.array_equal(loop_vert[corners], F):
            raise RuntimeError("Blender reordered the triangles' corners")
        corner_uv = loop_uv.reshape(-1, 2).astype(np.float64)[corners]
        return corner_uv, seconds, ""
    finally:
        if bpy.context.object is not None and bpy.context.object.mode != "OBJECT":
            bpy.ops.object.mode_set(mode="OBJECT")
        bpy.data.objects.remove(obj)
        bpy.data.meshes.remove(mesh)


def _tutte_uv(V: np.ndarray, F: np.ndarray, bnd: np.ndarray, bnd_uv: np.ndarray) -> np.ndarray:
    """Tutte embedding (uniform weights) with the boundary fixed at ``bnd_uv``: (n,2)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    n = len(V)
    e = F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    e = np.unique(np.sort(e, axis=1), axis=0)
    A = sp.coo_array((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])),
                     shape=(n, n)).tocsr()
    A.data[:] = 1.0
    L = (sp.diags_array(np.asarray(A.sum(axis=1)).ravel()) - A).tocsr()
    interior = np.setdiff1d(np.arange(n), bnd)
    uv = np.zeros((n, 2))
    uv[bnd] = bnd_uv
    rhs = -(L[interior][:, bnd] @ bnd_uv)
    lu = spla.splu(L[interior][:, interior].tocsc())
    uv[interior] = lu.solve(rhs)
    return uv


def slim_unwrap(V: np.ndarray, F: np.ndarray, iterations: int = 20) -> tuple[np.ndarray, float, str]:
    """libigl SLIM, symmetric Dirichlet energy, from a harmonic map onto a circle.

    ``igl.boundary_loop`` -> ``igl.map_vertices_to_circle`` -> ``igl.harmonic(k=1)`` (cotangent
    weights; when that map has flipped triangles, which SLIM cannot start from, a uniform-weight
    Tutte embedding replaces it and the note says so), scaled uniformly so its UV area equals the
    3D area, then ``igl.slim_precompute`` (no constraints) and ``igl.slim_solve(data, iterations)``.
    The whole chain is timed.

    Returns
    -------
    corner_uv : (m,3,2) float64
    seconds : float
    note : str
    """
    import igl

    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    t0 = time.perf_counter()
    bnd = igl.boundary_loop(F)
    bnd_uv = igl.map_vertices_to_circle(np.asfortranarray(V), bnd.astype(np.int32))
    uv0 = igl.harmonic(V, F, bnd, np.ascontiguousarray(bnd_uv), 1)
    note = "init: cotan harmonic"
    nflip = len(igl.flipped_triangles(np.ascontiguousarray(uv0), F))
    if nflip:
        uv0 = _tutte_uv(V, F, bnd, np.asarray(bnd_uv))
        note = f"init: Tutte (cotan harmonic had {nflip} flips)"
    p0, p1, p2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    area3d = 0.5 * np.linalg.norm(np.cross(p1 - p0, p2 - p0), axis=1).sum()
    d1, d2 = uv0[F[:, 1]] - uv0[F[:, 0]], uv0[F[:, 2]] - uv0[F[:, 0]]
    area_uv = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]).sum()
    uv0 = uv0 * np.sqrt(area3d / area_uv)
    data = igl.slim_precompute(
        np.asfortranarray(V), np.asfortranarray(F.astype(np.int32)), np.asfortranarray(uv0),
        igl.MappingEnergyType.SYMMETRIC_DIRICHLET,
        np.zeros(0, dtype=np.int32), np.zeros((0, 2), dtype=np.float64, order="F"), 0.0)
    uv = igl.slim_solve(data, iterations)
    seconds = time.perf_counter() - t0
    return np.asarray(uv)[:, :2][F], seconds, note
