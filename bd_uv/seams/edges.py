"""The mesh's edge table and how much a seam along each edge costs.

Seams are cheap where an artist would put them: along sharp edges, concave creases and material
boundaries; dear across flat, visible areas. The cost multiplies each edge's length.
"""
from dataclasses import dataclass

import numpy as np

from ..solvers import radix
from ..trim import CHUNK

# Dihedral turn from which a concave edge gets its full discount (half the cost).
CONCAVE_FULL = np.radians(5.0)

@dataclass(frozen=True)
class EdgeTable:
    """Undirected edges of a triangle mesh.

    Attributes
    ----------
    ends : (e,2) int32, vertex pair of each edge (smaller index first)
    faces : (e,2) int32, the two faces of each interior edge; ``faces[:,1] = -1`` on the boundary
    length : (e,) float64, 3D length
    cost : (e,) float64, seam cost per unit length in (0, 1]: 1 on flat edges, lower on creases
    face_edges : (m,3) int32, edge of each face corner's outgoing half-edge F[f,k] -> F[f,k+1]
    corners : (e,2,2) int32, ``corners[e,s,t]``: the corner (``3 f + k``) of ``ends[e,t]`` in
        ``faces[e,s]`` (-1 where there is no such face); the seam search drops it (None) once
        its checks are done where ``fans`` is known (``topology`` reads it only without fans)

    The indices are int32 (``INDEX``: int64 from 2**31 corners on): the table is held through
    the whole seam search, 114 MB in int64 on a 500k-face mesh; arithmetic on them that can
    pass 2**31 (vertex pair keys) is done in int64.
    fans : Fans or None, the corners around each vertex in order (None where the mesh is not
        an oriented manifold: then cuts are found by a graph search)
    """
    ends: np.ndarray
    faces: np.ndarray
    length: np.ndarray
    cost: np.ndarray
    face_edges: np.ndarray
    corners: np.ndarray
    fans: object = None

    def keys(self, pairs, n):
        """Edge index of each vertex pair (s,2), -1 where the pair is not an edge."""
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        k = np.minimum(pairs[:, 0], pairs[:, 1]) * n + np.maximum(pairs[:, 0], pairs[:, 1])
        mine = self.ends[:, 0].astype(np.int64) * n + self.ends[:, 1]
        pos = np.clip(mine.searchsorted(k), 0, len(mine) - 1)
        return np.where(mine[pos] == k, pos, -1)


