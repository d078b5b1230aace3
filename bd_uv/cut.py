"""Repair an island whose UV boundary crosses itself by cutting it into overlap-free pieces.

Cutting never moves a UV: every piece keeps the flip and distortion certificate of the map it comes
from (Lipman 2012, eq. 4.9 is per face), and a piece whose boundary is simple and wound right is
one-to-one (Theorems 5.1 and 5.2). Pieces grow from a peripheral face in breadth-first order across
the island's interior edges; each piece is the largest breadth-first ball (found by bisection on its
radius) that is still overlap-free, and what is left is cut again the same way.
"""
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, shortest_path

from .overlap import island_overlaps
from .uv_boundary import uv_boundary


def _overlap_free(F, uv, faces):
    lab = np.full(len(F), -1, dtype=np.int64)
    lab[faces] = 0
    return bool(island_overlaps(F, uv, lab, 1).overlap_free[0])


def split_overlapping(V, F, corner_uv, faces_of_island, face_groups=None):
    """Cut one island into pieces whose UV boundaries are simple and disjoint.

    Parameters
    ----------
    V : (n,3) float array (unused by the cut, kept for the common signature)
    F : (m,3) int array
    corner_uv : (m,3,2) float array, the island's UVs (no flipped face expected: a flipped face
        is never overlap-free on its own and stays a piece of one face)
    faces_of_island : (k,) int array, the island's faces (indices into F)
    face_groups : (m,) int array, optional, a group per face of F (e.g. the Blender polygon each
        triangle comes from): faces of one group always end in the same piece, so no cut runs
        through a polygon

    Returns
    -------
    pieces : list of (k_i,) int64 arrays, faces of each piece (indices into F), the largest first;
        one piece (the island itself) when it is already overlap-free
    cut_edges : (c,2) int64, mesh vertex pairs of the edges cut between pieces (mark them as seams)
    """
    F = np.asarray(F, dtype=np.int64)
    faces = np.asarray(faces_of_island, dtype=np.int64).reshape(-1)
    Fi = F[faces]
    uvi = np.asarray(corner_uv, dtype=np.float64).reshape(-1, 3, 2)[faces]
    k = len(faces)
    if k == 0:
        return [], np.zeros((0, 2), dtype=np.int64)
    if _overlap_free(Fi, uvi, np.arange(k)):
        return [faces.copy()], np.zeros((0, 2), dtype=np.int64)
    pairs = uv_boundary(Fi, uvi, np.zeros(k, dtype=np.int64)).interior // 3   # face pairs
    adj = sp.coo_array((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(k, k)).tocsr()
    adj = adj + adj.T
    group = (np.arange(k) if face_groups is None
             else np.unique(np.asarray(face_groups)[faces], return_inverse=True)[1].ravel())
    piece = np.full(k, -1, dtype=np.int64)
    todo = [np.arange(k)]
    while todo:  # one pass per piece or component, never per face
        comp = todo.pop()
        if _overlap_free(Fi, uvi, comp):
            piece[comp] = piece.max() + 1
            continue
        sub = adj[comp][:, comp]
        # Distances between groups (faces of one group at distance 0 from each other), so a ball
        # holds whole groups.
        gid, g = np.unique(group[comp], return_inverse=True)
        gs = sub.tocoo()
        keep = g[gs.row] != g[gs.col]
        gsub = sp.coo_array((np.ones(int(keep.sum())), (g[gs.row[keep]], g[gs.col[keep]])),
                            shape=(len(gid), len(gid))).tocsr()
        seed_g = int(np.argmax(shortest_path(gsub, unweighted=True, indices=0)))  # peripheral
        dist = shortest_path(gsub, unweighted=True, indices=seed_g)[g]
        seed = int(np.flatnonzero(g == seed_g)[0])
        lo, hi = 0, int(np.max(dist[np.isfinite(dist)]))
        # radius 0 is the seed's group (its polygon): whole when that is overlap-free, else the
        # seed face alone (a polygon folded over itself in UV cannot stay whole)
        best = np.flatnonzero(dist <= 0)
        _, lab = connected_components(sub[best][:, best], directed=False)
        best = best[lab == lab[np.searchsorted(best, seed)]]
        if not _overlap_free(Fi, uvi, comp[best]):
            best = np.array([seed])
        while lo < hi:  # largest radius whose ball (its part around the seed) is overlap-free
            t = (lo + hi + 1) // 2
            ball = np.flatnonzero(dist <= t)
            _, lab = connected_components(sub[ball][:, ball], directed=False)
            ball = ball[lab == lab[np.searchsorted(ball, seed)]]
            if _overlap_free(Fi, uvi, comp[ball]):
                lo, best = t, ball
            else:
                hi = t - 1
        piece[comp[best]] = piece.max() + 1
        rest = np.setdiff1d(np.arange(len(comp)), best)
        if len(rest):
            n_rest, lab = connected_components(sub[rest][:, rest], directed=False)
            todo += [comp[rest[lab == c]] for c in range(n_rest)]
    sizes = np.bincount(piece)
    order = np.argsort(-sizes, kind="stable")
    pieces = [faces[piece == p] for p in order]
    cut = piece[pairs[:, 0]] != piece[pairs[:, 1]]
    h = uv_boundary(Fi, uvi, np.zeros(k, dtype=np.int64)).interior[cut, 0]
    f, c = h // 3, h % 3
    cut_edges = np.stack([Fi[f, c], Fi[f, (c + 1) % 3]], axis=1)
    return pieces, cut_edges
