"""Splitting a chart in two along its cheapest neck (spectral bisection with a Cheeger sweep).

The charts' Fiedler vectors come from ``fiedler.fiedler_vectors``; here each chart's faces are
swept in their order for the least cut per area, the cut snapped to the cheapest one near it (an
s-t min cut) and straightened by a majority filter.
"""
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, maximum_flow

from ..geometry import components
from ..solvers import radix
from .compressed import compressed
from .fiedler import fiedler_vectors
from ..trim import TRIM_FACES, release_memory

# Neither side of a split may hold less than this share of the chart's area.
MIN_SIDE = 0.05
# Dual rings on each side of a sweep cut within which the min cut may move it.
BAND_RINGS = 4


def fiedler_split(face_area, centroid, pairs, edge_len, edge_cost):
    """Two-way split of a chart's faces along a cheap, short, straight cut.

    The Fiedler vector of the chart's dual graph (edge weights ``length * cost / centroid
    distance``, face areas as mass) orders the faces smoothly along the chart's longest extent;
    the sweep then picks the prefix whose cut weight per area of the smaller side
    (``sum(length * cost) / min(A1, A2)``, the Cheeger ratio) is least, which falls on necks and
    creases. A majority filter then moves every face with two of its three neighbours on the
    other side across, which turns staircases into straight runs along edge loops.

    Parameters
    ----------
    face_area : (k,) float64
    centroid : (k,3) float64
    pairs : (e,2) int64, chart-local face pairs sharing an edge that may be cut
    edge_len, edge_cost : (e,) float64, length and seam cost of each such edge

    Returns
    -------
    side : (k,) bool, or None when the chart cannot be split
    """
    side, split = fiedler_split_many(face_area, centroid, np.array([0, len(face_area)]),
                                     np.asarray(pairs, np.int64).reshape(-1, 2), edge_len,
                                     edge_cost)
    return side if split[0] else None


