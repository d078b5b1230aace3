"""The mesh's edge table and how much a seam along each edge costs.

Seams are cheap where an artist would put them: along sharp edges, concave creases and material
boundaries; dear across flat, visible areas. The cost multiplies each edge's length.
"""
from dataclasses import dataclass

import numpy as np

# Dihedral turn from which a concave edge gets its full discount (half the cost).
CONCAVE_FULL = np.radians(5.0)

@dataclass(frozen=True)
class EdgeTable:
    """Undirected edges of a triangle mesh.

    Attributes
    ----------
    ends : (e,2) int64, vertex pair of each edge (smaller index first)
    faces : (e,2) int64, the two faces of each interior edge; ``faces[:,1] = -1`` on the boundary
    length : (e,) float64, 3D length
    cost : (e,) float64, seam cost per unit length in (0, 1]: 1 on flat edges, lower on creases
    face_edges : (m,3) int64, edge of each face corner's outgoing half-edge F[f,k] -> F[f,k+1]
    corners : (e,2,2) int64, ``corners[e,s,t]``: the corner (``3 f + k``) of ``ends[e,t]`` in
        ``faces[e,s]`` (-1 where there is no such face)
    """
    ends: np.ndarray
    faces: np.ndarray
    length: np.ndarray
    cost: np.ndarray
    face_edges: np.ndarray
    corners: np.ndarray

    def keys(self, pairs, n):
        """Edge index of each vertex pair (s,2), -1 where the pair is not an edge."""
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        k = np.minimum(pairs[:, 0], pairs[:, 1]) * n + np.maximum(pairs[:, 0], pairs[:, 1])
        mine = self.ends[:, 0] * n + self.ends[:, 1]
        pos = np.clip(np.searchsorted(mine, k), 0, len(mine) - 1)
        return np.where(mine[pos] == k, pos, -1)


def edge_table(V, F, face_groups=None, crease_angle=np.radians(30.0)):
    """Edges, their faces and the cost of a seam along each.

    Parameters
    ----------
    V : (n,3) float64
    F : (m,3) int64, consistently oriented (outward normals make convex edges positive)
    face_groups : (m,) int array, optional, a material (or any group) per face: edges between two
        groups cost as little as the sharpest crease
    crease_angle : float radians, the dihedral turn at which a seam costs ``exp(-1)`` of a flat one

    Returns
    -------
    EdgeTable
        ``cost = exp(-theta / crease_angle)`` with ``theta`` the angle between the two face
        normals, halved again on concave edges (the seam hides in the fold; the discount grows to a
        half over the first ``CONCAVE_FULL`` of turn).
    """
    n, m = len(V), len(F)
    a = F.ravel()
    b = np.roll(F, -1, axis=1).ravel()
    key = np.minimum(a, b) * n + np.maximum(a, b)
    uniq, inv = np.unique(key, return_inverse=True)
    inv = inv.ravel()
    e = len(uniq)
    ends = np.stack([uniq // n, uniq % n], axis=1)
    order = np.argsort(inv, kind="stable")
    first = np.searchsorted(inv[order], np.arange(e))
    count = np.bincount(inv, minlength=e)
    faces = np.full((e, 2), -1, dtype=np.int64)
    faces[:, 0] = order[first] // 3
    two = count >= 2
    faces[two, 1] = order[first[two] + 1] // 3
    P = V[ends]
    length = np.linalg.norm(P[:, 1] - P[:, 0], axis=1)
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    N /= np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)
    cost = np.ones(e)
    f0, f1 = faces[two, 0], faces[two, 1]
    # atan2 rather than arccos: exact near 0, where arccos turns rounding noise into angles.
    theta = np.arctan2(np.linalg.norm(np.cross(N[f0], N[f1]), axis=1),
                       np.einsum("ij,ij->i", N[f0], N[f1]))
    # Concave when the opposite vertex of f1 lies above f0's plane. The discount grows with the
    # angle (full from CONCAVE_FULL on): on a flat edge (a planar quad's diagonal) the side is
    # rounding noise, which must not halve the cost of one run and not the next.
    Ff1 = F[f1]
    off_edge = (Ff1 != ends[two, :1]) & (Ff1 != ends[two, 1:])
    opp = Ff1[np.arange(len(f1)), np.argmax(off_edge, axis=1)]
    concave = np.einsum("ij,ij->i", V[opp] - P[two, 0], N[f0]) > 0
    half = np.where(concave, 0.5 * np.minimum(theta / CONCAVE_FULL, 1.0), 0.0)
    c = np.exp(-theta / crease_angle) * (1.0 - half)
    if face_groups is not None:
        g = np.asarray(face_groups)
        c = np.where(g[f0] != g[f1], min(c.min(initial=1.0), np.exp(-np.pi / crease_angle)), c)
    cost[two] = np.maximum(c, 1e-3)
    # Corners of each edge's ends in its faces: its half-edge h runs corner h -> the next one.
    corners = np.full((e, 2, 2), -1, dtype=np.int64)
    for s_, h in ((0, order[first]), (1, order[first[two] + 1])):
        sel = slice(None) if s_ == 0 else two
        nxt = h - h % 3 + (h % 3 + 1) % 3
        forward = a[h] == ends[sel, 0]
        corners[sel, s_, 0] = np.where(forward, h, nxt)
        corners[sel, s_, 1] = np.where(forward, nxt, h)
    return EdgeTable(ends, faces, length, cost, inv.reshape(m, 3), corners)
