"""Shortest-path and spanning trees that do not depend on how a library breaks ties.

The cut graph's weights are whole quanta (``cut_graph.quantised_weights``), so equally short
paths and equally heavy spanning trees are common; scipy's ``dijkstra`` broke the ties of its
predecessors one way up to 1.15 (a Fibonacci heap) and another from 1.16 (``std::priority_queue``),
and ``minimum_spanning_tree`` orders equal weights by an unstable sort. The same mesh must give
the same seams on every stack, so the trees are chosen here by fixed rules from exact numbers:
among equals, the highest index wins (scipy 1.16+'s own choice for the predecessors).

Measured (benchmarks/results/issue21-ties17): of 12 rules tried (predecessor of least or highest
index, after least distance or not; equal dual weights the first, the last, or scipy's order),
only the highest index in both trees passes both ``test_no_chart_is_cut_that_could_stay_whole``
and ``test_a_merged_long_band_is_bisected_and_packs_better``; against scipy 1.15's seams it
gives fewer or equal charts and shorter or equal seams on 10 meshes.
"""
import numpy as np


def canonical_predecessors(dist, ends, w, root):
    """The shortest-path tree of ``dist`` by a fixed rule: each vertex's predecessor is, among
    its tight neighbours u (``dist[u] + w(u, v) == dist[v]``, exact in whole quanta), the one
    of least ``dist[u]``, then of highest index (scipy 1.16+'s own rule, measured by np2-16).

    Parameters
    ----------
    dist : (N,) float64, exact distances from ``root`` (inf where unreached)
    ends : (e,2) int, the undirected edges; w : (e,) float64 > 0, their weights
    root : int, or (r,) int: the roots of a forest (``dist`` from the nearest, each tree
        apart from the others)

    Returns
    -------
    (N,) int32, the predecessors, -9999 at the root and unreached vertices (as scipy's).
    """
    a = np.concatenate([ends[:, 0], ends[:, 1]])
    b = np.concatenate([ends[:, 1], ends[:, 0]])
    da = dist[a]
    isroot = np.zeros(len(dist), dtype=bool)
    isroot[root] = True                         # one root or a forest's
    tight = (da + np.concatenate([w, w]) == dist[b]) & np.isfinite(da) & ~isroot[b]
    a, b, da = a[tight], b[tight], da[tight]
    # Per child b: least dist[a], then highest a (two scatter-reductions: 2.5x faster than a
    # lexsort).
    low = np.full(len(dist), np.inf)
    np.minimum.at(low, b, da)
    keep = da == low[b]
    best = np.full(len(dist), -1, dtype=np.int64)
    np.maximum.at(best, b[keep], a[keep])
    pred = np.where(best < 0, -9999, best).astype(np.int32)
    return pred


def distinct_ranks(data):
    """Weights 1..n in the order of ``data``, equal values the later first (the highest index
    wins, as for the predecessors): all distinct, so the minimum spanning tree over them is
    unique (whatever the algorithm or its sort), and it is one of the minimum spanning trees of
    ``data``."""
    n = len(data)
    order = n - 1 - np.argsort(data[::-1], kind="stable")      # stable on the reversed
    ranks = np.empty(n, dtype=np.float64)
    ranks[order] = np.arange(1, n + 1, dtype=np.float64)
    return ranks
