"""The batch's triangles in an order, numbering and quad split fixed by the vertices alone, so
the seam search finds the same seams whatever Blender's numbering or choice of diagonal in this
session (``auto_seams.solve``).

No ``bpy``: numpy only.
"""
from __future__ import annotations

import numpy as np


def canonical_triangles(V, F, tri_poly, tri_loops):
    """The batch's triangles in an order and numbering fixed by the vertices alone.

    Blender numbers the polygons (and loops, and triangles) of the same mesh differently from
    one session to the next (a new UV sphere, say): quads split by :func:`canonical_quads`,
    each triangle rotated to start at its smallest vertex id (orientation kept), triangles
    sorted by their vertex ids, polygons numbered in that order.

    Returns
    -------
    Fc : (m,3) int64, the triangles in canonical order
    order : (m,) int64, ``Fc[i]`` is (the canonical split of) triangle ``order[i]``
    poly : (m,) int64, polygon of each canonical triangle, numbered from 0 in order
    """
    Fc, _ = canonical_quads(V, F, tri_poly, tri_loops)
    r = np.argmin(Fc, axis=1)
    Fc = np.take_along_axis(Fc, (r[:, None] + np.arange(3)) % 3, axis=1)
    order = np.lexsort((Fc[:, 2], Fc[:, 1], Fc[:, 0]))
    _, first, inv = np.unique(tri_poly[order], return_index=True, return_inverse=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first)] = np.arange(len(first))
    return Fc[order], order, rank[inv.ravel()]


def canonical_quads(V, F, tri_poly, tri_loops):
    """Every quad split along the same diagonal whatever Blender chose: the shorter one (to
    1e-9 of the quad's size), on a tie the one through the quad's smallest vertex id, the other
    where that one would fold the quad (a concave quad). Blender picks the diagonal of a
    symmetric quad by rounding noise, differently from one session to the next.

    Parameters
    ----------
    V : (n,3) float64; F : (m,3) int64; tri_poly : (m,) int64; tri_loops : (m,3) int64, the
        Blender loop of each corner (a polygon's loops are consecutive, in polygon order)

    Returns
    -------
    F, tri_loops : (m,3) int64, the same triangles except in quads (two triangles per polygon)
    """
    order = np.argsort(tri_poly, kind="stable")
    count = np.bincount(tri_poly)
    pair = (count[tri_poly[order]] == 2)
    first = order[pair][0::2]
    second = order[pair][1::2]
    if len(first) == 0:
        return F, tri_loops
    loops = np.concatenate([tri_loops[first], tri_loops[second]], axis=1)
    verts = np.concatenate([F[first], F[second]], axis=1)
    srt = np.argsort(loops, axis=1, kind="stable")
    ls = np.take_along_axis(loops, srt, axis=1)
    vs = np.take_along_axis(verts, srt, axis=1)
    # Two triangles of a quad share two corners: 4 distinct loops, in polygon order.
    uniq = np.concatenate([np.ones((len(ls), 1), bool), ls[:, 1:] != ls[:, :-1]], axis=1)
    quad = uniq.sum(axis=1) == 4
    ql = ls[quad][uniq[quad]].reshape(-1, 4)
    qv = vs[quad][uniq[quad]].reshape(-1, 4)
    P = V[qv]
    d02 = np.linalg.norm(P[:, 2] - P[:, 0], axis=1)
    d13 = np.linalg.norm(P[:, 3] - P[:, 1], axis=1)
    size = np.maximum(d02, d13)
    tie = np.abs(d13 - d02) <= 1e-9 * size
    low = np.argmin(qv, axis=1) % 2 == 1            # the smallest vertex on diagonal 1-3
    use13 = np.where(tie, low, d13 < d02)

    def folds(a, b, c, d):            # triangles (a,b,c) and (a,c,d) facing apart
        n1 = np.cross(P[:, b] - P[:, a], P[:, c] - P[:, a])
        n2 = np.cross(P[:, c] - P[:, a], P[:, d] - P[:, a])
        return np.einsum("ij,ij->i", n1, n2) <= 0
    use13 = np.where(folds(0, 1, 2, 3), True, np.where(folds(1, 2, 3, 0), False, use13))
    c0 = np.where(use13[:, None], [1, 2, 3], [0, 1, 2])
    c1 = np.where(use13[:, None], [1, 3, 0], [0, 2, 3])
    F, tri_loops = F.copy(), tri_loops.copy()
    fa, fb = first[quad], second[quad]
    F[fa] = np.take_along_axis(qv, c0, axis=1)
    F[fb] = np.take_along_axis(qv, c1, axis=1)
    tri_loops[fa] = np.take_along_axis(ql, c0, axis=1)
    tri_loops[fb] = np.take_along_axis(ql, c1, axis=1)
    return F, tri_loops