def fiedler_split_many(face_area, centroid, offsets, pairs, edge_len, edge_cost, keys=None,
                       dist=None):
    """``fiedler_split`` of many charts at once: one block-diagonal factorisation, every step
    vectorised over the charts (the same cut for each chart as alone, up to rounding).

    Parameters
    ----------
    face_area : (k,) float64, centroid : (k,3) float64, the nodes of all charts, chart by chart
    offsets : (g+1,) int64, chart j owns nodes ``offsets[j]:offsets[j+1]``
    pairs : (e,2) int64, node pairs (within one chart) sharing an edge that may be cut
    edge_len, edge_cost : (e,) float64
    keys : (k,) int64, optional, the nodes' elimination keys (``orders.fiedler_solver``: -1
        where a chart is to be ordered afresh; rewritten in place where it is)
    dist : (e,) float64, optional, the distance between each pair's centroids (formed here
        when not given, ``np.linalg.norm`` row by row: the same bits)

    Returns
    -------
    side : (k,) bool
    split : (g,) bool, whether each chart was split (else its ``side`` means nothing)
    """
    k, g = len(face_area), len(offsets) - 1
    release_memory(k)                       # the round's freed arrays, before the factors
    size = np.diff(offsets)
    group = np.repeat(np.arange(g), size)
    split = np.zeros(g, dtype=bool)
    side = np.zeros(k, dtype=bool)
    if k == 0 or len(pairs) == 0:
        return side, split
    if pairs.dtype != np.int64 and k <= TRIM_FACES:
        # The pairs in int64 (the same values): numpy gathers by an int32 index on its slow
        # path (~2x), ~15 of them here; kept int32 on large charts (memory: bisect.py).
        pairs = pairs.astype(np.int64)
    pg = group[pairs[:, 0]]
    npairs = np.bincount(pg, minlength=g)
    live = (size >= 2) & (npairs > 0)
    d = (np.linalg.norm(centroid[pairs[:, 0]] - centroid[pairs[:, 1]], axis=1) if dist is None
         else dist)
    mean_len = np.bincount(pg, edge_len, g) / np.maximum(npairs, 1)
    w = edge_len * edge_cost / np.maximum(d, 1e-12 * mean_len[pg])
    del pg, d                               # per pair: dead before the factors
    x = fiedler_vectors(pairs, w, face_area, centroid, offsets, group, keys=keys)
    if x is None:
        return side, split
    release_memory(k)                       # the factors' freed heap, before the sweep's arrays
    # Sweep per chart: order by rounded x (ties by node), prefixes of 1..k_j-1 nodes.
    start = offsets[:-1]
    scale = np.zeros(g)
    np.maximum.at(scale, group, np.abs(x))
    q = np.maximum(scale * 1e-9, 1e-300)[group]
    order = _sweep_order(np.round(x / q), group, g)
    del x, q                                # each dead array dropped as soon as read: the
    pos = np.empty(k, dtype=np.int64)       # first round's sweep over a 500k-node sphere is
    pos[order] = np.arange(k)               # one of the search's memory peaks
    rank = pos - start[group]
    c = edge_len * edge_cost
    lo = np.minimum(pos[pairs[:, 0]], pos[pairs[:, 1]])
    hi = np.maximum(pos[pairs[:, 0]], pos[pairs[:, 1]])
    del pos
    diff = np.bincount(lo + 1, c, minlength=k + 1) - np.bincount(hi + 1, c, minlength=k + 1)
    del lo, hi
    cutw = diff.cumsum()                 # cutw[start_j + t]: prefix of t nodes of chart j
    del diff
    acum = face_area[order].cumsum()
    base = np.concatenate([[0.0], acum])[start]
    total = np.bincount(group, face_area, g)
    p = np.arange(k)
    t = rank[order]                        # = p - start[group[order]]: nodes before p
    gp = group[order]
    valid = t >= 1                         # prefix of t >= 1 nodes, t <= k_j - 1
    A = acum[p - 1] - base[gp]             # area of the first t nodes
    A = np.where(valid, A, 0.0)
    del acum, base
    small = np.minimum(A, total[gp] - A)
    raw_score = np.where(valid, cutw[p] / np.maximum(small, 1e-300), np.inf)
    del cutw, valid
    score = np.where(small >= MIN_SIDE * total[gp], raw_score, np.inf)
    del A, small
    none = np.bincount(gp, np.isfinite(score), g) == 0
    score = np.where(none[gp], raw_score, score)
    sscale = np.zeros(g)
    fin = np.isfinite(score)
    np.maximum.at(sscale, gp[fin], np.abs(score[fin]))
    sq = np.maximum(sscale * 1e-9, 1e-300)[gp]
    first = _least_per_group(np.where(fin, np.round(score / sq), np.inf), gp, g)
    tg = np.zeros(g, dtype=np.int64)
    tg[gp[first]] = t[first]
    side = rank < tg[group]
    # The sweep's ~25 per-node arrays are dead now: dropped before the min cut and the filters
    # (a 500k-node sphere's first split was the search's memory peak).
    del order, rank, p, t, gp, raw_score, score, none, sscale, fin, sq, first, tg
    side = _snap_many(side, pairs, c, group, g)
    raw = side.copy()
    # Majority filter: a node with two or three neighbours across moves over (never two
    # neighbours at once, which could leave a checkerboard), a few passes.
    for _ in range(4):
        other = side[pairs[:, 0]] != side[pairs[:, 1]]
        move = np.bincount(pairs[other].ravel(), minlength=k) >= 2
        both = move[pairs[:, 0]] & move[pairs[:, 1]]
        move[np.maximum(pairs[both, 0], pairs[both, 1])] = False
        if not move.any():
            break
        side = side ^ move
    # Pieces cut off from their side's bulk (a few nodes) go to the other side; a chart left
    # all on one side keeps its snapped cut.
    same = side[pairs[:, 0]] == side[pairs[:, 1]]
    _, comp = components(k, pairs[:, 0][same], pairs[:, 1][same])
    csize = np.bincount(comp)
    side = side ^ (csize[comp] < np.maximum(3, 0.02 * size)[group])
    ones = np.bincount(group, side, g)
    uniform = (ones == 0) | (ones == size)
    side = np.where(uniform[group], raw, side)
    ones = np.bincount(group, side, g)
    split = live & (ones > 0) & (ones < size)
    return side, split


def _sweep_order(r, group, g):
    """``np.lexsort((np.arange(k), r, group))``: nodes by chart, then by ``r`` (rounded
    ``x / q``: integers of magnitude at most ~1e9), ties by node; by 16-bit radix passes
    (``solvers.radix``) where every ``r`` is finite, numpy's lexsort otherwise (and for more
    than ``radix.LARGE`` nodes: the sweep over a 500k-face sphere is a memory peak)."""
    k = len(r)
    if k == 0 or k > radix.LARGE or not np.isfinite(r).all() or np.abs(r).max() >= 2.0 ** 31:
        return np.lexsort((np.arange(k), r, group))
    key = group.astype(np.int64) << 32 | (r.astype(np.int64) + (1 << 31))
    return radix.order(key, max(g, 1) << 32, passes=4)


