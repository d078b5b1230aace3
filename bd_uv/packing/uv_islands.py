"""UV islands of any UV map: faces joined across an edge whose two corners carry the same UVs on
both sides (what Blender's UV editor calls an island), and a duplicate face (the same three
vertices in the same cyclic order, with the same UVs) joined to its twin, so packing moves the two
together."""
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..uv_boundary import uv_boundary


def uv_islands(F, corner_uv):
    """Label every face with its UV island.

    Parameters
    ----------
    F : (m,3) int array, mesh vertex of each corner
    corner_uv : (m,3,2) float array; faces with non-finite UVs get -1

    Returns
    -------
    (m,) int64, island labels 0..k-1 in order of each island's first face (-1: no UVs)
    """
    F = np.asarray(F, dtype=np.int64)
    uv = np.asarray(corner_uv, dtype=np.float64).reshape(len(F), 3, 2)
    ok = np.isfinite(uv).all(axis=(1, 2))
    m = len(F)
    lab = np.full(m, -1, dtype=np.int64)
    if not ok.any():
        return lab
    idx = np.flatnonzero(ok)
    where = np.full(m, -1, dtype=np.int64)
    where[idx] = np.arange(len(idx))
    n = len(idx)
    twin = _same_face_same_uvs(F[idx], uv[idx])
    dup = np.zeros(m, dtype=bool)
    dup[idx] = twin != np.arange(n)
    # Edges are read without the duplicates (a duplicate makes its twin's edges non-manifold,
    # which would cut its twin's island apart); each duplicate then joins its twin.
    bd = uv_boundary(F, uv, np.where(ok & ~dup, 0, -1))
    a, b = bd.interior[:, 0] // 3, bd.interior[:, 1] // 3
    a, b = np.concatenate([where[a], np.arange(n)]), np.concatenate([where[b], twin])
    graph = sp.coo_array((np.ones(len(a)), (a, b)), shape=(n, n))
    _, comp = connected_components(graph, directed=False)
    # renumber by first face so labels follow face order
    first = np.full(comp.max() + 1, n, dtype=np.int64)
    np.minimum.at(first, comp, np.arange(n))
    rank = np.empty_like(first)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    lab[idx] = rank[comp]
    return lab


def _same_face_same_uvs(F, uv):
    """(m,) int64: for each face, the first face on the same three vertices in the same cyclic
    order with the same corner UVs (itself when it has no twin)."""
    r = np.argmin(F, axis=1)                       # rotate to start at the smallest vertex
    turn = (r[:, None] + np.arange(3)) % 3
    G = np.take_along_axis(F, turn, axis=1).astype(np.float64)
    W = np.take_along_axis(uv, turn[:, :, None], axis=1).reshape(len(F), 6)
    _, first, inv = np.unique(np.concatenate([G, W], axis=1), axis=0, return_index=True,
                              return_inverse=True)
    return first[inv.ravel()]
