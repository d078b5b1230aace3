"""The benchmark's own tools: generated assets, the isolated run and the done-when verdicts.

They are measuring instruments for issue 9's "done when", so their verdicts are checked here on
numbers built by hand; nothing asserts a time.
"""
import os
import sys

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "benchmarks"))

import assets  # noqa: E402
import bench_unwrap  # noqa: E402
from isolate import run_isolated  # noqa: E402
from measure import load_mesh_by_index, uv_stats  # noqa: E402

import bd_uv  # noqa: E402

DATA = os.path.join(ROOT, "tests", "data")


def test_many_islands_is_deterministic_and_has_n_disk_like_islands(tmp_path):
    a = assets.many_islands(40, seed=3, out_dir=str(tmp_path / "a"))
    b = assets.many_islands(40, seed=3, out_dir=str(tmp_path / "b"))
    with open(a, "rb") as fa, open(b, "rb") as fb:
        assert fa.read() == fb.read()
    V, F = load_mesh_by_index(a)
    isl = bd_uv.islands(V, F)
    assert len(isl) == 40
    assert all(i.error is None for i in isl)
    # no vertex is unreferenced, every patch keeps its orientation (a consistent disk or annulus)
    assert np.array_equal(np.unique(F), np.arange(len(V)))
    sizes = sorted(len(i.faces) for i in isl)
    assert sizes[0] == 8


