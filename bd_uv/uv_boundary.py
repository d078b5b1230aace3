"""The UV boundary of a labelled layout, found from the corner UVs as stored.

A half-edge is interior when a face of the same island holds the reverse half-edge with the same
UVs at both ends; every other half-edge is a boundary segment (seams and slits included). The
overlap certificate (:mod:`.overlap`), the layout certificate, the packer's outlines and the
live certificate all start from it.
"""
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Boundary:
    """The UV boundary segments of a labelled layout.

    Attributes
    ----------
    p, q : (b,2) float64, start and end UV of each boundary half-edge (faces on its left when the
        face is counter-clockwise)
    island : (b,) int64, the island of each segment
    face : (b,) int64, the face each segment belongs to
    edge : (b,2) int64, mesh vertices (start, end) of each segment
    pid, qid : (b,) int64, ids of the start and end UV points (equal ids: same island, same UV)
    interior : (h,2) int64, pairs of matched interior half-edges (flat corner ids ``3 f + k``)
    """
    p: np.ndarray
    q: np.ndarray
    island: np.ndarray
    face: np.ndarray
    edge: np.ndarray
    pid: np.ndarray
    qid: np.ndarray
    interior: np.ndarray


def row_ids(*cols):
    """Dense ids of equal rows of integer columns (each (N,)); returns (N,) int64."""
    order = np.lexsort(cols[::-1])
    sorted_cols = [c[order] for c in cols]
    new = np.ones(len(order), dtype=bool)
    if len(order):
        new[1:] = np.any([c[1:] != c[:-1] for c in sorted_cols], axis=0)
    ids = np.empty(len(order), dtype=np.int64)
    ids[order] = np.cumsum(new) - 1
    return ids


def exact_bits(x):
    """Exact integer image of float64 values (+0.0 and -0.0 made equal)."""
    x = np.asarray(x, dtype=np.float64) + 0.0
    return x.view(np.int64)


def uv_boundary(F, corner_uv, face_island):
    """The UV boundary of every island, found from the stored corner UVs.

    Parameters
    ----------
    F : (m,3) int array
    corner_uv : (m,3,2) float array (float32 allowed), UVs as stored
    face_island : (m,) int array, island per face, -1 for faces of no island. Faces with non-finite
        UVs are left out.

    Returns
    -------
    Boundary
    """
    F = np.asarray(F, dtype=np.int64)
    uv = np.asarray(corner_uv, dtype=np.float64).reshape(-1, 3, 2)
    lab = np.asarray(face_island, dtype=np.int64).reshape(-1)
    use = (lab >= 0) & np.isfinite(uv).all(axis=(1, 2))
    faces = np.flatnonzero(use)
    # Half-edge i runs corner h[i] = 3 f + k -> its next corner in face f = faces[i // 3]. Only
    # the (h,) columns the sort needs are made for every half-edge; UVs are read per pair (a
    # 500k-face layout held ~250 MB of per-half-edge copies here, now ~100 MB).
    # The columns in int32 where every id fits (the outputs are int64 as documented).
    small = 3 * len(F) < 2**31 - 1 and (F.size == 0 or int(F.max()) < 2**31 - 1) \
        and (lab.size == 0 or int(lab.max()) < 2**31 - 1)
    it = np.int32 if small else np.int64
    h = (3 * faces[:, None].astype(it) + np.arange(3, dtype=it)).ravel()   # flat corner ids
    hn = h - h % 3 + (h % 3 + 1) % 3
    Fr = F.ravel()
    a, b = Fr[h].astype(it), Fr[hn].astype(it)
    del Fr
    flat_uv = uv.reshape(-1, 2)
    isl = np.repeat(lab[faces].astype(it), 3)
    # Pair half-edges of one island on the same undirected edge; interior iff exactly two, opposite
    # directions, and the same UV at each end.
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    order = np.lexsort((hi, lo, isl)).astype(it, copy=False)
    same_next = np.zeros(len(h), dtype=bool)
    if len(h) > 1:
        same_next[:-1] = _equal_next(isl, order)
        same_next[:-1] &= _equal_next(lo, order)
        same_next[:-1] &= _equal_next(hi, order)
    del lo, hi
    # Groups of exactly two: i and i + 1 equal, neither equal to its other neighbour.
    two = same_next.copy()
    two[1:] &= ~same_next[:-1]
    two[:-1] &= ~same_next[1:]
    i1 = np.flatnonzero(two)
    del same_next, two
    x, y = order[i1], order[i1 + 1]
    del order, i1
    # One UV column at a time: the (k,2) gathers of both ends of both half-edges were ~48 MB at
    # once on a 500k-face layout.
    match = a[x] == b[y]
    for col in (0, 1):
        match &= flat_uv[h[x], col] == flat_uv[hn[y], col]
        match &= flat_uv[hn[x], col] == flat_uv[h[y], col]
    x, y = x[match], y[match]
    del match
    interior = np.zeros(len(h), dtype=bool)
    interior[x] = True
    interior[y] = True
    inner = np.stack([h[x], h[y]], axis=1).astype(np.int64)
    del x, y
    bnd = np.flatnonzero(~interior)
    del interior
    # The outputs first, then the per-half-edge columns dropped before the boundary's ids.
    p, q, bi = flat_uv[h[bnd]], flat_uv[hn[bnd]], isl[bnd].astype(np.int64)
    edge = np.stack([a[bnd], b[bnd]], axis=1).astype(np.int64)
    del h, hn, a, b, isl
    ids = row_ids(np.concatenate([bi, bi]), exact_bits(np.concatenate([p[:, 0], q[:, 0]])),
                  exact_bits(np.concatenate([p[:, 1], q[:, 1]])))
    nb = len(bnd)
    return Boundary(p, q, bi, faces[bnd // 3], edge, ids[:nb], ids[nb:], inner)


def _equal_next(col, order):
    """``col[order][1:] == col[order][:-1]`` without the sorted copy of ``col``'s dtype held
    beside its shifted comparison (one gather, one comparison)."""
    s = col[order]
    return s[1:] == s[:-1]
