"""The seam search's paths for large charts (100k+ face meshes) keep what it decides.

- ``cluster_fiedler.clusters``: connected clusters of one chart each, small charts untouched;
- a chart split through its cluster graph is cut where the node graph cuts it (a long tube:
  across its middle, one circumference of seam);
"""
import numpy as np
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components

from bd_uv.seams import cluster_fiedler, split


def _tube(nu=24, nv=120, length=20.0):
    """An open tube of radius 1 along z, ``nu`` quads around, ``nv`` along (two triangles each)."""
    t = 2 * np.pi * np.arange(nu) / nu
    z = np.linspace(0.0, length, nv + 1)
    V = np.stack([np.tile(np.cos(t), nv + 1), np.tile(np.sin(t), nv + 1), np.repeat(z, nu)], 1)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    i, j = i.ravel(), j.ravel()
    a, b = j * nu + i, j * nu + (i + 1) % nu
    c, d = a + nu, b + nu
    F = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    return V, F.astype(np.int64)


def _dual(V, F):
    """Face areas, centroids, face pairs across interior edges and those edges' lengths."""
    P = V[F]
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    e = np.sort(F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    face = np.repeat(np.arange(len(F)), 3)
    key = e[:, 0] * len(V) + e[:, 1]
    order = np.argsort(key, kind="stable")
    same = key[order][1:] == key[order][:-1]
    pairs = np.stack([face[order][:-1][same], face[order][1:][same]], 1)
    ends = e[order][:-1][same]
    length = np.linalg.norm(V[ends[:, 0]] - V[ends[:, 1]], axis=1)
    return area, P.mean(axis=1), pairs, length


def test_clusters_are_connected_pieces_of_one_chart_and_small_charts_stay_whole(monkeypatch):
    V, F = _tube()
    area, cen, pairs, _ = _dual(V, F)
    k = len(F)
    # Two charts: the tube's faces (large), then a copy of its first 50 faces (small).
    small = 50
    sub = pairs[(pairs < small).all(axis=1)]
    mass = np.concatenate([area, area[:small]])
    centroid = np.concatenate([cen, cen[:small]])
    allp = np.concatenate([pairs, sub + k])
    group = np.repeat([0, 1], [k, small])
    monkeypatch.setattr(cluster_fiedler, "COARSE_NODES", 1000)
    label, coarse = cluster_fiedler.clusters(mass, centroid, allp, group, 2)
    assert coarse[:k].all() and not coarse[k:].any()
    # The small chart's nodes are clusters of one, the large chart's about CLUSTER nodes each.
    assert len(np.unique(label[k:])) == small
    n_big = len(np.unique(label[:k]))
    assert k / (4 * cluster_fiedler.CLUSTER) < n_big < k / 2
    # No cluster holds nodes of two charts; each is connected by its own pairs.
    assert not np.intersect1d(label[:k], label[k:]).size
    inside = label[allp[:, 0]] == label[allp[:, 1]]
    g = coo_array((np.ones(int(inside.sum())), (allp[inside, 0], allp[inside, 1])),
                  shape=(k + small, k + small))
    n_comp, comp = connected_components(g, directed=False)
    assert n_comp == label.max() + 1
    assert np.array_equal(np.unique(np.stack([label, comp], 1), axis=0)[:, 0],
                          np.arange(n_comp))
    # Numbered by their smallest node, so grouped chart by chart.
    assert np.all(np.diff(np.array([np.flatnonzero(label == c)[0] for c in range(n_comp)])) > 0)


def test_a_long_tube_is_cut_across_its_middle_through_its_cluster_graph(monkeypatch):
    V, F = _tube()
    area, cen, pairs, length = _dual(V, F)
    cost = np.ones(len(pairs))
    fine = split.fiedler_split(area, cen, pairs, length, cost)
    monkeypatch.setattr(cluster_fiedler, "COARSE_NODES", 1000)
    calls = []
    original = cluster_fiedler.clusters
    monkeypatch.setattr(cluster_fiedler, "clusters", lambda *a: calls.append(1) or original(*a))
    coarse = split.fiedler_split(area, cen, pairs, length, cost)
    assert calls, "the cluster graph was not used"
    circumference = 24 * 2 * np.sin(np.pi / 24)
    for side in (fine, coarse):
        assert side is not None
        across = side[pairs[:, 0]] != side[pairs[:, 1]]
        # One ring: the two sides are two z-ranges, the seam is one circumference.
        z = cen[:, 2]
        assert z[side].max() < z[~side].min() or z[~side].max() < z[side].min()
        assert length[across].sum() <= 1.01 * circumference
        share = area[side].sum() / area.sum()
        assert 0.4 <= share <= 0.6
    # Both cut at the same ring, up to a few rings of faces.
    ring = lambda s: min(cen[s, 2].max(), cen[~s, 2].max())
    assert abs(ring(fine) - ring(coarse)) <= 3 * 20.0 / 120
