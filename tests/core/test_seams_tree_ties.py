"""The cut graph's trees do not depend on how scipy breaks ties (issue 21, ties17).

Its weights are whole quanta, so equally short paths and equally heavy spanning trees are
common; scipy 1.16 changed which of equally short predecessors ``dijkstra`` returns, and the
seams of the same mesh differed between Blender 4.2-5.0's stack and 5.1+'s. Checked here against
brute force written out in plain Python: the shortest-path tree is the canonical one (each
vertex's predecessor the tight neighbour of least distance, then highest index) and the dual
spanning tree the unique one over distinct ranks, equal weights the later first (whatever
algorithm or sort finds it).
"""
import importlib

import numpy as np

from bd_uv.seams.cut_graph import cut_graph
from bd_uv.seams.tree_ties import canonical_predecessors
from seams_helpers import chart_topology, holed_block, torus

cg_mod = importlib.import_module("bd_uv.seams.cut_graph")


def _tie_graph(n, seed):
    """A grid graph of n x n vertices, shuffled ids, weights 1-3 whole units plus diagonals of
    weight 2: many equally short paths."""
    rng = np.random.default_rng(seed)
    perm = rng.permutation(n * n)
    ends, w = [], []
    for i in range(n):
        for j in range(n):
            for di, dj, base in ((1, 0, 1), (0, 1, 1), (1, 1, 2)):
                if i + di < n and j + dj < n:
                    a, b = perm[i * n + j], perm[(i + di) * n + j + dj]
                    ends.append((min(a, b), max(a, b)))
                    w.append(float(base if rng.random() < 0.7 else base + 1))
    return np.array(ends, dtype=np.int64), np.array(w)


def _brute_tree(N, ends, w, root):
    """Bellman-Ford distances, then each vertex's predecessor by the rule, one by one."""
    dist = [float("inf")] * N
    dist[root] = 0.0
    for _ in range(N):
        for (a, b), x in zip(ends.tolist(), w.tolist()):
            dist[b] = min(dist[b], dist[a] + x)
            dist[a] = min(dist[a], dist[b] + x)
    pred = [-9999] * N
    for v in range(N):
        if v == root or dist[v] == float("inf"):
            continue
        tight = [u for (a, b), x in zip(ends.tolist(), w.tolist()) for u, t in ((a, b), (b, a))
                 if t == v and dist[u] + x == dist[v]]
        pred[v] = min(tight, key=lambda u: (dist[u], -u))
    return dist, pred


def test_shortest_path_tree_is_the_canonical_one_by_brute_force():
    ties = 0
    for seed in range(4):
        ends, w = _tie_graph(7, seed)
        N = 7 * 7 + 2                        # two isolated vertices: unreached
        G = cg_mod._csr(w, ends[:, 0], ends[:, 1], N)
        for root in (0, 5, 48):
            dist, pred = cg_mod._shortest_tree(G, root, ends, w)
            want_d, want_p = _brute_tree(N, ends, w, root)
            assert dist.tolist() == want_d
            assert pred.tolist() == want_p
            d = np.asarray(want_d)
            for v in range(N):
                tight = [(a, b) for a, b in ends.tolist() if v in (a, b) and
                         d[a + b - v] + w[ends.tolist().index([a, b])] == d[v]]
                ties += len(tight) > 1
            assert canonical_predecessors(dist, ends, w, root).tolist() == want_p
    assert ties > 50                         # the graphs do have ties to break


def test_distinct_ranks_order_equal_weights_the_later_first():
    from bd_uv.seams.tree_ties import distinct_ranks
    rng = np.random.default_rng(5)
    for n in (0, 1, 2, 7, 60):
        x = rng.integers(0, 4, n).astype(np.float64)
        want = [0.0] * n
        for r, i in enumerate(sorted(range(n), key=lambda i: (x[i], -i))):
            want[i] = float(r + 1)
        assert distinct_ranks(x).tolist() == want


def _kruskal(n, rows, cols, data, reverse_ties):
    """A minimum spanning forest by Kruskal in plain Python, equal weights taken in the given
    order or reversed: with distinct weights both give the one tree."""
    idx = sorted(range(len(data)), key=lambda i: (data[i], -i if reverse_ties else i))
    parent = list(range(n))

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x
    keep = []
    for i in idx:
        ra, rb = find(rows[i]), find(cols[i])
        if ra != rb:
            parent[ra] = rb
            keep.append(i)
    return keep


def test_cut_graph_takes_the_same_dual_tree_whatever_orders_equal_weights(monkeypatch):
    """scipy's minimum_spanning_tree replaced by Kruskal with equal weights in either order:
    the cut is the same, since the dual tree is taken over distinct ranks."""
    import scipy.sparse as sp
    V, F = holed_block(holes=2, s=2)          # voxels: every edge the same length, genus 2
    Vt, Ft = torus(nu=16, nv=8)[:2]

    def weight(V):
        return lambda e: np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1)
    real = cut_graph(F, len(V), weight(V)), cut_graph(Ft, len(Vt), weight(Vt))
    calls = []
    for reverse in (False, True):
        def mst(g, reverse=reverse):
            c = g.tocoo()
            r, k, x = c.row.tolist(), c.col.tolist(), c.data.tolist()
            assert len(set(x)) == len(x)      # distinct: one minimum tree
            keep = _kruskal(g.shape[0], r, k, x, reverse)
            calls.append(len(keep))
            return sp.csr_matrix((np.array(x)[keep], (np.array(r)[keep], np.array(k)[keep])),
                                 shape=g.shape)
        monkeypatch.setattr(cg_mod, "minimum_spanning_tree", mst)
        got = cut_graph(F, len(V), weight(V)), cut_graph(Ft, len(Vt), weight(Vt))
        assert all(np.array_equal(a, b) for a, b in zip(got, real))
    assert calls and min(calls) > 0
    assert chart_topology(np.asarray(F))[0] < 0       # the block has handles: the tree is used