def index_dtype(size):
    """int32 for indices below ``size`` when it fits, else int64."""
    return np.int32 if size < 2**31 - 1 else np.int64


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
    idx = index_dtype(3 * m)
    a = F.ravel()
    b = np.roll(F, -1, axis=1).ravel()
    key = np.minimum(a, b) * n + np.maximum(a, b)
    del b
    # (``radix``: np.unique's and the stable argsort's results by 16-bit radix passes, up to
    # ``radix.LARGE`` keys; 5-10 % of the table on 1k-20k-face meshes)
    uniq, inv, _ = radix.unique(key, n * n)
    del key
    inv = inv.ravel().astype(idx)
    e = len(uniq)
    ends = np.stack([uniq // n, uniq % n], axis=1).astype(idx)
    del uniq
    order = radix.order(inv, e).astype(idx)
    first = inv[order].searchsorted(np.arange(e, dtype=idx)).astype(idx)
    count = np.bincount(inv, minlength=e)
    faces = np.full((e, 2), -1, dtype=idx)
    faces[:, 0] = order[first] // 3
    two = count >= 2
    del count
    faces[two, 1] = order[first[two] + 1] // 3
    # The per-edge and per-face arithmetic ``CHUNK`` rows at a time (each row's own numbers:
    # the same bits): the (e,2,3) end positions and the interior edges' normals, cross products
    # and opposite vertices at once were ~200 MB on a 500k-face mesh, the search's set-up peak.
    length = np.empty(e)
    for i in range(0, e, CHUNK):
        s = slice(i, i + CHUNK)
        # (rows by ``take``: numpy's fancy index is ~4x dearer for rows, ~2x by int32 ids)
        length[s] = np.linalg.norm(V.take(ends[s, 1], axis=0) - V.take(ends[s, 0], axis=0), axis=1)
    N = np.empty((m, 3))
    for i in range(0, m, CHUNK):
        Fs = F[i:i + CHUNK]
        Ns = N[i:i + CHUNK]
        P0 = V.take(Fs[:, 0], axis=0)
        Ns[:] = np.cross(V.take(Fs[:, 1], axis=0) - P0, V.take(Fs[:, 2], axis=0) - P0)
        Ns /= np.maximum(np.linalg.norm(Ns, axis=1, keepdims=True), 1e-300)
    Fs = Ns = P0 = None
    cost = np.ones(e)
    f0, f1 = faces[two, 0], faces[two, 1]
    tw = two.ravel().nonzero()[0]
    c = np.empty(len(tw))
    for i in range(0, len(tw), CHUNK):
        s = slice(i, i + CHUNK)
        N0, N1 = N.take(f0[s], axis=0), N.take(f1[s], axis=0)
        # atan2 rather than arccos: exact near 0, where arccos turns rounding noise into angles.
        theta = np.arctan2(np.linalg.norm(np.cross(N0, N1), axis=1),
                           np.einsum("ij,ij->i", N0, N1))
        # Concave when the opposite vertex of f1 lies above f0's plane. The discount grows with
        # the angle (full from CONCAVE_FULL on): on a flat edge (a planar quad's diagonal) the
        # side is rounding noise, which must not halve the cost of one run and not the next.
        Ff1, es = F.take(f1[s], axis=0), ends.take(tw[s], axis=0)
        off_edge = (Ff1 != es[:, :1]) & (Ff1 != es[:, 1:])
        opp = Ff1[np.arange(len(Ff1)), np.argmax(off_edge, axis=1)]
        concave = np.einsum("ij,ij->i", V.take(opp, axis=0) - V.take(es[:, 0], axis=0), N0) > 0
        half = np.where(concave, 0.5 * np.minimum(theta / CONCAVE_FULL, 1.0), 0.0)
        c[s] = np.exp(-theta / crease_angle) * (1.0 - half)
    N = N0 = N1 = Ff1 = es = off_edge = opp = concave = half = theta = tw = None
    if face_groups is not None:
        g = np.asarray(face_groups)
        c = np.where(g[f0] != g[f1], min(c.min(initial=1.0), np.exp(-np.pi / crease_angle)), c)
    cost[two] = np.maximum(c, 1e-3)
    del c, f0, f1
    # Corners of each edge's ends in its faces: its half-edge h runs corner h -> the next one.
    corners = np.full((e, 2, 2), -1, dtype=idx)
    for s_, h in ((0, order[first]), (1, order[first[two] + 1])):
        sel = slice(None) if s_ == 0 else two
        nxt = h - h % 3 + (h % 3 + 1) % 3
        forward = a[h] == ends[sel, 0]
        corners[sel, s_, 0] = np.where(forward, h, nxt)
        corners[sel, s_, 1] = np.where(forward, nxt, h)
    del order, first, h, nxt, forward
    face_edges = inv.reshape(m, 3)
    return EdgeTable(ends, faces, length, cost, face_edges, corners,
                     _fans(F, face_edges, faces, ends, corners))


@dataclass(frozen=True)
class Fans:
    """The corners around every vertex, in turn (an oriented manifold mesh).

    Corner ``c`` (``3 f + k``) turns to ``next[c]``, the same vertex's corner in the face across
    the edge ``F[f,k] -> F[f,k+1]`` (``edge[c]``), -1 on the mesh boundary. ``order`` lists
    all corners fan by fan, each fan from its first corner (a boundary vertex's fan starts
    where the boundary does; a closed fan at its smallest corner); ``first[i]`` marks the
    start of a fan in ``order`` and ``ring[i]`` a closed fan's start (its last corner turns
    back to it). ``fan[c]`` (int32) is the fan of corner ``c``, which occupies
    ``order[starts[fan]:starts[fan + 1]]`` (so the fans of a few faces are read without a pass
    over the whole mesh).
    """
    next: np.ndarray
    edge: np.ndarray
    order: np.ndarray
    first: np.ndarray
    ring: np.ndarray
    fan: np.ndarray
    starts: np.ndarray


def _fans(F, face_edges, faces, ends, corners):
    """``Fans`` of the mesh, or None where it is not an oriented manifold (an edge with three
    faces, two faces running an edge the same way, a corner reached twice)."""
    m = len(F)
    # Corner ids in the table's index type and the 0/1 sides in int8 (integers all through:
    # the same results as int64): ~15 arrays of a corner each, the set-up's peak in int64.
    idx = index_dtype(3 * m)
    c = np.arange(3 * m, dtype=idx)
    edge = face_edges.ravel()
    v = F.ravel()
    side = (faces[:, 0].take(edge) != c // 3).astype(np.int8)
    end = (ends[:, 0].take(edge) != v).astype(np.int8)
    nxt = corners[edge, 1 - side, end]
    del side
    on = nxt >= 0
    count = np.bincount(edge, minlength=len(ends))
    # Oriented: across every interior edge the two faces run it in opposite directions (one
    # starts it at each end), so each corner is turned to from at most one corner.
    if (count > 2).any() or (np.bincount(edge, end, len(ends))[count == 2] != 1).any() \
            or (v[nxt[on]] != v[on]).any():
        return None
    del count, end
    prev = np.full(3 * m, -1, dtype=idx)
    prev[nxt[on]] = c[on]
    steps = int(np.ceil(np.log2(max(int(np.bincount(v).max(initial=1)), 2)))) + 1
    # Closed fans: the smallest corner of each cycle becomes its start.
    fwd = np.where(on, nxt, c)
    low, p = c.copy(), fwd
    # (``take``: numpy's gather by an int32 index by fancy index is ~2x dearer)
    for _ in range(steps):
        low = np.minimum(low, low.take(p))
        p = p.take(p)
    fwd = None
    p = np.where(prev >= 0, prev, c)
    for _ in range(steps):
        p = p.take(p)
    ring = prev[p] >= 0                     # never reaches a corner without a predecessor
    start = np.where(ring, low, p)
    del low
    # Rank of each corner in its fan: steps back to the start (list ranking).
    p = np.where((prev >= 0) & (c != start), prev, c)
    del prev
    rank = (p != c).astype(idx)
    for _ in range(steps):
        rank = rank + rank.take(p)
        p = p.take(p)
    del p
    if 3 * m <= radix.LARGE:     # the same order by radix passes (stable: ties alike); a
        #                            large mesh's corners keep numpy's (no int64 key beside them)
        r = int(rank.max(initial=0)) + 1
        order = radix.order(start.astype(np.int64) * r + rank, 3 * m * r, passes=3)
    else:
        order = np.lexsort((rank, start))
    del rank
    first = np.r_[True, start[order][1:] != start[order][:-1]]
    del start
    fan = np.empty(3 * m, dtype=np.int32)
    fan[order] = first.cumsum() - 1
    starts = np.append(first.ravel().nonzero()[0], 3 * m)
    return Fans(nxt.astype(idx, copy=False), edge.astype(idx, copy=False), order.astype(idx),
                first, first & ring[order], fan, starts.astype(idx))

