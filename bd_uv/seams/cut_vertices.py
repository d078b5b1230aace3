"""The mesh cut open along seams: the cut vertex of every corner, corners glued across uncut
interior edges only, from the edge table's fans on an oriented manifold (runs of each vertex's
fan between cut edges), else by a graph search over the corners. ``topology.charts`` groups the
cut mesh into charts.
"""
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .edges import index_dtype


def cut_mesh(F, E, cut, faces=None):
    """The mesh cut open along the seams: corners glued across uncut interior edges only.

    Parameters
    ----------
    F : (m,3) int64
    E : edges.EdgeTable
    cut : (e,) bool, the seams
    faces : (k,) int64, optional: only these faces (a union of whole charts)

    Returns
    -------
    Fc : (m,3) int64, faces in cut vertex ids (-1 on faces not asked for)
    voc : (nc,) int64, the input vertex of each cut vertex
    """
    m = len(F)
    corners, corner, voc = _cut_corners(F, E, cut, faces)
    Fc = np.full(3 * m, -1, dtype=np.int64)
    Fc[corners] = corner
    return Fc.reshape(m, 3), voc


def _cut_corners(F, E, cut, faces):
    """``cut_mesh``'s cut vertices for the corners of ``faces`` only: (corners (k,) int64
    increasing, corner (k,) int32 (int64 from 2**31 corners on) the cut vertex of each,
    voc). ``charts`` reads them without the (m,3) array over the whole mesh."""
    m = len(F)
    if faces is None:
        mask = np.ones(m, dtype=bool)
    else:
        mask = np.zeros(m, dtype=bool)
        mask[faces] = True
    # Only the corners of the faces asked for take part.
    corners = np.repeat(mask, 3).ravel().nonzero()[0]
    if E.fans is not None:
        corner = _fan_runs(E.fans, cut, mask, corners)
    else:                                   # not an oriented manifold: a graph search
        on = np.zeros(len(E.ends), dtype=bool)
        on[E.face_edges[mask].ravel()] = True
        edges = (on & (E.faces[:, 1] >= 0) & ~cut).ravel().nonzero()[0]
        edges = edges[mask[E.faces[edges, 0]] & mask[E.faces[edges, 1]]]
        cn = E.corners[edges]
        rows, cols = [cn[:, 0, 0], cn[:, 0, 1]], [cn[:, 1, 0], cn[:, 1, 1]]
        pos = np.full(3 * m, -1, dtype=np.int64)
        pos[corners] = np.arange(len(corners))
        rows, cols = pos[np.concatenate(rows)], pos[np.concatenate(cols)]
        g = sp.coo_array((np.ones(len(rows)), (rows, cols)), shape=(len(corners), len(corners)))
        _, corner = connected_components(g, directed=False)
    corner = corner.astype(index_dtype(3 * m), copy=False)
    voc = np.empty(int(corner.max()) + 1 if len(corner) else 0, dtype=np.int64)
    voc[corner] = F.ravel()[corners]
    return corners, corner, voc


def _fan_runs(fans, cut, mask, corners):
    """Cut vertex of every corner from the fans: the corners around a vertex split into runs
    at every cut edge and every face not asked for, each run one cut vertex.

    Runs are numbered by their smallest corner, as a graph search over the corners would number
    its components (so the charts come out the same either way). When the corners asked for are
    a small share of the mesh's, only their fans are read (the late rounds of a seam search ask
    about a few small charts of a large mesh).

    Parameters
    ----------
    fans : edges.Fans, cut : (e,) bool, mask : (m,) bool faces asked for
    corners : (k,) int64, the corners of the faces asked for, increasing

    Returns
    -------
    (k,) int64, the cut vertex of each of ``corners``, 0.. in the order of their smallest corner
    """
    sub = 4 * len(corners) < len(fans.order)
    if sub:                                 # the positions of the fans the corners lie in
        f = np.unique(fans.fan[corners])
        lo, hi = fans.starts[f], fans.starts[f + 1]
        lens = hi - lo
        at = np.arange(int(lens.sum())) + np.repeat(lo - (lens.cumsum() - lens), lens)
        c, first, ring = fans.order[at], fans.first[at], fans.ring[at]
    else:
        c, first, ring = fans.order, fans.first, fans.ring
    # (``take``: numpy's gathers by an int32 index by fancy index are ~2x dearer)
    nx = fans.next.take(c)
    # Whether position i turns to the next corner of its fan (or a ring's last to its first).
    joined = ((nx >= 0) & ~cut.take(fans.edge.take(c)) & mask.take(c // 3)
              & mask.take(np.maximum(nx, 0) // 3))
    new = first.copy()
    new[1:] |= ~joined[:-1]
    starts = new.ravel().nonzero()[0]
    low = np.minimum.reduceat(c, starts)
    run = new.cumsum(dtype=c.dtype) - 1
    # A closed fan whose last corner turns back to its first: its first and last runs are one.
    fan_first = first.ravel().nonzero()[0]
    fan_last = np.append(fan_first[1:] - 1, len(c) - 1)
    join = ring[fan_first] & joined[fan_last] & (run[fan_first] != run[fan_last])
    a, b = run[fan_first[join]], run[fan_last[join]]
    low[a] = low[b] = np.minimum(low[a], low[b])
    del nx, joined, new
    label = np.empty(len(fans.order), dtype=low.dtype)
    label[c] = low.take(run)
    del run
    if sub:
        return np.unique(label[corners], return_inverse=True)[1].ravel()
    label = label[corners]
    used = np.zeros(len(fans.order), dtype=bool)
    used[label] = True
    return (used.cumsum(dtype=label.dtype) - 1)[label]
