"""Cuts that open a chart into a disk: the handles of a genus-g surface and the paths that join
its boundary loops (tree-cotree, Eppstein 2003; greedy shortest loops, Erickson and Whittlesey
2005)."""
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra, minimum_spanning_tree

from ..geometry import components
from ..solvers import radix
from .compressed import compressed
from .tree_ties import canonical_predecessors, distinct_ranks
from ..array_calls import quiet

# Roots tried (farthest-point samples) for the loops of a closed chart of genus >= 1.
ROOT_TRIES = 6
# Edge weights are whole multiples of a quantum, a power of two near this share of their 10th
# percentile (below the polygons' diagonals, weighted a million times):
# rounding noise (the same mesh stored as float32) then leaves equal lengths equal, path sums are
# exact, and shortest-path ties and the choice between equally short loop systems fall the same
# way (by index) every time. Each weight moves by at most half a quantum (6e-5 of that length).
QUANTUM = 2.0 ** -10
# Quanta still straddle a rounding boundary here and there, so sums over many edges (a root's
# distance, a loop system's length) can differ by a few quanta: within this share they tie.
TIE = 1e-3
# ``cut_graphs``: charts of at most this many triangles share one batched shortest-path tree
# (genus 0 with a boundary), in runs of at most BATCH_TRIS triangles (~20 arrays of a run's
# corners and edges at once: ~10 MB at 20,000); larger ones go alone.
SMALL_TRIS = 5_000
BATCH_TRIS = 20_000


