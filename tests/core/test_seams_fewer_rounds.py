"""Work the seam search saves without changing its seams (issue 21 item 3, seams8).

- ``cut_graph`` of a chart of genus 0 with boundary loops (an annulus, a disk with holes) forms
  only the shortest-path tree: on the capped sphere every edge outside the tree is in the
  cotree, so the tree-cotree cut is the tree paths from the caps. The same cut as the full
  construction, and it opens the chart into one disk (checked by cutting the triangles apart
  here and counting).
- ``rounds.refine`` maps a chart its cut graph opened in the same round, not in the next: the
  same seams, fewer rounds.
"""
import importlib

import numpy as np
import pytest

from bd_uv.seams import auto as auto_mod
from bd_uv.seams import rounds as rounds_mod
from bd_uv.seams.cut_graph import cut_graph
from seams_helpers import chart_topology, torus

cg_mod = importlib.import_module("bd_uv.seams.cut_graph")


def holed_grid(n=12, holes=((3, 3),), seed=0, jitter=0.3):
    """An n x n grid of unit cells (two triangles each, diagonals of both directions) with the
    2x2-cell squares at ``holes`` removed: a disk with len(holes) holes. Vertices jittered so
    the edge lengths differ; with ``jitter`` 0 many shortest paths tie."""
    rng = np.random.default_rng(seed)
    g = np.arange(n + 1)
    x, y = np.meshgrid(g, g, indexing="ij")
    V = np.c_[x.ravel(), y.ravel(), np.zeros(x.size)].astype(np.float64)
    V[:, :2] += jitter * rng.uniform(-0.5, 0.5, (len(V), 2))
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    gone = np.zeros((n, n), dtype=bool)
    for i, j in holes:
        gone[i:i + 2, j:j + 2] = True
    F = []
    for i in range(n):
        for j in range(n):
            if gone[i, j]:
                continue
            a, b, c, d = idx[i, j], idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]
            F += [[a, b, c], [a, c, d]] if (i + j) % 2 else [[a, b, d], [b, c, d]]
    F = np.array(F, dtype=np.int64)
    used = np.unique(F)
    remap = np.full(len(V), -1)
    remap[used] = np.arange(len(used))
    return V[used], remap[F]


def length_weight(V):
    return lambda pairs: np.linalg.norm(V[pairs[:, 0]] - V[pairs[:, 1]], axis=1)


def cut_apart(F, cut):
    """The triangles with the vertices split along the cut edges (union-find of the corners
    around each vertex across uncut shared edges), renumbered 0..k-1."""
    parent = list(range(3 * len(F)))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i
    cuts = {tuple(sorted(e)) for e in np.asarray(cut).tolist()}
    corner = {}                             # (face, vertex) -> corner id
    for f, t in enumerate(F.tolist()):
        for j, v in enumerate(t):
            corner[f, v] = 3 * f + j
    owners = {}
    for f, t in enumerate(F.tolist()):
        for j in range(3):
            owners.setdefault(tuple(sorted((t[j], t[(j + 1) % 3]))), []).append(f)
    for e, fs in owners.items():
        if len(fs) == 2 and e not in cuts:
            for v in e:
                a, b = find(corner[fs[0], v]), find(corner[fs[1], v])
                parent[a] = b
    roots = np.array([find(i) for i in range(3 * len(F))])
    _, tri = np.unique(roots, return_inverse=True)
    return tri.reshape(-1, 3)


@pytest.mark.parametrize("holes,jitter", [(((3, 3),), 0.3), (((3, 3),), 0.0),
                                          (((2, 2), (2, 7), (7, 4)), 0.3),
                                          (((2, 2), (2, 7), (7, 4)), 0.0)],
                         ids=["annulus", "annulus-ties", "three-holes", "three-holes-ties"])
def test_a_genus0_cut_graph_is_the_full_tree_cotree_cut_and_opens_one_disk(monkeypatch, holes,
                                                                            jitter):
    V, F = holed_grid(holes=holes, jitter=jitter)
    chi, loops = chart_topology(F)
    assert (chi, loops) == (1 - len(holes), 1 + len(holes))        # genus 0, holes + 1 loops
    fast = cut_graph(F, len(V), length_weight(V))
    spans = []
    real = cg_mod.minimum_spanning_tree

    def spy(*a, **k):
        spans.append(1)
        return real(*a, **k)
    monkeypatch.setattr(cg_mod, "minimum_spanning_tree", spy)
    assert spans == [] and cut_graph(F, len(V), length_weight(V)).tolist() == fast.tolist()
    monkeypatch.setattr(cg_mod, "_genus0", lambda *a: False)      # the full construction
    full = cut_graph(F, len(V), length_weight(V))
    assert spans == [1]
    assert np.array_equal(fast, full)
    assert chart_topology(cut_apart(F, fast)) == (1, 1)            # one disk
    # the tree paths join the holes' loops to the outer one: one path per hole, no more edges
    # than a tree on the loops needs
    assert len(fast) >= len(holes)