def test_many_islands_holes_are_extra_boundary_loops(tmp_path):
    V, F = load_mesh_by_index(assets.many_islands(300, seed=0, out_dir=str(tmp_path)))
    isl = bd_uv.islands(V, F)
    holed = [i for i in isl if len(i.loops) > 1]
    assert holed and all(len(i.loops) == 2 for i in holed)
    # Euler characteristic of an annulus is 0, of a disk 1
    for i in isl:
        e = np.unique(np.sort(i.tris[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
        chi = len(i.vertices) - len(e) + len(i.tris)
        assert chi == 2 - len(i.loops)


def test_patch_and_subdivide_keep_a_disk(tmp_path):
    src = os.path.join(DATA, "three_peaks.off")
    p = assets.patch(src, 1000, out_dir=str(tmp_path))
    V, F = load_mesh_by_index(p)
    assert len(F) >= 1000
    isl = bd_uv.islands(V, F)
    assert len(isl) == 1 and len(isl[0].loops) == 1
    s = assets.subdivided(os.path.join(DATA, "nefertiti.off"), 1, out_dir=str(tmp_path))
    V2, F2 = assets.read_obj_fast(s)
    assert len(F2) == 4 * 562
    V3, F3 = load_mesh_by_index(s)
    assert np.array_equal(F2, F3) and np.allclose(V2, V3)


def _boundary_walk(F):
    """Boundary edges (used by one face) walked from one of them, each vertex's next boundary
    vertex: (edges walked before returning to the start, boundary edges, a vertex with other
    than one successor)."""
    e = np.sort(F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    edges, count = np.unique(e, axis=0, return_counts=True)
    directed = F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    b = {tuple(x) for x in edges[count == 1]}
    nxt = {}
    branching = False
    for a, c in directed:
        if (min(a, c), max(a, c)) in b:
            branching |= a in nxt
            nxt[a] = c
    start = next(iter(nxt))
    v, steps = nxt[start], 1
    while v != start and steps <= len(b):
        v, steps = nxt[v], steps + 1
    return steps, len(b), branching


def test_patch_grows_past_rings_that_meet_at_a_vertex(tmp_path):
    """cow.off's whole rings up to 616 faces meet at a vertex (a bowtie, which bd-uv rightly
    refuses as a disk); the patch grows to the first ring that closes into a disk."""
    src = os.path.join(DATA, "cow.off")
    V0, F0 = load_mesh_by_index(src)
    # the old patch (whole rings to >= 600 faces) is no disk: its boundary branches at a vertex
    bowtie = np.array([[0, 1, 2], [0, 3, 4]])
    assert not assets.is_disk(bowtie) and assets.is_disk(bowtie[:1])
    p = assets.patch(src, 600, out_dir=str(tmp_path))
    V, F = load_mesh_by_index(p)
    assert len(F) > 616 and assets.is_disk(F)
    steps, nb, branching = _boundary_walk(F)
    assert not branching and steps == nb            # one boundary loop through every edge
    e = np.unique(np.sort(F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
    assert len(np.unique(F)) - len(e) + len(F) == 1
    isl = bd_uv.islands(V, F)
    assert len(isl) == 1 and len(isl[0].loops) == 1
    r = bd_uv.unwrap(V, F, bound=5.0)
    assert r.certified


def test_isolated_run_reports_the_same_distortion_and_a_peak():
    path = os.path.join(DATA, "nefertiti.off")
    r = run_isolated(path, "bd-init-lscm", 60)
    assert "error" not in r, r
    V, F = load_mesh_by_index(path)
    from bd_uv.frames import lscm_map
    from bd_uv.geometry import local_coordinates

    isl = bd_uv.islands(V, F)[0]
    u = lscm_map(local_coordinates(V[isl.vertices], isl.tris), isl.tris, len(isl.vertices),
                 isl.loops)
    cu = np.zeros((len(F), 3, 2))
    cu[isl.faces] = np.stack([u[isl.tris].real, u[isl.tris].imag], axis=-1)
    st = uv_stats(V, F, cu)
    assert r["flips"] == st.flips == 0
    assert r["max_d"] == pytest.approx(st.max_distortion, rel=1e-12)
    assert r["rss_peak_mb"] >= r["rss_base_mb"] > 0
    # a call under REPEAT_BELOW is timed again (at least once more: its first call is within
    # REPEAT_SECONDS), one above it once
    from isolate import REPEAT_BELOW, REPEAT_MAX
    assert (r["calls"] > 1) == (r["seconds"] < REPEAT_BELOW) and r["calls"] <= REPEAT_MAX


def _row(mesh, key, seconds, max_d, mean_d, flips=0, c=None):
    return bench_unwrap.Row(mesh, 100, key, seconds=seconds, max_d=max_d, mean_d=mean_d,
                            flips=flips, certified_c=c)


def test_done_when_verdicts():
    rows = [
        _row("a", "blender-abf", 1.0, 2.0, 1.10),
        _row("a", "blender-lscm", 0.5, 1.9, 1.10),
        _row("a", "blender-minstretch", 1.0, 3.0, 1.3),
        _row("a", "igl-slim", 1.0, 1.7, 1.3, flips=0),
        _row("a", "bd-init-lscm", 0.1, 1.8, 1.10),
        _row("a", "bd-lscm-5", 0.9, 1.8, 1.12, c=5.0),           # mean 1.12 <= 1.122
        _row("a", "bd-lscm-auto", 2.0, 1.6, 1.15, c=1.6),        # 1.6 < 1.7, mean 1.15 <= 1.155
        _row("b", "blender-abf", 1.0, 2.0, 1.0),
        _row("b", "blender-lscm", 0.5, 1.0, 1.0, flips=3),        # flipped: not a candidate
        _row("b", "blender-minstretch", 1.0, 3.0, 1.3),
        _row("b", "igl-slim", 1.0, 2.5, 1.3),
        _row("b", "bd-init-lscm", 0.1, 1e4, 1.5, flips=2),
        _row("b", "bd-lscm-5", 4.0, 5.0, 1.03, c=5.0),            # mean 1.03 > 1.02, 4x time
        _row("b", "bd-lscm-auto", 2.5, 2.0, 1.04, c=2.0),         # 2.0 == ABF max: not below
    ]
    text = "\n".join(bench_unwrap.done_when(rows, bench_unwrap.DEFAULT_ORDER))
    line = {ln.split(":")[0] + ":" + ln.split(":")[1]: ln for ln in text.splitlines()
            if ln.startswith("- **")}

    def verdict(prefix):
        hits = [v for k, v in line.items() if prefix in k]
        assert len(hits) == 1, (prefix, list(line))
        return hits[0].split("**")[1]

    assert verdict("C=5: 0 flips") == "PASS"
    assert verdict("C=5: max D <= 5") == "PASS"
    assert verdict("C=5: max D <= initial") == "PASS"        # b's initial map flips: n/a
    assert verdict("C=5: mean D") == "FAIL"
    assert verdict("auto: certified C") == "FAIL"
    assert verdict("auto: mean D") == "PASS"
    assert verdict("auto: median time") == "PASS"            # median(2.0, 2.5)
    assert verdict("C=5: median time") == "FAIL"             # median(0.9, 4.0) = 2.45
    assert verdict("C=5: no mesh above 3x") == "FAIL"
    assert "n/a (initial map flips)" in text


def test_auto_quality_grids_are_the_test_suites_grids():
    """``bench_auto_quality``'s height-field grids are the surfaces the earlier passes' quality
    tables used (``tests/core/helpers.grid``), vertex for vertex and triangle for triangle."""
    import bench_auto_quality
    from helpers import grid

    for name, (nx, ny, z) in bench_auto_quality.GRIDS.items():
        V, F = bench_auto_quality.load(name)
        V0, F0 = grid(nx, ny, z=z)
        assert np.array_equal(V, V0) and np.array_equal(F, F0), name
        assert len(F) == 2 * (nx - 1) * (ny - 1)
    assert [len(bench_auto_quality.load(n)[1]) for n in ("grid8", "grid9", "grid12")] == \
        [98, 112, 242]


def test_no_waiting_disk_table_reports_a_refused_disk_and_fails_it():
    """A bd-uv call that returns no map (its mean distortion None) gets a row saying why and
    fails auto's quality criteria, instead of stopping the table."""
    import bench_no_waiting as bnw
    row = dict(seconds=0.01, faces=500, max_d=1.2, mean_d=1.05, certified_c=None, note="")
    res = {}
    for p, auto in (("ok.obj", dict(row, seconds=0.015, max_d=1.1, mean_d=1.04, certified_c=1.1)),
                    ("bowtie.obj", dict(row, max_d=None, mean_d=None,
                                        note="failed: non-manifold vertex"))):
        for k in bnw.PEERS:
            res[(p, k)] = dict(row)
        res[(p, "bd-lscm-5")] = dict(row, seconds=0.005, certified_c=5.0)
        res[(p, "bd-lscm-auto")] = auto
    lines, crit = bnw.disk_table(["ok.obj", "bowtie.obj"], res)
    verdict = dict(crit)
    assert any("bowtie.obj" in ln and "non-manifold vertex" in ln for ln in lines)
    assert any(ln.startswith("| ok.obj | 500 |") and "| 1.50 |" in ln for ln in lines)
    assert verdict["auto / ABF <= 2.0 on every disk"]           # 0.015 / 0.01 on the one map
    assert not verdict["auto's certified C < every peer's max distortion"]
    assert not verdict["auto's mean <= 1.05 x ABF's"]


def _strip_disk(n=6):
    """A 2 x n vertex strip (2 (n-1) triangles, counter-clockwise in (x, y)) in the plane."""
    x = np.arange(n, dtype=np.float64)
    V = np.r_[np.c_[x, np.zeros(n), np.zeros(n)], np.c_[x, np.ones(n), np.zeros(n)]]
    i = np.arange(n - 1)
    F = np.r_[np.c_[i, i + 1, i + n + 1], np.c_[i, i + n + 1, i + n]].astype(np.int64)
    return V, F


def test_map_shape_counts_uv_pieces_and_finds_a_self_overlap():
    """``isolate.map_shape`` on hand-made UVs of a planar strip: the identity map is one piece
    with no overlap; moving the last column's UVs apart cuts it into two pieces; a map wound
    round past a full turn (no flip, boundary crossing itself) overlaps; a mirrored face
    overlaps."""
    from isolate import map_shape
    V, F = _strip_disk(6)
    cu = V[F][:, :, :2].copy()
    assert map_shape(F, cu, 0) == (1, False)
    cut = cu.copy()
    last = np.isin(F, [4, 5, 10, 11]).all(axis=1)            # the two faces of the last cell
    assert last.sum() == 2
    cut[last] += 10.0                                          # their own UVs, away from the rest
    assert map_shape(F, cut, 0) == (2, False)
    # wrap the strip's long axis round an annulus through 1.6 turns: locally fine, globally
    # lying over itself
    n = 12
    V, F = _strip_disk(n)
    t = V[:, 0] / (n - 1) * 1.6 * 2 * np.pi
    r = 3.0 - V[:, 1]                                     # inward with y: counter-clockwise
    U = np.c_[r * np.cos(t), r * np.sin(t)]
    cu = U[F]
    st = uv_stats(V, F, cu)
    assert st.flips == 0
    assert map_shape(F, cu, st.flips) == (1, True)
    assert map_shape(F, V[F][:, :, :2], 0) == (1, False)
    flipped = V[F][:, :, :2].copy()
    flipped[0] = flipped[0][[0, 2, 1]]
    assert map_shape(F, flipped, 1)[1]


def test_no_waiting_disk_table_judges_c_against_one_to_one_peers_and_counts_pieces():
    """The table prints each peer's max with "ov" where the peer's map overlaps itself, auto's C
    against all peers (as before) and against the one-to-one peers only, and the pieces at auto
    and C = 5; one piece per disk is a criterion of its own."""
    import bench_no_waiting as bnw
    row = dict(seconds=0.01, faces=500, max_d=1.2, mean_d=1.05, certified_c=None, note="",
               overlaps=False, pieces=1)
    res = {}
    for p in ("a.obj", "b.obj"):
        for k in bnw.PEERS:
            res[(p, k)] = dict(row, max_d=3.0)
        res[(p, "bd-lscm-5")] = dict(row, seconds=0.005, certified_c=5.0)
        res[(p, "bd-lscm-auto")] = dict(row, certified_c=1.5)
    res[("a.obj", "blender-abf")] = dict(row, max_d=1.3, overlaps=True)   # below C, overlapping
    res[("b.obj", "bd-lscm-5")]["pieces"] = 3
    lines, crit = bnw.disk_table(["a.obj", "b.obj"], res)
    verdict = dict(crit)
    a = next(ln for ln in lines if ln.startswith("| a.obj |")).split(" | ")
    assert a[8:12] == ["1.3", "3", "1.3 ov, 3, 3, 3", "1, 1"]
    b = next(ln for ln in lines if ln.startswith("| b.obj |")).split(" | ")
    assert b[8:12] == ["3", "3", "3, 3, 3, 3", "1, 3"]
    assert not verdict["auto's certified C < every peer's max distortion"]
    one_to_one = [ok for what, ok in crit if "does not overlap itself" in what]
    assert one_to_one == [True]
    assert not verdict["one piece per disk at auto and at C = 5"]


def test_patch_of_a_surface_with_no_disk_ring_is_refused(tmp_path):
    """A torus's rings around a face close into an annulus (the ball wraps around the tube) and
    then the whole torus: from some size no whole ring is a disk, and patch says so instead of
    writing the closed surface."""
    import trimesh
    t = trimesh.creation.torus(major_radius=1.0, minor_radius=0.6, major_sections=12,
                               minor_sections=8)
    src = assets.write_obj(str(tmp_path / "torus.obj"), t.vertices, t.faces)
    assert len(t.faces) == 192
    with pytest.raises(ValueError, match="no whole ring"):
        assets.patch(src, 190, out_dir=str(tmp_path))
    V, F = load_mesh_by_index(assets.patch(src, 20, out_dir=str(tmp_path)))
    assert assets.is_disk(F) and len(F) >= 20


def _source_faces(V0, F0, path):
    """Indices into F0 of the faces written to ``path`` (matched by their corners' positions)."""
    key = {tuple(sorted(map(tuple, V0[f]))): i for i, f in enumerate(F0)}
    V, F = load_mesh_by_index(path)
    return np.array(sorted(key[tuple(sorted(map(tuple, V[f])))] for f in F))


def _rings(F, seeds):
    """Each face's number of steps over shared edges from the nearest seed face (plain BFS)."""
    by_edge = {}
    for i, f in enumerate(F):
        for a, b in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0])):
            by_edge.setdefault((min(a, b), max(a, b)), []).append(i)
    nbr = [[] for _ in F]
    for fs in by_edge.values():
        for i in fs:
            nbr[i] += [j for j in fs if j != i]
    dist = np.full(len(F), -1)
    dist[list(seeds)] = 0
    todo = list(seeds)
    while todo:
        nxt = []
        for i in todo:
            for j in nbr[i]:
                if dist[j] < 0:
                    dist[j] = dist[i] + 1
                    nxt.append(j)
        todo = nxt
    return dist


def _whole_rings_and_least(F0, dist, got, faces):
    """``got`` is every face within its largest ring, at least ``faces`` faces, a disk, and no
    fewer whole rings holding at least ``faces`` faces make a disk."""
    r = dist[got].max()
    assert np.array_equal(got, np.flatnonzero(dist <= r))
    assert len(got) >= faces and assets.is_disk(F0[got])
    for q in range(r):
        fewer = np.flatnonzero(dist <= q)
        assert len(fewer) < faces or not assets.is_disk(F0[fewer])


def test_ball_and_strip_are_whole_rings_round_a_box_point_and_a_path(tmp_path):
    """assets.ball grows rings round the face nearest the centre of a side of the bounding box,
    assets.strip round a shortest face path between the faces nearest two opposite sides; both
    checked against a plain breadth-first search on cow.off (ball 150 at x+ has 169 faces, as
    issue21-unseen16-2026-11-28.md's cow-ball150x+ did)."""
    src = os.path.join(DATA, "cow.off")
    V0, F0 = load_mesh_by_index(src)
    cen = V0[F0].mean(axis=1)
    lo, hi = V0.min(axis=0), V0.max(axis=0)
    near = [int(np.argmin(((cen - p) ** 2).sum(axis=1))) for p in
            ([hi[0], (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2],
             [(lo[0] + hi[0]) / 2, lo[1], (lo[2] + hi[2]) / 2],
             [(lo[0] + hi[0]) / 2, hi[1], (lo[2] + hi[2]) / 2])]
    got = _source_faces(V0, F0, assets.ball(src, 150, "x+", out_dir=str(tmp_path)))
    assert len(got) == 169
    _whole_rings_and_least(F0, _rings(F0, [near[0]]), got, 150)
    p = assets.strip(src, 600, "y", out_dir=str(tmp_path))
    assert os.path.basename(p) == "cow-strip600y.obj"
    # the route: from the face at the least y to the one at the largest, each face sharing an
    # edge with the next, as many steps as a breadth-first search from the first end takes
    route = assets.strip_route(V0, F0, "y")
    d0 = _rings(F0, [near[1]])
    assert route[0] == near[1] and route[-1] == near[2] and len(route) == d0[near[2]] + 1
    assert all(len(set(F0[a]) & set(F0[b])) == 2 for a, b in zip(route[:-1], route[1:]))
    got = _source_faces(V0, F0, p)
    _whole_rings_and_least(F0, _rings(F0, route), got, 600)
