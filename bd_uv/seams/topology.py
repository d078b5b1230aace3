"""Charts of a mesh cut along seams, with the topology that decides how each is cut further.

Faster than ``mesh.islands`` for the seam search, which asks again after every round of cuts:
the input was validated once, so here only the charts, their vertices, Euler characteristic and
boundary loops are found, all at once.
"""
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..geometry import HOOK_VERTICES, components
from ..solvers import radix
from .edges import index_dtype

# Boundary vertices (of all the disks of a call) up to which each loop is walked in Python.
WALK = 2000


@dataclass(frozen=True)
class Chart:
    """One chart: a connected piece of the mesh cut along the seams.

    Attributes
    ----------
    faces : (k,) int64, input face ids
    vertices : (nk,) int64, input vertex of each chart vertex
    tris : (k,3) int64, the chart's triangles in chart vertex ids
    loops : tuple of (b,) int64 arrays, the boundary loop of a disk (empty otherwise)
    kind : "disk" | "open" (genus >= 1 or several boundary loops) | "sphere" (closed, genus 0)
    error : None (the charts come from a validated mesh)
    """
    faces: np.ndarray
    vertices: np.ndarray
    tris: np.ndarray
    loops: tuple
    kind: str
    error: object = None


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
    corners = np.flatnonzero(np.repeat(mask, 3))
    if E.fans is not None:
        corner = _fan_runs(E.fans, cut, mask, corners)
    else:                                   # not an oriented manifold: a graph search
        on = np.zeros(len(E.ends), dtype=bool)
        on[E.face_edges[mask].ravel()] = True
        edges = np.flatnonzero(on & (E.faces[:, 1] >= 0) & ~cut)
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
        at = np.arange(int(lens.sum())) + np.repeat(lo - (np.cumsum(lens) - lens), lens)
        c, first, ring = fans.order[at], fans.first[at], fans.ring[at]
    else:
        c, first, ring = fans.order, fans.first, fans.ring
    nx = fans.next[c]
    # Whether position i turns to the next corner of its fan (or a ring's last to its first).
    joined = (nx >= 0) & ~cut[fans.edge[c]] & mask[c // 3] & mask[np.maximum(nx, 0) // 3]
    new = first.copy()
    new[1:] |= ~joined[:-1]
    starts = np.flatnonzero(new)
    low = np.minimum.reduceat(c, starts)
    run = np.cumsum(new, dtype=c.dtype) - 1
    # A closed fan whose last corner turns back to its first: its first and last runs are one.
    fan_first = np.flatnonzero(first)
    fan_last = np.append(fan_first[1:] - 1, len(c) - 1)
    join = ring[fan_first] & joined[fan_last] & (run[fan_first] != run[fan_last])
    a, b = run[fan_first[join]], run[fan_last[join]]
    low[a] = low[b] = np.minimum(low[a], low[b])
    del nx, joined, new
    label = np.empty(len(fans.order), dtype=low.dtype)
    label[c] = low[run]
    del run
    if sub:
        return np.unique(label[corners], return_inverse=True)[1].ravel()
    label = label[corners]
    used = np.zeros(len(fans.order), dtype=bool)
    used[label] = True
    return (np.cumsum(used, dtype=label.dtype) - 1)[label]


def charts(F, E, cut, faces=None):
    """Charts of the faces ``faces`` (default all) of the mesh cut along ``cut``.

    Parameters
    ----------
    F : (m,3) int64
    E : edges.EdgeTable
    cut : (e,) bool
    faces : (k,) int64, optional: a union of whole charts

    Returns
    -------
    list of Chart, ordered by their smallest face id
    """
    faces = np.arange(len(F)) if faces is None else np.sort(np.asarray(faces, dtype=np.int64))
    corners, corner, voc = _cut_corners(F, E, cut, faces)
    T = corner.reshape(-1, 3)               # the distinct faces' corners, in face order
    # A face listed twice is joined to its copy through their vertices only (below).
    fans = E.fans is not None and len(T) == len(faces)
    if len(T) != len(faces):
        T = T[np.searchsorted(np.unique(faces), faces)]
    del corners, corner
    # Compact the cut vertices used; faces connected through a shared cut vertex (a corner
    # glued across an uncut edge) form one chart. The per-corner arrays are int32 where the
    # ids fit (the whole-mesh call before the final unwrap held ~160 MB of them in int64 on a
    # 500k-face mesh).
    used = np.zeros(len(voc), dtype=bool)
    used[T.ravel()] = True
    ids = np.flatnonzero(used)
    tri = (np.cumsum(used, dtype=T.dtype) - 1)[T]
    del T, used
    nv, k = len(ids), len(faces)
    # Boundary half-edges: on a seam, on the mesh boundary, or next to a face not asked for
    # (the half-edge F[f,j] -> F[f,j+1] runs along edge E.face_edges[f,j]).
    inset = np.zeros(len(F), dtype=bool)
    inset[faces] = True
    fe = E.face_edges[faces].ravel()
    f0, f1 = E.faces[fe, 0], E.faces[fe, 1]
    bnd = cut[fe] | (f1 < 0) | ~inset[f0] | ~inset[np.maximum(f1, 0)]
    if fans:
        # An oriented manifold: faces meet at a cut vertex only across an uncut edge, so the
        # charts are the components of the faces joined across their inner half-edges (k
        # nodes, not the k + nv of faces and vertices), numbered by their least face alike.
        # Each inner edge once, from its first face (f0), as CSR rows of the faces.
        inner = ~bnd.reshape(k, 3) & (f0.reshape(k, 3) == faces[:, None])
        indptr = np.zeros(k + 1, dtype=np.int64)
        np.cumsum(inner.sum(axis=1), out=indptr[1:])
        other = f1[inner.ravel()]
        if k != len(F):                     # input face ids -> positions in ``faces``
            pos = np.empty(len(F), dtype=np.int64)
            pos[faces] = np.arange(k)
            other = pos[other]
        n_c, fl = _components(indptr, other, k)
        vl = np.empty(nv, dtype=fl.dtype)
        vl[tri] = fl[:, None]
        del inner, indptr, other
    else:
        idx = index_dtype(3 * k + nv + 1)
        # Faces and cut vertices, each face joined to its three corners' vertices.
        n_c, comp = _components(np.concatenate([np.arange(0, 3 * k + 1, 3, dtype=idx),
                                                np.full(nv, 3 * k, dtype=idx)]),
                                np.add(tri.ravel(), k, dtype=idx), k + nv)
        fl, vl = comp[:k], comp[k:]
    del fe, f0, f1, inset
    hb = np.flatnonzero(bnd)                # boundary half-edges, as corners of ``tri``
    del bnd
    ba, bb = tri.ravel()[hb], np.roll(tri, -1, axis=1).ravel()[hb]
    nb = np.bincount(fl[hb // 3], minlength=n_c)
    nf = np.bincount(fl, minlength=n_c)
    nvc = np.bincount(vl, minlength=n_c)
    ne = (3 * nf + nb) // 2
    chi = nvc - ne + nf
    disk = (nb > 0) & (chi == 1)
    if not fans:
        # Without fans a chart need not be a surface: its boundary loops are counted.
        bo = np.argsort(ba, kind="stable")
        _, lab = _components(np.concatenate([[0], np.cumsum(np.bincount(ba, minlength=nv))]),
                             bb[bo], nv)
        rep_v = np.full(nv, -1, dtype=np.int64)
        rep_v[lab[ba]] = ba                 # a boundary vertex of each loop
        disk &= np.bincount(vl[rep_v[rep_v >= 0]], minlength=n_c) == 1
    # (With fans every chart is an orientable surface, chi = 2 - 2 genus - loops: chi = 1 with
    # a boundary is one loop.)
    # Group faces and vertices by chart.
    forder = radix.order(fl, n_c)
    fb = np.searchsorted(fl[forder], np.arange(n_c + 1))
    vorder = radix.order(vl, n_c)
    vb = np.searchsorted(vl[vorder], np.arange(n_c + 1))
    local = np.empty(nv, dtype=np.int64)
    local[vorder] = np.arange(nv) - vb[vl[vorder]]
    loops = _disk_loops(ba, bb, vl, disk, nv, fans)
    kinds = np.where(disk, "disk", np.where((nb == 0) & (chi == 2), "sphere", "open")).tolist()
    cf, cv, ct = faces[forder], voc[ids[vorder]], local[tri[forder]]
    fbl, vbl = fb.tolist(), vb.tolist()
    # Copies of the slices: a chart kept (merging keeps its charts for rounds) holds its own
    # arrays, not the whole call's.
    out = [Chart(cf[fbl[c]:fbl[c + 1]].copy(), cv[vbl[c]:vbl[c + 1]].copy(),
                 ct[fbl[c]:fbl[c + 1]].copy(), (local[loops[c]],) if c in loops else (), kinds[c])
           for c in range(n_c)]
    out.sort(key=lambda ch: int(ch.faces[0]))
    return out


def _components(indptr, indices, n):
    """``connected_components`` (undirected) of the graph of n nodes whose edges are given as
    CSR rows (``indptr``, ``indices``), built directly: no COO conversion or index checks, a
    measurable share of a small mesh's seam search, which asks every round.

    Graphs of up to ``geometry.HOOK_VERTICES`` nodes go to ``geometry.components`` (min-label
    hooking, no sparse set-up: the charts of a small mesh's rounds), numbered alike.

    Returns
    -------
    (count, (n,) int labels), numbered as ``connected_components`` numbers them
    """
    if n <= HOOK_VERTICES:
        return components(n, np.repeat(np.arange(n), np.diff(indptr)), indices)
    g = sp.csr_matrix((np.ones(len(indices)), indices.astype(np.int32, copy=False),
                       indptr.astype(np.int32, copy=False)), shape=(n, n))
    return connected_components(g, directed=True, connection="weak")


def _disk_loops(ba, bb, vl, disk, nv, walk=False):
    """The boundary loop of every disk chart at once, by list ranking (pointer doubling).

    Each boundary vertex of a disk has one outgoing boundary half-edge (a cut vertex is one
    fan of corners), so a disk's boundary is one cycle; it is read from its first vertex in
    ``ba`` order, following the half-edges.

    Parameters
    ----------
    ba, bb : (b,) int64, boundary half-edges ``ba -> bb`` (cut vertex ids, all charts)
    vl : (nv,) int64, chart of each cut vertex
    disk : (n_c,) bool
    walk : bool, every boundary vertex has one half-edge in and one out (the charts of an
        oriented manifold): up to ``WALK`` boundary vertices, each loop is followed in Python

    Returns
    -------
    dict chart -> (L,) int64 cut vertex ids of its loop in order
    """
    sel = disk[vl[ba]]
    sa, sb = ba[sel], bb[sel]
    if len(sa) == 0:
        return {}
    cs = vl[sa]
    charts_, first = np.unique(cs, return_index=True)
    if walk and len(sa) <= WALK:
        # The same loops, from the same first vertex: fewer steps than the doubling's numpy
        # calls (a dozen per round, ~log2 of the longest loop rounds).
        nx = dict(zip(sa.tolist(), sb.tolist()))
        out = {}
        for c, x in zip(charts_.tolist(), sa[first].tolist()):
            loop = [x]
            for _ in range(len(sa)):
                x = nx[x]
                if x == loop[0]:
                    break
                loop.append(x)
            out[c] = np.array(loop, dtype=sa.dtype)
        return out
    nxt = np.arange(nv)
    nxt[sa] = sb
    pred = np.full(nv, -1, dtype=np.int64)
    pred[sb] = sa
    term = pred[sa[first]]                  # each loop ends just before its start
    nxt[term] = term
    r = np.zeros(nv, dtype=np.int64)
    r[sa] = 1
    r[term] = 0
    while True:
        s_ = nxt[sa]
        if np.all(nxt[s_] == s_):
            r[sa] = r[sa] + r[s_] * (s_ != sa)
            break
        r[sa], nxt[sa] = r[sa] + r[s_], nxt[s_]
    # r: steps to the loop's end; the start has the most.
    order = np.lexsort((-r[sa], cs))
    bounds = np.searchsorted(cs[order], charts_)
    ends = np.append(bounds[1:], len(order))
    return {int(c): sa[order[b:e]] for c, b, e in zip(charts_, bounds, ends)}