def test_cut_graph_of_a_handle_still_takes_the_full_construction(monkeypatch):
    V, F, _, _ = torus(nu=24, nv=8)
    keep = np.ones(len(F), dtype=bool)
    keep[:4] = False                        # a torus with a hole: genus 1, one loop
    Fh = F[keep]
    used = np.unique(Fh)
    remap = np.full(len(V), -1)
    remap[used] = np.arange(len(used))
    Fh, Vh = remap[Fh], V[used]
    spans = []
    real = cg_mod.minimum_spanning_tree
    monkeypatch.setattr(cg_mod, "minimum_spanning_tree",
                        lambda *a, **k: spans.append(1) or real(*a, **k))
    c = cut_graph(Fh, len(Vh), length_weight(Vh))
    assert spans == [1]
    assert chart_topology(cut_apart(Fh, c)) == (1, 1)


def test_a_chart_its_cut_graph_opens_is_mapped_in_the_same_round(monkeypatch):
    # A closed torus: the first round cuts its handles; the opened chart is a disk, mapped in
    # that round (before: in the next). The same seams either way, one round fewer.
    V, F, _, _ = torus(R=4.0, r=1.0, nu=32, nv=12)
    real_charts, real_maps, real_refine = rounds_mod.charts, rounds_mod.chart_maps, auto_mod.refine
    runs = {}
    for same_round in (True, False):
        calls, maps = [0], []

        def refine(*a, **k):
            calls[0] = 0
            return real_refine(*a, **k)

        def charts(*a, **k):
            # The former rounds: a round's second ``charts`` (the charts its cut graphs opened)
            # finds nothing, so they wait for the next round, as they did.
            calls[0] += 1
            return [] if calls[0] == 2 and not same_round else real_charts(*a, **k)

        def chart_maps(V_, disks, *a, **k):
            maps.append(sorted(len(c.faces) for c in disks))
            return real_maps(V_, disks, *a, **k)
        monkeypatch.setattr(auto_mod, "refine", refine)
        monkeypatch.setattr(rounds_mod, "charts", charts)
        monkeypatch.setattr(rounds_mod, "chart_maps", chart_maps)
        res, added, info = auto_mod.unwrap_auto(V, F, bound=2.0, stretch=2.0, merge=False,
                                                atlas_cuts=False)
        assert res.certified
        runs[same_round] = (sorted(map(tuple, np.sort(added, axis=1).tolist())), info["rounds"],
                            maps)
    seams, rounds, maps = runs[True]
    assert maps[0] == [len(F)]              # round 1 maps the opened torus, all its faces
    assert runs[False][2][0] == [len(F)] and len(runs[False][2]) == len(maps)
    assert runs[False][0] == seams
    assert rounds == runs[False][1] - 1


def _holed_torus():
    V, F, _, _ = torus(nu=24, nv=8)
    keep = np.ones(len(F), dtype=bool)
    keep[:4] = False                        # genus 1, one loop: cut_graph alone
    Fh = F[keep]
    used = np.unique(Fh)
    remap = np.full(len(V), -1)
    remap[used] = np.arange(len(used))
    return V[used], remap[Fh]


@pytest.mark.parametrize("small,batch", [(5_000, 20_000), (5_000, 300), (150, 20_000)],
                         ids=["one-run", "short-runs", "large-ones-alone"])
def test_cut_graphs_of_a_round_are_cut_graph_chart_by_chart(monkeypatch, small, batch):
    """``cut_graphs`` (a round's open charts at once: the genus-0 ones share one shortest-path
    tree) gives each chart ``cut_graph``'s own cut, array for array, whatever the charts around
    it: annuli and disks with holes (jittered and with tied lengths), a holed torus and a
    closed torus (which go alone), vertices shuffled, in runs of any length."""
    monkeypatch.setattr(cg_mod, "SMALL_TRIS", small)
    monkeypatch.setattr(cg_mod, "BATCH_TRIS", batch)
    rng = np.random.default_rng(3)
    meshes = [holed_grid(holes=h, jitter=j, seed=s, n=n)
              for h, j, s, n in [(((3, 3),), 0.3, 0, 12), (((3, 3),), 0.0, 1, 12),
                                 (((2, 2), (2, 7), (7, 4)), 0.3, 2, 12),
                                 (((2, 2), (2, 7), (7, 4)), 0.0, 3, 12),
                                 (((1, 1),), 0.2, 4, 5), (((4, 9), (9, 2)), 0.1, 5, 14)]]
    meshes.insert(2, _holed_torus())
    V, F, _, _ = torus(nu=12, nv=6)
    meshes.insert(5, (V, F))
    charts, verts = [], []
    for V, F in meshes:
        perm = rng.permutation(len(V))      # shuffled vertex ids
        inv = np.argsort(perm)
        charts.append((inv[F], len(V)))
        verts.append(V[perm])
    allV = np.concatenate(verts)
    calls = []
    real = cg_mod._genus0_cuts
    monkeypatch.setattr(cg_mod, "_genus0_cuts",
                        lambda ch, *a: calls.append(len(ch)) or real(ch, *a))
    got = cg_mod.cut_graphs(charts, length_weight(allV))
    want = [cut_graph(t, nv, length_weight(Vc)) for (t, nv), Vc in zip(charts, verts)]
    assert len(got) == len(want) == 8
    for g, w in zip(got, want):
        assert g.dtype == w.dtype == np.int64 and g.shape == w.shape and np.array_equal(g, w)
    assert all(len(w) for w in want)        # every chart here needs a cut (the tori too)
    sizes = [len(t) for t, _ in charts]
    assert sum(calls) == sum(s <= small for s in sizes)     # each small chart in one run
    assert len(calls) == (1 if batch == 20_000 else len(calls)) and (batch > 300 or
                                                                      len(calls) > 2)
