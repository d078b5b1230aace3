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
from .cut_vertices import _cut_corners, cut_mesh
from .edges import index_dtype

__all__ = ["WALK", "Chart", "charts", "cut_mesh"]  # cut_mesh: cut_vertices.py's, as it was here

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
        T = T[np.unique(faces).searchsorted(faces)]
    del corners, corner
    # Compact the cut vertices used; faces connected through a shared cut vertex (a corner
    # glued across an uncut edge) form one chart. The per-corner arrays are int32 where the
    # ids fit (the whole-mesh call before the final unwrap held ~160 MB of them in int64 on a
    # 500k-face mesh).
    used = np.zeros(len(voc), dtype=bool)
    used[T.ravel()] = True
    ids = used.ravel().nonzero()[0]
    tri = (used.cumsum(dtype=T.dtype) - 1).take(T)
    del T, used
    nv, k = len(ids), len(faces)
    # Boundary half-edges: on a seam, on the mesh boundary, or next to a face not asked for
    # (the half-edge F[f,j] -> F[f,j+1] runs along edge E.face_edges[f,j]).
    inset = np.zeros(len(F), dtype=bool)
    inset[faces] = True
    # (``take``: numpy's gathers of rows, or by an int32 index, by fancy index are ~2-4x
    # dearer; the same values)
    fe = E.face_edges.take(faces, axis=0).ravel()
    f01 = E.faces.take(fe, axis=0)
    f0, f1 = f01[:, 0].copy(), f01[:, 1].copy()
    del f01
    bnd = cut.take(fe) | (f1 < 0) | ~inset.take(f0) | ~inset.take(np.maximum(f1, 0))
    if fans:
        # An oriented manifold: faces meet at a cut vertex only across an uncut edge, so the
        # charts are the components of the faces joined across their inner half-edges (k
        # nodes, not the k + nv of faces and vertices), numbered by their least face alike.
        # Each inner edge once, from its first face (f0), as CSR rows of the faces.
        inner = ~bnd.reshape(k, 3) & (f0.reshape(k, 3) == faces[:, None])
        indptr = np.zeros(k + 1, dtype=np.int64)
        inner.sum(axis=1).cumsum(out=indptr[1:])
        other = f1.compress(inner.ravel())
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
    hb = bnd.ravel().nonzero()[0]                # boundary half-edges, as corners of ``tri``
    del bnd
    # (the next corner of each half-edge's face by its index: no (k,3) ``np.roll`` copy)
    flat_tri = tri.ravel()
    ba, bb = flat_tri[hb], flat_tri[hb - hb % 3 + (hb + 1) % 3]
    nb = np.bincount(fl[hb // 3], minlength=n_c)
    nf = np.bincount(fl, minlength=n_c)
    nvc = np.bincount(vl, minlength=n_c)
    ne = (3 * nf + nb) // 2
    chi = nvc - ne + nf
    disk = (nb > 0) & (chi == 1)
    if not fans:
        # Without fans a chart need not be a surface: its boundary loops are counted.
        bo = ba.argsort(kind="stable")
        _, lab = _components(np.concatenate([[0], np.bincount(ba, minlength=nv).cumsum()]),
                             bb[bo], nv)
        rep_v = np.full(nv, -1, dtype=np.int64)
        rep_v[lab[ba]] = ba                 # a boundary vertex of each loop
        disk &= np.bincount(vl[rep_v[rep_v >= 0]], minlength=n_c) == 1
    # (With fans every chart is an orientable surface, chi = 2 - 2 genus - loops: chi = 1 with
    # a boundary is one loop.)
    # Group faces and vertices by chart.
    forder = radix.order(fl, n_c)
    fb = fl[forder].searchsorted(np.arange(n_c + 1))
    vorder = radix.order(vl, n_c)
    vb = vl[vorder].searchsorted(np.arange(n_c + 1))
    local = np.empty(nv, dtype=np.int64)
    local[vorder] = np.arange(nv) - vb[vl[vorder]]
    loops = _disk_loops(ba, bb, vl, disk, nv, fans)
    kinds = np.where(disk, "disk", np.where((nb == 0) & (chi == 2), "sphere", "open")).tolist()
    cf, cv, ct = faces[forder], voc[ids[vorder]], local.take(tri.take(forder, axis=0))
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
    bounds = cs[order].searchsorted(charts_)
    ends = np.append(bounds[1:], len(order))
    return {int(c): sa[order[b:e]] for c, b, e in zip(charts_, bounds, ends)}
