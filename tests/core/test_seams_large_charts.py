"""The seam search's paths for large charts (100k+ face meshes) keep what it decides.

- ``cluster_fiedler.clusters``: connected clusters of one chart each, small charts untouched;
  the nodes of one grid cell of one chart connected by their pairs, whichever way the cells'
  keys are formed;
- a chart split through its cluster graph is cut where the node graph cuts it (a long tube:
  across its middle, one circumference of seam);
- a chart above ``rounds.MAP_VERTICES`` is split unmapped, and a region that passes whole is merged
  back into one certified chart;
- ``charts.chart_maps`` in bounded runs solves each chart as it would alone.
"""
import numpy as np
import pytest
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


@pytest.mark.parametrize("limit", [None, 1])
def test_clusters_are_the_connected_nodes_of_one_cell_of_one_chart(monkeypatch, limit):
    """Recomputed here node by node: each coarsened chart's grid (side sqrt(CLUSTER * mean node
    area), counted from its lowest cell), a dictionary of (chart, cell) tuples, the components
    of the pairs inside one tuple, numbered by their smallest node. Two tubes far apart on
    negative coordinates (cells below zero), a small chart between them; with ``limit`` 1 the
    cells are keyed by dense ranks (``np.unique``) instead of mixed-radix integers."""
    V, F = _tube(nu=20, nv=60)
    area, cen, pairs, _ = _dual(V, F)
    k, small = len(F), 40
    sub = pairs[(pairs < small).all(axis=1)]
    shift = np.array([-37.3, -5.1, -81.7])
    mass = np.concatenate([area, area[:small], 2.0 * area])
    centroid = np.concatenate([cen + shift, cen[:small], 1.5 * cen - shift])
    allp = np.concatenate([pairs, sub + k, pairs + k + small])
    group = np.repeat([0, 1, 2], [k, small, k])
    monkeypatch.setattr(cluster_fiedler, "COARSE_NODES", 1000)
    if limit is not None:
        monkeypatch.setattr(cluster_fiedler, "KEY_LIMIT", limit)
    label, coarse = cluster_fiedler.clusters(mass, centroid, allp, group, 3)
    n = len(mass)
    cell = {}
    for j in range(3):
        nodes = np.flatnonzero(group == j)
        if len(nodes) <= 1000:
            continue
        h = np.sqrt(cluster_fiedler.CLUSTER * mass[nodes].sum() / len(nodes))
        q = np.floor(centroid[nodes] / h).astype(np.int64)
        q -= q.min(axis=0)
        for i, c in zip(nodes.tolist(), map(tuple, q.tolist())):
            cell[i] = (j,) + c
    key = [cell.get(i, ("alone", i)) for i in range(n)]
    inside = np.array([key[a] == key[b] for a, b in allp.tolist()])
    g = coo_array((np.ones(int(inside.sum())), (allp[inside, 0], allp[inside, 1])), shape=(n, n))
    _, comp = connected_components(g, directed=False)
    assert np.array_equal(coarse, group != 1)
    assert np.array_equal(label, comp)
    assert label.dtype == np.int32


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


def _wavy_sheet(n=40):
    """A gently waved square sheet, ``n`` x ``n`` vertices: one chart passes C = 2, S = 2."""
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    V = np.stack([x.ravel(), y.ravel(), 0.05 * np.sin(3 * x.ravel())], 1)
    i = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)[None, :]).ravel()
    F = np.concatenate([np.stack([i, i + 1, i + n + 1], 1), np.stack([i, i + n + 1, i + n], 1)])
    return V, F.astype(np.int64)


def test_a_chart_above_map_vertices_is_split_unmapped_and_merged_back(monkeypatch):
    """The search maps no chart above ``MAP_VERTICES`` vertices top-down (its factor was the
    memory peak); a sheet that passes whole is still one chart, its pieces merged again."""
    from bd_uv.seams import auto, rounds
    from tests.core.seams_helpers import face_singular_values, record_mapped
    V, F = _wavy_sheet()
    monkeypatch.setattr(rounds, "MAP_VERTICES", 200)
    mapped = record_mapped(monkeypatch, rounds)
    result, added, info = auto.unwrap_auto(V, F, bound=2, stretch=2)
    assert mapped and max(mapped) <= 200           # the top-down rounds mapped pieces only
    assert info["charts"] == 1 and len(added) == 0
    (isl,) = result.islands
    assert isl.status == "certified" and len(isl.faces) == len(F)
    s1, s2, det = face_singular_values(V, F, result.corner_uv)
    assert (det > 0).all()
    P = V[F]
    area3 = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    scale = np.sqrt(area3.sum() / np.sum(s1 * s2 * area3))   # to 3D area
    assert max((scale * s1).max(), 1.0 / (scale * s2).min()) <= 2.0
    assert (s1 / s2).max() <= 2.0 * (1 + 1e-6)


def test_chart_maps_in_bounded_runs_solve_each_chart_as_alone(monkeypatch):
    """A batch above ``SEQUENTIAL_VERTICES`` is solved in runs of at most ``RUN_VERTICES``
    vertices (a larger chart alone), two factors at a time (in either order: two threads);
    each chart's map is its own solve."""
    from bd_uv.mesh import islands
    from bd_uv.seams import charts as charts_mod
    # Four separate tubes of rising lengths, each cut open along a line (a disk).
    Vs, Fs, seams, off = [], [], [], 0
    for j, nv in enumerate((6, 10, 14, 30)):
        v, f = _tube(nu=12, nv=nv)
        Vs.append(v + [0.0, 0.0, 40.0 * j])
        Fs.append(f + off)
        seams.append(np.stack([np.arange(nv) * 12, np.arange(1, nv + 1) * 12], 1) + off)
        off += len(v)
    V, F, seams = np.concatenate(Vs), np.concatenate(Fs), np.concatenate(seams)
    isl = [i for i in islands(V, F, seams) if i.error is None]
    assert len(isl) == 4 and all(len(i.loops) == 1 for i in isl)
    sizes = [len(i.vertices) for i in isl]
    solved = []
    real = charts_mod._lscm_pinned

    def spy(geom, faces, tris, n, idx, val):
        solved.append(n)
        return real(geom, faces, tris, n, idx, val)
    monkeypatch.setattr(charts_mod, "_lscm_pinned", spy)
    monkeypatch.setattr(charts_mod, "SEQUENTIAL_VERTICES", 10)
    monkeypatch.setattr(charts_mod, "RUN_VERTICES", sizes[0] + sizes[1])
    runs = charts_mod.chart_maps(V, isl)
    assert sorted(solved) == sorted([sizes[0] + sizes[1], sizes[2], sizes[3]])
    for i, one in enumerate(isl):
        alone = charts_mod.chart_maps(V, [one])
        np.testing.assert_allclose(runs.uv[runs.voff[i]:runs.voff[i + 1]], alone.uv,
                                   rtol=0, atol=1e-9 * np.abs(alone.uv).max())
