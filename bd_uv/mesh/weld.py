"""Welding a mesh's split vertices back into one surface, without pinching it.

glTF, PLY and OFF exporters split a vertex wherever its normal or UV differs (a PLY or OFF written
face by face splits every vertex); the unwrap wants the surface
whole, so vertices with the same position are welded. Two distinct vertices of a mesh can also
share a position where its parts only touch (a point contact): welding them would join faces at a
single vertex (a bow-tie), which no UV island can hold. So after the weld each vertex is split
again into one vertex per fan of faces around it (faces joined through edges at that vertex).
"""
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components


def welded(V, F):
    """Weld equal positions, then split every vertex into its edge-connected fans.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array

    Returns
    -------
    W : (k,3) float64, the welded vertices
    G : (m,3) int64, the faces on them (same face order and corner order as ``F``)
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    key = _fan_keys(V, F)
    _, first, G = np.unique(key, return_index=True, return_inverse=True)
    W = V[F.ravel()[first]]
    return W, G.reshape(len(F), 3)


def welded_in_place(V, F, parts=None):
    """The faces of :func:`welded`, on the file's own vertices: each welded vertex is named by
    the least file vertex among its corners, so ``V`` stays as it is (the vertices welded away
    are left unused) and every vertex id a report gives is one of the file's.

    ``parts`` : (m,) int array or None, each face's part (an OBJ's ``o`` object): faces of two
    parts are never welded together (Blender imports each object on its own).

    Returns
    -------
    G : (m,3) int64, same face order and corner order as ``F``
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    key = _fan_keys(V, F, parts)
    _, group = np.unique(key, return_inverse=True)
    group = group.reshape(-1)
    least = np.full(group.max() + 1 if len(group) else 0, np.iinfo(np.int64).max, np.int64)
    np.minimum.at(least, group, F.ravel())
    return least[group].reshape(F.shape)


def _fan_keys(V, F, parts=None):
    """(3m,) int64: one key per corner, equal for the corners of one (position, fan) (of one
    part, when ``parts`` gives each face's)."""
    m = len(F)
    _, pos = np.unique(V, axis=0, return_inverse=True)
    P = pos.reshape(-1)[F]                        # (m,3) position ids
    if parts is not None:                         # a position id per (position, part)
        both = np.stack([P.ravel(), np.repeat(np.asarray(parts, dtype=np.int64), 3)], 1)
        P = np.unique(both, axis=0, return_inverse=True)[1].reshape(m, 3)
    # corners c = 3f + j; the half-edge j of face f runs P[f,j] -> P[f,(j+1)%3]
    a, b = P.ravel(), np.roll(P, -1, axis=1).ravel()
    ca = np.arange(3 * m)                          # the corner at a
    cb = (ca // 3) * 3 + (ca % 3 + 1) % 3          # the corner at b
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    order = np.lexsort((hi, lo))
    same = (lo[order][1:] == lo[order][:-1]) & (hi[order][1:] == hi[order][:-1]) \
        & (lo[order][1:] != hi[order][1:])
    h1, h2 = order[:-1][same], order[1:][same]     # two half-edges of one edge
    # join the corners at the same end of the shared edge
    flip = a[h1] != a[h2]                          # the other face runs the edge backwards
    rows = np.concatenate([ca[h1], cb[h1]])
    cols = np.concatenate([np.where(flip, cb[h2], ca[h2]), np.where(flip, ca[h2], cb[h2])])
    graph = sp.coo_array((np.ones(len(rows)), (rows, cols)), shape=(3 * m, 3 * m))
    _, fan = connected_components(graph, directed=False)
    # a vertex per (position, fan); a fan never spans two positions (joins keep the end)
    return P.ravel() * (3 * m) + fan
