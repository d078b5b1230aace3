"""Mesh loading and the one distortion measure every benchmarked method is judged by.

Nothing here comes from the methods being compared: the UVs of each method are turned into
per-face Jacobians from the face's own 3D shape, and their singular values give the distortion.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class UVStats:
    """Distortion of one UV map, recomputed from the corner UVs alone.

    Attributes
    ----------
    distortion : (m,) float64
        Conformal distortion ``s_max / s_min`` per face; ``inf`` for flipped faces (signed UV
        area <= 0) and for faces with a non-finite UV.
    flipped : (m,) bool
        Signed UV area <= 0, or a non-finite UV.
    max_distortion : float
        Largest distortion over the non-flipped faces (``nan`` when every face is flipped).
    mean_distortion : float
        Mean distortion over the non-flipped faces, weighted by 3D face area.
    flips : int
        Number of flipped faces.
    """

    distortion: np.ndarray
    flipped: np.ndarray
    max_distortion: float
    mean_distortion: float
    flips: int


def load_mesh_by_index(path: str) -> tuple[np.ndarray, np.ndarray]:
    """Load a triangle mesh keeping the file's vertex and face order.

    OBJ files go through ``bd_uv.load_mesh`` (which reads them by position index) when bd_uv is
    importable; otherwise they are read here from their ``v`` and ``f`` lines only (texture and
    normal indices after a slash are ignored, so ``vt`` never splits a vertex), polygons with more
    than three corners fan-triangulated. OFF and PLY go through ``trimesh.load(path, process=False)``, which keeps the
    order.

    Returns
    -------
    V : (n,3) float64
    F : (m,3) int64
    """
    ext = os.path.splitext(path)[1].lower()
    if ext == ".obj":
        try:
            from bd_uv import load_mesh
        except ImportError:
            load_mesh = None
        if load_mesh is not None:
            mesh = load_mesh(path)
            return np.asarray(mesh.V, dtype=np.float64), np.asarray(mesh.F, dtype=np.int64)
        verts, faces = [], []
        with open(path, "r", encoding="utf-8", errors="replace") as fh:
            for line in fh:
                if line.startswith("v "):
                    verts.append([float(t) for t in line.split()[1:4]])
                elif line.startswith("f "):
                    idx = [int(t.split("/")[0]) for t in line.split()[1:]]
                    n = len(verts)
                    idx = [i - 1 if i > 0 else n + i for i in idx]
                    faces.extend([idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1))
        return np.asarray(verts, dtype=np.float64), np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    import trimesh

    tm = trimesh.load(path, process=False, force="mesh")
    return np.asarray(tm.vertices, dtype=np.float64), np.asarray(tm.faces, dtype=np.int64)


def boundary_edge_count(F: np.ndarray) -> int:
    """Number of edges used by exactly one face of ``F`` (m,3); 0 for a closed mesh."""
    e = np.sort(F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    return int(np.count_nonzero(counts == 1))


def face_areas(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """3D area of each face: (m,) float64."""
    p0, p1, p2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return 0.5 * np.linalg.norm(np.cross(p1 - p0, p2 - p0), axis=1)


def uv_stats(V: np.ndarray, F: np.ndarray, corner_uv: np.ndarray) -> UVStats:
    """Conformal distortion of a UV map from each face's 2x2 Jacobian (3D shape -> UV).

    Each triangle is laid out in its own orthonormal 2D frame (first edge on the x axis, third
    vertex at positive y), so the frame keeps the 3D orientation. The Jacobian is
    ``J = [d1 d2] [q1 q2]^-1`` with ``q`` the local edges and ``d`` the UV edges; its singular
    values are ``|a| + |b|`` and ``||a| - |b||`` with ``a = ((J00 + J11) + i (J10 - J01)) / 2`` and
    ``b = ((J00 - J11) + i (J10 + J01)) / 2`` (the similarity / anti-similarity split).

    Parameters
    ----------
    V : (n,3) float64
    F : (m,3) int64
    corner_uv : (m,3,2) float64
        UV of each face corner.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    uv = np.asarray(corner_uv, dtype=np.float64)
    p0, p1, p2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    e1, e2 = p1 - p0, p2 - p0
    l1 = np.linalg.norm(e1, axis=1)
    x = e1 / l1[:, None]
    q2x = np.einsum("ij,ij->i", e2, x)
    q2y = np.linalg.norm(e2 - q2x[:, None] * x, axis=1)          # > 0 for a non-degenerate face
    area3d = 0.5 * l1 * q2y

    d1 = uv[:, 1] - uv[:, 0]
    d2 = uv[:, 2] - uv[:, 0]
    signed_uv_area = 0.5 * (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    finite = np.isfinite(uv).all(axis=(1, 2))
    flipped = ~finite | ~(signed_uv_area > 0)

    # J = [d1 d2] @ inv([[l1, q2x], [0, q2y]])
    with np.errstate(divide="ignore", invalid="ignore"):
        inv00, inv01, inv11 = 1.0 / l1, -q2x / (l1 * q2y), 1.0 / q2y
        j00 = d1[:, 0] * inv00
        j10 = d1[:, 1] * inv00
        j01 = d1[:, 0] * inv01 + d2[:, 0] * inv11
        j11 = d1[:, 1] * inv01 + d2[:, 1] * inv11
        a = 0.5 * np.hypot(j00 + j11, j10 - j01)
        b = 0.5 * np.hypot(j00 - j11, j10 + j01)
        dist = (a + b) / np.abs(a - b)
    dist = np.where(flipped, np.inf, dist)

    ok = ~flipped
    if ok.any():
        max_d = float(dist[ok].max())
        mean_d = float(np.sum(area3d[ok] * dist[ok]) / np.sum(area3d[ok]))
    else:
        max_d = mean_d = float("nan")
    return UVStats(dist, flipped, max_d, mean_d, int(np.count_nonzero(flipped)))


def corner_uv_from_vertex_uv(F: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Per-corner UVs (m,3,2) from per-vertex UVs ``uv`` (n,2)."""
    return np.asarray(uv, dtype=np.float64)[:, :2][F]