def _least_per_group(s, gp, g):
    """The first node of each chart's least ``s`` (ties by node), as the first of each chart in
    ``np.lexsort((np.arange(k), s, gp))`` (``gp`` non-decreasing; ``s`` integers or inf), without
    the sort; the lexsort where an ``s`` is NaN."""
    k = len(s)
    if np.isnan(s).any():
        best = np.lexsort((np.arange(k), s, gp))
        return best[np.r_[True, gp[best][1:] != gp[best][:-1]]]
    least = np.full(g, np.inf)
    np.minimum.at(least, gp, s)
    idx = (s == least[gp]).ravel().nonzero()[0]
    return idx[np.r_[True, gp[idx][1:] != gp[idx][:-1]]]


def _snap_many(side, pairs, cost, group, g, rings=BAND_RINGS):
    """Move each chart's two-way cut to the cheapest one within a band of faces around it.

    The faces more than ``rings`` dual steps from the cut keep their side (the source and the
    sink); inside the band the cut is free, so it runs along creases (cheap edges) and takes the
    shortest route, straight where the mesh has a straight edge loop, rather than the level
    set's staircase. All charts go into one s-t min cut: they share only the source and the
    sink, so each gets its own minimum cut (the source side reachable in the residual graph is
    the unique smallest one).

    Parameters
    ----------
    side : (k,) bool, pairs : (e,2) int64 neighbouring nodes (within a chart)
    cost : (e,) float64 > 0, the seam cost of each shared edge (length times crease discount)
    group : (k,) int64 chart of each node, g : int charts

    Returns
    -------
    (k,) bool
    """
    k = len(side)
    across = side[pairs[:, 0]] != side[pairs[:, 1]]
    band = np.zeros(k, dtype=bool)
    band[pairs[across].ravel()] = True
    p0, p1 = pairs[:, 0], pairs[:, 1]
    for _ in range(rings):              # one dual ring more on each side
        grow = band.copy()
        grow[p1.compress(band[p0])] = True      # (``compress``: ~3x cheaper than a mask)
        grow[p0.compress(band[p1])] = True
        band = grow
    src = ~band & side
    snk = ~band & ~side
    active = (np.bincount(group, src, g) > 0) & (np.bincount(group, snk, g) > 0)
    if not active.any():
        return side
    pg = group[pairs[:, 0]]
    cmax = np.zeros(g)
    np.maximum.at(cmax, pg, cost)
    cap = np.maximum(np.round(cost * (1e4 / np.maximum(cmax, 1e-300))[pg]), 1).astype(np.int64)
    # The flow runs on the band only: every chart's source faces are contracted into the source
    # and its sink faces into the sink (they are joined to them by uncuttable edges), which
    # leaves the minimum cut, and the smallest source side, as they are.
    live = band & active[group]
    nb = int(live.sum())
    node = np.full(k, -1, dtype=np.int64)
    node[live] = np.arange(nb)
    node[src & active[group]] = nb
    node[snk & active[group]] = nb + 1
    na, nb_ = node[pairs[:, 0]], node[pairs[:, 1]]
    on = (na >= 0) & (nb_ >= 0) & (na != nb_) & ((na < nb) | (nb_ < nb))
    pa, pb, cp = na.compress(on), nb_.compress(on), cap.compress(on)
    data, indices, indptr = compressed(np.concatenate([pa, pb]), np.concatenate([pb, pa]),
                                        np.concatenate([cp, cp]), nb + 2)
    G = sp.csr_matrix((np.minimum(data, 2 ** 30).astype(np.int32), indices, indptr),
                      shape=(nb + 2, nb + 2))
    flow = maximum_flow(G, nb, nb + 1).flow
    if np.array_equal(flow.indptr, G.indptr) and np.array_equal(flow.indices, G.indices):
        # The flow on G's own pattern (G is symmetric): the residual graph keeps G's edges
        # with capacity left, no sparse subtraction.
        left = G.data > flow.data
        rows = np.repeat(np.arange(nb + 2), np.diff(indptr))
        rptr = np.zeros(nb + 3, dtype=np.int32)
        np.bincount(rows[left], minlength=nb + 2).cumsum(out=rptr[1:])
        residual = sp.csr_matrix((np.ones(len(rows[left])), indices[left], rptr),
                                 shape=G.shape)
    else:
        residual = (G - flow).tocsr()
        residual.data = (residual.data > 0).astype(np.float64)
        residual.eliminate_zeros()
    reach = breadth_first_order(residual, nb, directed=True, return_predecessors=False)
    new = np.zeros(nb + 2, dtype=bool)
    new[reach] = True
    out = side.copy()
    out[live] = new[:nb]
    return out
