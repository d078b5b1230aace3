"""The charts of pairs of neighbouring charts once the seams between them are removed (the unions
``merge.merge_charts`` tests), found from the two charts themselves: the same ``topology.Chart``
that ``topology.charts`` finds on the trial cut (faces, vertices, triangles, boundary loop and
kind, array for array), without reading the fans of every corner of the unions again.

Only on an oriented manifold (the edge table has fans): a chart vertex is a run of corners
around a mesh vertex between cut edges, so removing a seam edge joins, at each of its two ends,
the vertex of one chart to the vertex of the other, and nothing else changes.
"""
import numpy as np

from ..geometry import components
from .topology import Chart, _disk_loops
from ..trim import CHUNK


def union_charts(F, E, chs, label, xs, ys, removed, owner, trial):
    """The union of charts ``chs[xs[i]]`` and ``chs[ys[i]]`` for every i.

    Parameters
    ----------
    F : (m,3) int64, E : edges.EdgeTable with ``fans``
    chs : list of topology.Chart, the charts of the cut before the seams are removed
    label : (m,) int64, the chart (index into ``chs``) of each face
    xs, ys : (p,) int64, the two charts of each union (each chart in at most one union)
    removed : (r,) int64, the edges removed (each between the two charts of its union)
    owner : (r,) int64, the union (0..p-1) of each removed edge
    trial : (e,) bool, the cut with ``removed`` uncut

    Returns
    -------
    list of (i, topology.Chart), ordered by each union's least face (``topology.charts``' order)
    """
    p = len(xs)
    parts = [chs[c] for pair in zip(xs, ys) for c in pair]
    nv = np.array([len(c.vertices) for c in parts], dtype=np.int64)
    nf = np.array([len(c.faces) for c in parts], dtype=np.int64)
    voff = np.concatenate([[0], nv.cumsum()])
    N = int(voff[-1])
    # Per-corner arrays in int32 where the ids fit (a merge round of a 500k-face mesh covers
    # it whole: (m,3) int64 arrays are 12 MB each), dropped as soon as read.
    it = np.int32 if 2 * N + 3 * int(nf.sum()) < 2 ** 31 else np.int64
    part = np.repeat(np.arange(2 * p, dtype=it), nf)
    faces = np.concatenate([c.faces for c in parts])
    # Faces by union, then by face id (each union's faces sorted, as ``charts`` lists them).
    m = len(F)
    key = (part // 2).astype(np.int64) * m + faces      # distinct; each chart's faces a run
    order = key.argsort(kind="stable")  # (runs: a merge of sorted runs, no full sort)
    key, uf, fu = key[order], faces[order], part[order] // 2
    del faces, part
    # The parts' triangles at once in ``it``, each shifted by its part's vertex offset (the
    # same integers as part by part, without two temporaries a part).
    T = np.concatenate([c.tris for c in parts], dtype=it, casting="unsafe")
    T += np.repeat(voff[:-1].astype(it), nf)[:, None]
    T = T.take(order, axis=0)          # (``take``: numpy's row gather by fancy index is ~4x dearer)
    del order
    # Each removed edge joins, at each end, the vertex of its face on one side to the vertex
    # of its face on the other (the half-edges F[f,j] -> F[f,j+1] of the two faces run
    # opposite ways along it).
    f0, f1 = E.faces[removed, 0].astype(np.int64), E.faces[removed, 1].astype(np.int64)
    p0 = key.searchsorted(owner * m + f0)
    p1 = key.searchsorted(owner * m + f1)
    del key
    j0 = np.argmax(E.face_edges[f0] == removed[:, None], axis=1)
    j1 = np.argmax(E.face_edges[f1] == removed[:, None], axis=1)
    a = np.concatenate([T[p0, j0], T[p0, (j0 + 1) % 3]])
    b = np.concatenate([T[p1, (j1 + 1) % 3], T[p1, j1]])
    # Components of the few vertices the removed edges touch; the others stay alone.
    touched = np.unique(np.concatenate([a, b]))
    _, cl = components(len(touched), touched.searchsorted(a), touched.searchsorted(b))
    lab = np.arange(N, dtype=it)
    lab[touched] = N + cl                   # labels apart from the untouched vertices'
    # Union vertices numbered by their first corner (faces in order, then corner): ``charts``
    # numbers cut vertices by their least corner, and a union's corners run in that order.
    # (A component's first corner by ``minimum.at``: no sort of the corners.)
    flat = lab.take(T.ravel())
    del T
    L = len(flat)
    first = np.full(N + len(touched), L, dtype=np.int64)
    np.minimum.at(first, flat, np.arange(L))
    uniq = (first < L).ravel().nonzero()[0]
    new = np.empty(len(first), dtype=it)
    new[uniq[first[uniq].argsort()]] = np.arange(len(uniq), dtype=it)
    del first
    n = len(uniq)
    vm = np.empty(n, dtype=np.int64)
    vm[new[lab]] = np.concatenate([c.vertices for c in parts])
    del lab
    tri = new.take(flat).reshape(-1, 3)
    del flat, new
    vu = np.empty(n, dtype=it)
    vu[tri.ravel()] = np.repeat(fu, 3)
    # Boundary half-edges: on a seam of the trial cut, on the mesh boundary, or to a face of
    # another chart (a column at a time: (k,) temporaries, not (k,3)).
    fe = E.face_edges.take(uf, axis=0)
    bnd = trial.take(fe)
    mine = np.full(len(chs), -1, dtype=it)
    mine[xs] = mine[ys] = np.arange(p, dtype=it)
    for j in range(3):
        o = E.faces.take(fe[:, j], axis=0)
        o0, o1 = o[:, 0], o[:, 1]
        other = np.where(o0 == uf, o1, o0)
        bnd[:, j] |= (other < 0) | (mine.take(label.take(np.maximum(other, 0))) != fu)
    del fe, o, o0, o1, other
    nb = np.bincount(fu, bnd.sum(axis=1), minlength=p).astype(np.int64)
    nfu = np.bincount(fu, minlength=p)
    nvu = np.bincount(vu, minlength=p)
    chi = nvu - (3 * nfu + nb) // 2 + nfu
    disk = (nb > 0) & (chi == 1)
    kinds = np.where(disk, "disk", np.where((nb == 0) & (chi == 2), "sphere", "open")).tolist()
    hb = bnd.ravel().nonzero()[0]
    del bnd
    # (the next corner of each half-edge's face by its index: no (k,3) ``np.roll`` copy)
    flat_tri = tri.ravel()
    ba, bb = flat_tri[hb], flat_tri[hb - hb % 3 + (hb + 1) % 3]
    loops = _disk_loops(ba, bb, vu, disk, n, True)
    del ba, bb, hb, vu
    fb = np.concatenate([[0], nfu.cumsum()]).tolist()
    vb = np.concatenate([[0], nvu.cumsum()]).tolist()
    out = []
    # Chart-local ids in int64, as ``charts`` gives: converted at once on a small round (one
    # call, not one a union), union by union on a large one (no (k,3) int64 copy beside them).
    t64 = tri.astype(np.int64) if len(tri) <= CHUNK else None
    for i in range(p):
        s, e, v0 = fb[i], fb[i + 1], vb[i]
        out.append((i, Chart(uf[s:e].copy(), vm[v0:vb[i + 1]].copy(),
                             (t64[s:e] if t64 is not None else tri[s:e].astype(np.int64)) - v0,
                             (loops[i].astype(np.int64) - v0,) if i in loops else (),
                             kinds[i])))
    out.sort(key=lambda t: int(t[1].faces[0]))
    return out