def cut_graph(tris, nv, weight):
    """Edges to cut so that a connected manifold chart becomes one disk.

    Each boundary loop is capped by a virtual vertex; on the closed surface so obtained a
    shortest-path tree T from the root (a cap, when there is one) and a dual spanning tree of the
    faces not crossed by T leave exactly 2g edges, each closing one loop through T. The cut is
    those loops plus the tree paths from the root to every cap, without the caps' edges: the
    handles' shortest generators and the shortest paths joining the boundary loops.

    Parameters
    ----------
    tris : (k,3) int64, the chart's triangles in chart vertex ids 0..nv-1
    nv : int
    weight : callable((e,2) int64 chart vertex pairs) -> (e,) float64 > 0, cost of cutting each
        edge (its length times the crease discount)

    Returns
    -------
    (c,2) int64, chart vertex pairs to cut. Empty for a disk and for a closed sphere (which
    needs a cut that this graph cannot choose: see ``split.fiedler_split``).
    """
    a = tris.ravel()
    b = tris.take([1, 2, 0], axis=1).ravel()          # (``np.roll``'s values, cheaper)
    fwd = a * nv + b
    # A half-edge is on the boundary where its reverse is no half-edge: ``np.isin`` as one sort
    # and one search (isin's set-up, ~50 us, was a tenth of a small chart's cut graph).
    rev = np.sort(b * nv + a)
    boundary = (rev[np.minimum(rev.searchsorted(fwd), len(rev) - 1)] != fwd if len(rev)
                else np.zeros(0, dtype=bool))
    del rev
    ba, bb = a[boundary], b[boundary]
    # Cap each boundary loop with a virtual vertex nv + loop and a fan of faces (bb, ba, cap).
    if len(ba):
        _, comp = components(nv, ba, bb)
        labels, loop_of = np.unique(comp[ba], return_inverse=True)
        caps = nv + loop_of.ravel()
        n_caps = len(labels)
        all_tris = np.concatenate([tris, np.stack([bb, ba, caps], axis=1)])
    else:
        n_caps = 0
        all_tris = tris
    N = nv + n_caps
    ea = all_tris.ravel()
    eb = all_tris.take([1, 2, 0], axis=1).ravel()
    key = np.minimum(ea, eb) * N + np.maximum(ea, eb)
    uniq, inv, _ = radix.unique(key, N * N)      # np.unique's, by radix passes
    ends = np.stack([uniq // N, uniq % N], axis=1)
    real = ends[:, 1] < nv
    w = np.full(len(uniq), 0.0)
    w[real] = weight(ends[real])
    w = quantised_weights(w, real)
    # What every root shares: the edge graph, and each edge's two faces.
    G = _csr(w, ends[:, 0], ends[:, 1], N)
    if n_caps and _genus0(N, len(uniq), len(all_tris)):
        # Genus 0 (the capped surface's Euler characteristic is 2: an annulus, a disk with
        # holes) leaves no edge outside the tree and the cotree (2g = 0 of them): the cut is
        # the tree paths from the caps alone; the dual spanning tree need not be formed.
        pred = _shortest_tree(G, nv, ends, w)[1]
        return _tree_paths(np.zeros(0, np.int64), pred, uniq, ends, w, N, nv, n_caps)[0]
    order = inv.argsort(kind="stable")
    first = inv[order].searchsorted(np.arange(len(uniq)))
    f0, f1 = order[first] // 3, order[first + 1] // 3
    graph = (G, uniq, ends, w, f0, f1, len(all_tris), N, nv, n_caps)
    if n_caps:
        return _loops_from(nv, graph)[0]
    # Closed: the loops all pass through the root, so try a few roots spread over the chart
    # and keep the shortest system of loops.
    best = _loops_from(0, graph)
    if len(best[0]) == 0:
        return best[0]                     # a sphere: no loop to cut
    far = dijkstra(G, directed=False, indices=0)
    for _ in range(ROOT_TRIES):
        # The first of the farthest vertices, up to TIE (not a rounding-level winner) ...
        r = int((far >= far.max() * (1.0 - TIE)).ravel().nonzero()[0][0])
        trial = _loops_from(r, graph)
        if trial[1] < best[1] * (1.0 - TIE):     # ... and only a clearly shorter system wins
            best = trial
        far = np.minimum(far, dijkstra(G, directed=False, indices=r))
    return best[0]


def cut_graphs(charts, weight):
    """``cut_graph`` of each of several charts, the same cuts: a chart that is genus 0 with a
    boundary (an annulus, a disk with holes: nearly every chart a round's cut graphs open)
    takes the tree paths from its caps, and those of small charts are found together (one edge
    graph, one multi-root shortest-path tree: the fixed cost of ~1 ms a cut graph paid once a
    batch); the others go through ``cut_graph`` one by one.

    Parameters
    ----------
    charts : list of (tris (k,3) int64, nv int), as ``cut_graph`` takes them
    weight : callable((e,2) int64 vertex pairs numbered across the charts: chart i's vertex v
        is ``sum(nv of charts before i) + v``) -> (e,) float64 > 0

    Returns
    -------
    list of (c,2) int64 chart vertex pairs, ``cut_graph``'s for each chart
    """
    off = np.concatenate([[0], np.cumsum([nv for _, nv in charts], dtype=np.int64)])
    out = [None] * len(charts)
    small = [i for i, (tris, _) in enumerate(charts) if len(tris) <= SMALL_TRIS]
    runs, size = [], BATCH_TRIS
    for i in small:                          # runs of at most BATCH_TRIS triangles
        if size + len(charts[i][0]) > BATCH_TRIS:
            runs.append([])
            size = 0
        runs[-1].append(i)
        size += len(charts[i][0])
    for run in runs:
        for j, c in zip(run, _genus0_cuts([charts[j] for j in run], weight, off[run])):
            out[j] = c
    for i, (tris, nv) in enumerate(charts):
        if out[i] is None:
            out[i] = cut_graph(tris, nv, lambda pairs, _o=off[i]: weight(pairs + _o))
    return out


def _genus0_cuts(charts, weight, base):
    """``cut_graph``'s genus-0 branch for every chart of ``charts`` that is genus 0 with a
    boundary, all at once; None for the others. ``base``: each chart's first vertex in
    ``weight``'s numbering.

    Each chart's vertices and caps form a block of one vertex range (chart i's vertex v at
    ``O_i + v``, its caps after them), so every step chart by chart sees its own graph in the
    same order: the boundary (reverse half-edges within the block), the loops (components
    numbered by least vertex), the edges (sorted pair keys, each chart's a run), the weights
    (quantised over each chart's own), the exact distances from each chart's first cap (one
    multi-source ``dijkstra``; the charts are not joined) and ``canonical_predecessors``."""
    k = len(charts)
    nvs = np.array([nv for _, nv in charts], dtype=np.int64)
    nfs = np.array([len(t) for t, _ in charts], dtype=np.int64)
    voff = np.concatenate([[0], nvs.cumsum()])
    NV = int(voff[-1])
    T = np.concatenate([t for t, _ in charts]).astype(np.int64)
    T += np.repeat(voff[:-1], nfs)[:, None]
    a = T.ravel()
    b = T.take([1, 2, 0], axis=1).ravel()
    del T
    fwd = a * NV + b
    rev = np.sort(b * NV + a)
    boundary = (rev[np.minimum(rev.searchsorted(fwd), len(rev) - 1)] != fwd if len(rev)
                else np.zeros(0, dtype=bool))
    del rev, fwd
    ba, bb = a[boundary], b[boundary]
    vchart = np.repeat(np.arange(k), nvs)
    _, comp = components(NV, ba, bb)
    labels, loop_of = np.unique(comp[ba], return_inverse=True)
    loop_of = loop_of.ravel()
    lchart = vchart[ba[np.unique(loop_of, return_index=True)[1]]] if len(labels) else \
        np.zeros(0, np.int64)
    ncaps = np.bincount(lchart, minlength=k)
    coff = np.concatenate([[0], ncaps.cumsum()])
    # The blocks: chart i's vertex v at O_i + v, its cap j at O_i + nv_i + j.
    O = voff[:-1] + coff[:-1]
    N = NV + int(coff[-1])
    gid = np.arange(NV) + np.repeat(coff[:-1], nvs)
    caps = O[lchart[loop_of]] + nvs[lchart[loop_of]] + (loop_of - coff[lchart[loop_of]])
    ea = np.concatenate([gid[a], gid[bb], gid[ba], caps])
    eb = np.concatenate([gid[b], gid[ba], caps, gid[bb]])
    del a, b, comp
    key = np.minimum(ea, eb) * N + np.maximum(ea, eb)
    del ea, eb
    uniq, _, _ = radix.unique(key, N * N)
    del key
    ends = np.stack([uniq // N, uniq % N], axis=1)
    block = np.repeat(np.arange(k), nvs + ncaps)
    echart = block[ends[:, 0]]
    ne = np.bincount(echart, minlength=k)
    nf = nfs + np.bincount(vchart[ba], minlength=k)
    ok = (ncaps > 0) & (nvs + ncaps - ne + nf == 2)         # ``_genus0`` of each chart
    res = [None] * k
    if not ok.any():
        return res
    isreal = np.ones(N, dtype=bool)
    isreal[O[lchart] + nvs[lchart] + (np.arange(len(lchart)) - coff[lchart])] = False
    real = isreal[ends[:, 1]]
    w = np.zeros(len(uniq))
    # The weights in ``weight``'s numbering: the block's vertex v -> base_i + v.
    shift = (base - O)[block]
    er = ends[real]
    w[real] = weight(er + shift[er[:, 0]][:, None])
    del er
    eoff = np.concatenate([[0], ne.cumsum()])
    for i in ok.ravel().nonzero()[0]:
        s, e = eoff[i], eoff[i + 1]
        w[s:e] = quantised_weights(w[s:e], real[s:e])
    sel = ok[echart]
    G = _csr(w[sel], ends[sel, 0], ends[sel, 1], N)
    roots = O[ok] + nvs[ok]                                  # each chart's first cap
    dist = dijkstra(G, directed=False, indices=roots, min_only=True)
    del G
    pred = canonical_predecessors(dist, ends[sel], w[sel], roots)
    capv = ~isreal & ok[block]
    v = _tree_walk(capv.ravel().nonzero()[0], pred, N)
    cut = np.stack([v, pred[v]], axis=1)
    cut = cut[np.all(isreal[cut], axis=1)].astype(np.int64)
    cc = block[cut[:, 0]]
    bounds = cc.searchsorted(np.arange(k + 1))
    for i in ok.ravel().nonzero()[0]:
        res[i] = cut[bounds[i]:bounds[i + 1]] - O[i]
    return res


def _genus0(nv, ne, nf):
    """Whether a closed connected surface of ``nv`` vertices, ``ne`` edges and ``nf`` faces is
    a sphere (Euler characteristic 2)."""
    return nv - ne + nf == 2


def quantised_weights(w, real):
    """Weights as whole numbers of quanta (float64 integers, so sums are exact), at least 1.

    Parameters
    ----------
    w : (e,) float64 >= 0, edge weights (the caps' edges 0), possibly inf (never cut)
    real : (e,) bool, the mesh's edges (the scale is taken from these)

    Returns
    -------
    (e,) float64, ``max(1, round(w / q))`` with ``q`` a power of two near ``QUANTUM`` times the
    10th percentile of the finite weights; inf stays inf. A weight too large to count in quanta
    exactly (above 2^40 quanta) is capped there: never cut unless nothing else will do.
    """
    fin = real & np.isfinite(w)
    low = _percentile10(w[fin]) if fin.any() else 1.0
    q = 2.0 ** np.floor(np.log2(max(low, 1e-300) * QUANTUM))
    with quiet("over", "invalid"):
        k = np.round(np.where(np.isfinite(w), w, np.inf) / q)
    return np.clip(k, 1.0, 2.0 ** 40)


def _loops_from(root, graph):
    """Tree-cotree cut from ``root``: (cut (c,2) chart vertex pairs, its total weight).

    ``graph``: (G the weighted edge graph (csr), uniq the edges' keys, ends (e,2), w (e,)
    weights, f0, f1 (e,) each edge's two faces, nf faces, N vertices with the caps, nv chart
    vertices, n_caps), the same for every root."""
    G, uniq, ends, w, f0, f1, nf, N, nv, n_caps = graph
    dist, pred = _shortest_tree(G, root, ends, w)
    in_tree = np.zeros(len(uniq), dtype=bool)
    child = (pred >= 0).ravel().nonzero()[0]
    tk = np.minimum(child, pred[child]) * N + np.maximum(child, pred[child])
    in_tree[uniq.searchsorted(tk)] = True
    # Dual spanning tree over edges not in T, keeping the longest loops (so the leftover edges
    # close the shortest ones).
    loop_len = dist[ends[:, 0]] + dist[ends[:, 1]] + w
    dual = ~in_tree
    big = loop_len[dual].max(initial=0.0) + 1.0
    fd0, fd1 = f0[dual], f1[dual]
    # Equal loop lengths are common (whole quanta): the tree is taken over distinct ranks
    # (equal ones the later in the dual graph's row-major order first), unique, so no sort's
    # tie order decides it.
    dg = _csr(big - loop_len[dual] + 1e-12, fd0, fd1, nf)
    dg.data = distinct_ranks(dg.data)
    mst = minimum_spanning_tree(dg).tocoo()
    del dg
    cot = np.zeros(len(uniq), dtype=bool)
    r, c = mst.row.astype(np.int64), mst.col.astype(np.int64)  # int32: pair keys overflow
    del mst
    tree_keys = np.minimum(r, c) * nf + np.maximum(r, c)
    del r, c
    # The dual edges' keys formed once, without (e,2) stacks: a 500k-face chart's cut graph
    # was a memory peak of the seam search.
    dk = np.minimum(fd0, fd1) * nf + np.maximum(fd0, fd1)
    del fd0, fd1
    dorder = dk.argsort(kind="stable")     # two edges on one face pair: the first, always
    hit = dorder[dk[dorder].searchsorted(tree_keys)]
    del dk, dorder, tree_keys
    cot[dual.ravel().nonzero()[0][hit]] = True
    left = (~in_tree & ~cot).ravel().nonzero()[0]
    return _tree_paths(left, pred, uniq, ends, w, N, nv, n_caps)


def _shortest_tree(G, root, ends, w):
    """(dist, pred) from ``root``: scipy's exact distances (whole quanta) and the canonical
    predecessors of ``tree_ties`` (scipy's own broke ties differently before and after 1.16)."""
    dist = dijkstra(G, directed=False, indices=root)
    return dist, canonical_predecessors(dist, ends, w, root)


def _tree_walk(front, pred, N):
    """The vertices (of N) on the paths of the predecessor tree ``pred`` (-1 at a root) from
    the vertices ``front`` back to their roots, each walked once, that have a predecessor: the
    edge (v, pred[v]) of each is on the cut."""
    marked = np.zeros(N, dtype=bool)
    while len(front):
        front = front[~marked[front]]
        marked[front] = True
        front = pred[front]
        front = front[front >= 0]
    return (marked & (pred >= 0)).ravel().nonzero()[0]


def _tree_paths(left, pred, uniq, ends, w, N, nv, n_caps):
    """The cut of ``_loops_from``: the leftover edges ``left`` and the tree paths (``pred``)
    from their ends and from every cap back to the root; (cut, its total weight)."""
    # The tree paths from the leftover edges' ends and from every cap back to the root.
    v = _tree_walk(np.unique(np.concatenate([ends[left].ravel(), nv + np.arange(n_caps)])),
                   pred, N)
    cut = np.concatenate([np.stack([v, pred[v]], axis=1), ends[left]])
    cut = cut[np.all(cut < nv, axis=1)].astype(np.int64)
    return cut, float(np.sum(w[uniq.searchsorted(np.minimum(cut[:, 0], cut[:, 1]) * N
                                                + np.maximum(cut[:, 0], cut[:, 1]))]))


def _percentile10(x):
    """``float(np.percentile(x, 10))`` to the bit (numpy's linear method: the same order
    statistics and interpolation), from a partition of the two it needs; numpy's own costs
    ~0.2 ms of set-up, paid at every cut graph."""
    n = len(x)
    v = (n - 1) * 0.1
    lo = int(np.floor(v))
    hi = min(lo + 1, n - 1)
    g = v - lo
    p = np.partition(x, (lo, hi))
    a, b = p[lo], p[hi]
    d = b - a
    return float(b - d * (1 - g)) if g >= 0.5 else float(a + d * g)


def _csr(vals, rows, cols, n):
    """``sp.csr_matrix(sp.coo_array((vals, (rows, cols)), shape=(n, n)))`` (duplicates summed,
    indices sorted), built directly (``compressed``): the cut graph of a chart of a few dozen
    faces is mostly scipy's fixed costs otherwise."""
    return sp.csr_matrix(compressed(rows, cols, vals, n), shape=(n, n))
