"""A mesh that is one clean disk, found, solved and certified in one pass (``unwrapping.one_disk``,
``unwrapping.disk_certificate``): the same island, map and certificate as the general path, and
nothing accepted that the general path would refuse or word otherwise."""
import dataclasses

import numpy as np
import pytest

import bd_uv
from bd_uv.certificate import certify_islands
from bd_uv.mesh import checked_islands
from bd_uv.options import unwrap_options
from bd_uv.overlap import island_overlaps
from bd_uv.unwrapping import disk_certificate, disk_conformal, one_disk
from bd_uv.unwrapping.unwrap import pin_arrays, unwrap_islands
from bd_uv.unwrapping.rounding import tightened
from helpers import grid, load_off, rings
from unwrap_contract import distortion_and_flips


def curved_grid(n=8):
    return grid(n, n, z=lambda x, y: 0.3 * np.sin(3 * x) * np.cos(2 * y))


def jagged():
    """A grid with every other boundary face of its bottom row taken out: a sawtooth boundary,
    not star-shaped from any point once mapped."""
    V, F = curved_grid(10)
    # the bottom row's triangles on the boundary edge (the first of each square's two)
    bottom = np.flatnonzero(V[F].max(axis=1)[:, 1] < 0.1)
    bottom = bottom[bottom < len(F) // 2]
    F = np.delete(F, bottom[::2], axis=0)
    used, inv = np.unique(F, return_inverse=True)
    return V[used], inv.reshape(-1, 3)


def unused_vertex():
    """A grid whose vertex list holds a vertex no face uses (first and in the middle)."""
    V, F = curved_grid(6)
    V = np.r_[[[9.0, 9.0, 9.0]], V[:20], [[7.0, 7.0, 7.0]], V[20:]]
    return V, np.where(F >= 20, F + 2, F + 1)


DISKS = {"grid": curved_grid, "nefertiti": lambda: load_off("nefertiti.off"), "jagged": jagged,
         "unused vertex": unused_vertex,
         "one face": lambda: (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.5]], float),
                              np.array([[0, 1, 2]]))}


def general(V, F, **kw):
    """The general path on the same arrays: checked_islands, the batched conformal map, the
    overlap certificate (and for "auto" the C kept only as far above the max as float32 needs,
    which ``unwrap`` does last on either path: ``rounding.tightened``)."""
    res = unwrap_islands(V, F, checked_islands(V, F), pin_arrays(None, None, len(F)),
                         unwrap_options(None, **kw))
    return tightened(V, F, res) if kw.get("bound") == "auto" else res


@pytest.mark.parametrize("name", sorted(DISKS))
def test_the_island_is_checked_islands_one(name):
    V, F = DISKS[name]()
    disk = one_disk.find(V, F.astype(np.int64))
    (isl,) = checked_islands(V, F.astype(np.int64))
    assert disk is not None and isl.error is None
    a = disk.island
    assert np.array_equal(a.faces, isl.faces) and np.array_equal(a.vertices, isl.vertices)
    assert np.array_equal(a.tris, isl.tris)
    assert len(a.loops) == len(isl.loops) == 1 and np.array_equal(a.loops[0], isl.loops[0])



def _same(a, b):
    """Two certificates equal field by field, NaN equal to NaN (a dataclass's == compares NaN
    fields by identity, which numpy 2's scalars do not keep)."""
    fa, fb = dataclasses.astuple(a), dataclasses.astuple(b)
    return type(a) is type(b) and all(
        x == y or (isinstance(x, float) and isinstance(y, float) and x != x and y != y)
        for x, y in zip(fa, fb))

@pytest.mark.parametrize("name", sorted(DISKS))
@pytest.mark.parametrize("bound", [5.0, 1.05, "auto"])
def test_the_one_pass_gives_the_general_paths_map_and_certificate(name, bound):
    """At C = 5 the conformal map fits; at 1.05 it does not (but for the one face) and the
    general path bends it from the same conformal map; "auto" searches from it and is certified
    by the one-disk certificate. The same UVs bit for bit, the same certificate, the island's
    figures as its certificate measures them; for "auto" to rounding (its search runs on the
    disk's own geometry, the general path's on a copy scaled to unit area: the same iterations
    and C, the UVs within 1e-11 of their extent)."""
    V, F = DISKS[name]()
    fast = bd_uv.unwrap(V, F, bound=bound)
    ref = general(V, np.asarray(F, np.int64), bound=bound)
    if bound == "auto":
        extent = np.ptp(ref.corner_uv.reshape(-1, 2), axis=0).max()
        assert np.abs(fast.corner_uv - ref.corner_uv).max() <= 1e-11 * extent
        assert fast.islands[0].iterations == ref.islands[0].iterations
        a, b = fast.certificates[0], ref.certificates[0]
        assert a.certified and b.certified and a.bound == b.bound
        assert np.isclose(a.max_distortion, b.max_distortion, rtol=1e-12, atol=0)
        assert np.isclose(a.mean_distortion, b.mean_distortion, rtol=1e-12, atol=0)
    else:
        assert np.array_equal(fast.corner_uv, ref.corner_uv, equal_nan=True)
        assert all(map(_same, fast.certificates, ref.certificates))
    assert len(fast.certificates) == len(ref.certificates)
    (r,) = fast.islands
    (g,) = ref.islands
    assert r.status == g.status == "certified" and r.flags == g.flags
    assert r.bound_certified == g.bound_certified
    assert np.isclose(r.max_distortion, g.max_distortion, rtol=1e-12, atol=0)
    assert np.isclose(r.mean_distortion, g.mean_distortion, rtol=1e-12, atol=0)
    # (a face's distortion moves with its corners: 4e-12 on nefertiti's at "auto")
    assert np.allclose(r.distortion, g.distortion, rtol=1e-12 if bound != "auto" else 1e-10,
                       atol=0)
    assert np.isclose(r.min_singular, g.min_singular, rtol=1e-12)
    assert np.isclose(r.max_singular, g.max_singular, rtol=1e-12)
    (c,) = certify_islands(V, F, fast.corner_uv, fast.face_island, [r.bound_certified])
    assert c.certified and _same(c, fast.certificates[0])
    assert r.max_distortion == c.max_distortion


def test_the_known_edges_build_the_sorted_edges_system():
    from bd_uv.solvers.lscm import _lscm_system, face_geometry
    V, F = load_off("nefertiti.off")
    disk = one_disk.find(V, F)
    isl = disk.island
    g = face_geometry(V[isl.vertices], isl.tris)
    idx, val = disk_conformal._far_pair(V[isl.vertices], isl.loops[0]), np.array([0.0, 1.0], complex)
    A, rhs, _, _ = _lscm_system(g.cbw(), g.cb, isl.tris, len(isl.vertices), idx, val)
    B, rhs2, _, _ = _lscm_system(g.cbw(), g.cb, isl.tris, len(isl.vertices), idx, val,
                                 (disk.twins[0], disk.twins[1], disk.loop))
    assert np.array_equal(A.indptr, B.indptr) and np.array_equal(A.indices, B.indices)
    assert np.array_equal(A.data, B.data) and np.array_equal(rhs, rhs2)


def torus(nu=10, nv=6):
    u, v = np.meshgrid(np.arange(nu) * 2 * np.pi / nu, np.arange(nv) * 2 * np.pi / nv,
                       indexing="ij")
    V = np.stack([(2 + 0.7 * np.cos(v)) * np.cos(u), (2 + 0.7 * np.cos(v)) * np.sin(u),
                  0.7 * np.sin(v)], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    idx = lambda i, j: (i % nu) * nv + (j % nv)
    a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
    return V, np.stack([np.stack([a, b, c], -1), np.stack([a, c, d], -1)], -2).reshape(-1, 3)


def _with(V, F, V2, F2, shift=5.0):
    return np.r_[V, V2 + [shift, 0, 0]], np.r_[F, F2 + len(V)]


def _not_disks():
    V, F = curved_grid(6)
    n = 6
    out = {}
    # Euler characteristic 1 + 0 and one boundary loop: only the component count tells
    out["disk and torus"] = _with(V, F, *torus())
    out["two disks"] = _with(V, F, V, F)
    W, G = V.copy(), F.copy()
    G[G == 4 * n + 4] = n + 1             # two interior vertices made one: a bow-tie of two
    out["closed fans pinched"] = (W, G)   # closed fans (only the Euler characteristic tells)
    G = F.copy()
    G[G == n - 1] = 0                     # two boundary vertices made one: a pinched boundary
    out["boundary pinched"] = (V, G)
    out["hole"] = (V, F[~(F == 2 * n + 2).any(axis=1)])     # the fan of an inner vertex out
    G = F.copy()
    G[3] = G[3, ::-1]
    out["flipped face"] = (V, G)
    W = V.copy()
    W[F[0, 2]] = W[F[0, 0]]
    out["degenerate face"] = (W, F)
    W = V.copy()
    W[7, 2] = np.nan
    out["NaN"] = (W, F)
    out["overflow"] = (V * 1e200, F)
    out["edge in three faces"] = (np.r_[V, [[0.1, 0.1, 1.0]]], np.r_[F, [[F[0, 0], F[0, 1],
                                                                         len(V)]]])
    out["repeated face"] = (V, np.r_[F, F[:1]])
    out["repeated vertex"] = (V, np.r_[F, [[F[0, 0], F[0, 0], F[0, 1]]]])
    Vt = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    out["closed"] = (Vt, np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]))
    return out


@pytest.mark.parametrize("name", sorted(_not_disks()))
def test_what_is_not_one_clean_disk_goes_the_general_way(name):
    V, F = _not_disks()[name]
    F = np.asarray(F, np.int64)
    assert one_disk.find(V, F) is None
    isl = checked_islands(V, F)
    assert len(isl) > 1 or isl[0].error is not None or len(isl[0].loops) != 1


def test_an_overlapping_conformal_map_is_cut_by_the_general_path():
    """A strip wound one and a half times round a low helix: nearly flat, its conformal map is
    an annulus sector of ~3 pi, lying over itself. The one pass finds the disk but does not clear
    its certificate; the general path cuts it, as it would have anyway."""
    t = np.linspace(0, 3 * np.pi, 150)
    n = len(t)
    V = np.r_[np.stack([np.cos(t), np.sin(t), 0.1 * t], 1),
              np.stack([1.3 * np.cos(t), 1.3 * np.sin(t), 0.1 * t], 1)]
    j = np.arange(n - 1)
    F = np.r_[np.c_[j, n + j, j + 1], np.c_[n + j, n + j + 1, j + 1]].astype(np.int64)
    assert one_disk.find(V, F) is not None
    res = bd_uv.unwrap(V, F, bound=5.0)
    ref = general(V, F, bound=5.0)
    assert len(res.islands) == 2 and all("cut" in r.flags for r in res.islands)
    assert np.array_equal(res.corner_uv, ref.corner_uv, equal_nan=True)
    assert [r.flags for r in res.islands] == [r.flags for r in ref.islands]
    assert [c.certified for c in certify_islands(V, F, res.corner_uv, res.face_island,
                                                 [5.0, 5.0])] == [True, True]


def _helix_strip():
    """``test_an_overlapping_conformal_map_is_cut_by_the_general_path``'s strip (298 faces)."""
    t = np.linspace(0, 3 * np.pi, 150)
    n = len(t)
    V = np.r_[np.stack([np.cos(t), np.sin(t), 0.1 * t], 1),
              np.stack([1.3 * np.cos(t), 1.3 * np.sin(t), 0.1 * t], 1)]
    j = np.arange(n - 1)
    return V, np.r_[np.c_[j, n + j, j + 1], np.c_[n + j, n + j + 1, j + 1]].astype(np.int64)


def test_auto_over_one_product_faces_leaves_a_conformal_map_over_itself_to_the_general_path(
        monkeypatch):
    """bound="auto" on a disk over ONE_PRODUCT_FACES faces (within AUTO_FACES): a conformal map
    whose boundary is not one simple loop is left to the general path before any search here
    (which would search it again): the general path's UVs bit for bit, one search only."""
    import time
    import bd_uv.solvers.bound_search as bs
    from bd_uv.unwrapping import disk_auto
    V, F = _helix_strip()
    disk = one_disk.find(V, F)
    _, u, _ = one_disk.unwrap_disk(V, F, disk, None, time.perf_counter())
    assert not disk_certificate.simple_ccw_loop(np.c_[u.real, u.imag][disk.island.loops[0]])
    monkeypatch.setattr(bs, "ONE_PRODUCT_FACES", len(F) - 1)
    assert len(F) <= disk_auto.AUTO_FACES
    searches = []
    run = bs.BoundSearch.search

    def counted(self, *a, **k):
        searches.append(self.k)
        return run(self, *a, **k)
    monkeypatch.setattr(bs.BoundSearch, "search", counted)
    assert disk_auto.minimise_disk(V, disk, u, 1000.0, 0.0) is None and not searches
    res = bd_uv.unwrap(V, F, bound="auto")
    n = len(searches)
    monkeypatch.setattr(disk_auto, "AUTO_FACES", 0)
    ref = bd_uv.unwrap(V, F, bound="auto")
    assert len(searches) == 2 * n
    assert np.array_equal(res.corner_uv, ref.corner_uv, equal_nan=True)
    assert [r.flags for r in res.islands] == [r.flags for r in ref.islands]
    certs = certify_islands(V, F, res.corner_uv, res.face_island,
                            [r.bound_certified for r in res.islands])
    assert all(c.certified and c.overlap_free for c in certs)


def test_a_search_whose_map_the_disk_certificate_refuses_is_not_run_again(monkeypatch):
    """bound="auto": where the one-disk path's searched map is not cleared by its certificate
    (a map lying over itself, as libigl bunny's 1,595-face patch: its conformal map is one
    simple loop, its searched map turns twice), the general path takes that search
    (``searched.hand_over``) instead of running its iterations again: one search, the general
    path's iterations, bound and UVs to rounding; a search of another start runs as ever."""
    import bd_uv.solvers.bound_search as bs
    from bd_uv.unwrapping import disk_auto, searched
    V, F = curved_grid()
    runs = []
    run = bs.BoundSearch.search

    def counted(self, *a, **k):
        runs.append(self.k)
        return run(self, *a, **k)
    monkeypatch.setattr(bs.BoundSearch, "search", counted)
    gate = disk_auto.AUTO_FACES
    monkeypatch.setattr(disk_auto, "AUTO_FACES", 0)
    ref = bd_uv.unwrap(V, F, bound="auto")
    assert len(runs) == 1
    monkeypatch.setattr(disk_auto, "AUTO_FACES", gate)
    monkeypatch.setattr(disk_auto, "_certified", lambda *a, **k: None)
    res = bd_uv.unwrap(V, F, bound="auto")
    assert len(runs) == 2                       # the one-disk path's search only
    (a,), (b,) = res.islands, ref.islands
    assert a.iterations == b.iterations and a.bound_certified == b.bound_certified
    assert a.flags == b.flags and "projected" in a.flags
    assert np.abs(res.corner_uv - ref.corner_uv).max() < 1e-12
    assert certify_islands(V, F, res.corner_uv, res.face_island, [a.bound_certified])[0].certified
    # kept for that island and start only, and once
    prob = type("P", (), {"island": object(), "pin_idx": np.zeros(0, np.int64)})()
    u = np.arange(3.0) + 0j
    searched.hand_over(prob.island, u, u + 1, 1.5, 7)
    assert searched._handed_over(prob, u + 0, True)[1:] == (1.5, 7)
    assert searched._handed_over(prob, u, True) is None
    searched.hand_over(prob.island, u, u + 1, 1.5, 7)
    assert searched._handed_over(prob, u + 1, True) is None


def _central_rings(V, F, faces):
    """Whole rings of faces around the face nearest the vertices' mean, grown over shared edges
    until at least ``faces`` faces: a disk cut from a closed or larger mesh."""
    seed = int(np.argmin(np.linalg.norm(V[F].mean(axis=1) - V.mean(axis=0), axis=1)))
    return rings(V, F, seed, faces)


def test_a_conformal_map_lying_over_itself_stays_one_island_at_a_lower_bound():
    """three_peaks' 554-face centre: its conformal map is flip-free and within C = 5 but folds
    over itself, which the general path cut into 3 islands (one of a single face). The one pass
    runs auto's search for the smallest C instead, up to its first map that does not lie over
    itself: one island, certified at the bound asked with a max distortion far below it,
    flagged "unfolded", and not the least C (the search stopped early: a map nearer the
    conformal one, whose mean is lower than the least C's); checked here from the UVs with
    numpy's SVD and shapely."""
    import shapely
    V, F = _central_rings(*load_off("three_peaks.off"), 500)
    assert len(F) == 554
    disk = one_disk.find(V, F)
    assert disk is not None
    done, u, overlaps = one_disk.unwrap_disk(V, F, disk, 5.0, 0.0)
    assert done is None and overlaps            # the conformal map within 5 lies over itself
    res = bd_uv.unwrap(V, F, bound=5.0)
    assert len(res.islands) == 1
    r = res.islands[0]
    assert r.status == "certified" and "unfolded" in r.flags and r.bound_requested == 5.0
    assert r.bound_certified == 5.0 and r.max_distortion < 2.0
    least = bd_uv.unwrap(V, F, bound="auto").islands[0]
    assert least.max_distortion < r.max_distortion and r.mean_distortion < least.mean_distortion
    uv = res.corner_uv
    # distortion and flips from each face's Jacobian in its own 3D frame (numpy's SVD)
    D, flipped = distortion_and_flips(V, F, uv)
    assert not flipped.any()
    assert D.max() <= r.max_distortion * (1 + 1e-9)
    # no overlap: the triangles' union covers the sum of their areas
    tris = shapely.polygons(uv)
    assert shapely.area(shapely.union_all(tris)) == pytest.approx(shapely.area(tris).sum(),
                                                                   rel=1e-9)


def test_islands_lying_over_themselves_are_unfolded_on_the_general_path_too():
    """Two copies of that centre, one mesh (not one disk: the general path, per island): each
    island gets the smallest C within the 5 asked before any cut, as the one pass does; with
    a pin on the second its map stays pinned and that island is cut as before."""
    V, F = _central_rings(*load_off("three_peaks.off"), 500)
    V2, F2 = np.r_[V, V + [10.0, 0.0, 0.0]], np.r_[F, F + len(V)]
    res = bd_uv.unwrap(V2, F2, bound=5.0)
    assert [(len(r.faces), r.status, "unfolded" in r.flags) for r in res.islands] == [
        (554, "certified", True), (554, "certified", True)]
    certs = certify_islands(V2, F2, res.corner_uv, res.face_island,
                            [r.bound_certified for r in res.islands])
    assert all(c.certified and c.overlap_free and c.max_distortion < 2.0 for c in certs)
    pinned = bd_uv.unwrap(V2, F2, bound=5.0, pin_corners=[3 * len(F), 3 * len(F) + 1],
                          pin_uv=[[0.0, 0.0], [1.0, 0.0]])
    assert "unfolded" in pinned.islands[0].flags
    pieces = pinned.islands[1:]                 # the pinned copy, cut as before
    assert len(pieces) >= 2 and all(r.cut_from == 1 for r in pieces)
    assert all("cut" in r.flags and "unfolded" not in r.flags for r in pieces)
    assert all(r.status == "certified" for r in pinned.islands)


def _fan(p):
    """A triangle fan over the polygon p (k,2): its faces and corner UVs, whose UV boundary is
    the polygon (faces may flip: the boundary is what island_overlaps reads)."""
    k = len(p)
    j = np.arange(1, k - 1)
    F = np.c_[np.zeros_like(j), j, j + 1]
    return F, p[F]


def _polygons(rng):
    for _ in range(300):
        k = int(rng.integers(3, 40))
        ang = np.sort(rng.uniform(0, 2 * np.pi, k))
        rad = rng.uniform(0.2, 1.0, k)
        p = np.c_[rad * np.cos(ang), rad * np.sin(ang)]
        kind = rng.integers(0, 6)
        if kind == 1:
            p = p[::-1]                                    # clockwise
        elif kind == 2:
            p = p + rng.normal(0, 0.3, p.shape)            # often crossing itself
        elif kind == 3 and k > 4:
            p[k // 2] = p[0]                               # a pinch
        elif kind == 4:
            p = p + [rng.uniform(-2, 2), rng.uniform(-2, 2)]   # star-shaped but not about 0
            p[:, 0] *= rng.uniform(0.05, 3)
        elif kind == 5 and k > 4:
            p[2] = p[1] + 0.5 * (p[1] - p[0]) * -1        # folds back onto the segment before
        yield p


TOUCHING = [np.array([[0, 0], [4, 0], [4, 4], [2, 0], [0, 4]], float),   # a point on an edge
            np.array([[0, 0], [4, 0], [4, 4], [2, 4], [2, 6], [2, 2], [0, 4]], float),  # overlap
            np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)]                 # a square


def test_the_polygon_tests_agree_with_island_overlaps():
    """Random polygons (star-shaped about the origin or elsewhere, clockwise, noisy, pinched,
    folded) and exact touching ones (orientations exactly 0: decided by GEOS)."""
    rng = np.random.default_rng(20261127)
    seen = {True: 0, False: 0}
    star = refused = 0
    for p in [*_polygons(rng), *TOUCHING]:
        q = np.concatenate([p[1:], p[:1]])
        F, uv = _fan(p)
        truth = bool(island_overlaps(F, uv, np.zeros(len(F), np.int64)).overlap_free[0])
        assert disk_certificate._simple_ccw(p, q) == truth
        assert disk_certificate.simple_ccw_loop(p) == truth
        # the cheap turning test refuses no simple counter-clockwise polygon
        turns = disk_certificate.turns_once(p[:, 0] + 1j * p[:, 1])
        assert turns or not truth
        refused += not turns
        if disk_certificate._star_shaped(p, q):
            star += 1
            assert truth
        seen[truth] += 1
    assert seen[True] > 50 and seen[False] > 50 and star > 20 and refused > 20


def test_the_free_unknowns_iterations_reach_the_whole_maps_bound(monkeypatch):
    """bound="auto" on a small island iterates on the free unknowns (``BoundSearch._run_free``);
    the iterations on the whole map (the path of islands over ONE_PRODUCT_FACES faces) reach the
    same bound, to rounding."""
    import bd_uv.solvers.bound_search as bs
    from bd_uv.unwrapping import disk_auto, searched
    V, F = load_off("nefertiti.off")
    small = bd_uv.unwrap(V, F, bound="auto")
    monkeypatch.setattr(bs, "ONE_PRODUCT_FACES", 0)
    monkeypatch.setattr(disk_auto, "AUTO_FACES", 0)     # the general path: the whole map
    monkeypatch.setattr(searched, "FREE_FACES", 0)      # (its least C's free gate too)
    whole = bd_uv.unwrap(V, F, bound="auto")
    a, b = small.islands[0], whole.islands[0]
    assert a.iterations == b.iterations
    assert abs(a.max_distortion - b.max_distortion) < 1e-9
    assert small.certificates[0].certified and whole.certificates[0].certified


@pytest.mark.parametrize("name", ["grid", "nefertiti", "jagged"])
@pytest.mark.parametrize("precision", [None, np.float32])
def test_a_clean_disk_needs_no_repair(name, precision, monkeypatch):
    """seams="needed" (the command line's and Blender's default) skips repair.repair_mesh on a
    clean disk: the same result as with the repair run."""
    import bd_uv.seams.needed as needed
    V, F = DISKS[name]()
    assert needed.clean_disk(V, F, precision)
    fast = bd_uv.unwrap(V, F, seams="needed", precision=precision)
    monkeypatch.setattr(needed, "clean_disk", lambda *a: False)
    ref = bd_uv.unwrap(V, F, seams="needed", precision=precision)
    assert np.array_equal(fast.corner_uv, ref.corner_uv, equal_nan=True)
    assert np.array_equal(fast.face_island, ref.face_island)
    assert fast.repair == ref.repair == () and fast.seams_added.shape == ref.seams_added.shape
    assert [(r.status, r.flags, r.bound_certified, r.max_distortion) for r in fast.islands] == \
        [(r.status, r.flags, r.bound_certified, r.max_distortion) for r in ref.islands]
    assert np.array_equal(fast.islands[0].faces, ref.islands[0].faces)
    assert np.array_equal(fast.islands[0].vertices, ref.islands[0].vertices)


def test_needed_mode_finds_a_clean_disk_once(monkeypatch):
    """seams="needed" finds the disk once (``seams.needed.clean_disk``) and the unwrap takes it
    as found: the same corner UVs as ``seams="marked"``, which finds it itself."""
    V, F = DISKS["nefertiti"]()
    calls = []
    real = one_disk.find

    def counted(*args):
        calls.append(1)
        return real(*args)
    monkeypatch.setattr(one_disk, "find", counted)
    res = bd_uv.unwrap(V, F, seams="needed")
    assert len(calls) == 1
    calls.clear()
    ref = bd_uv.unwrap(V, F)
    assert len(calls) == 1
    assert np.array_equal(res.corner_uv, ref.corner_uv)
    assert res.islands[0].bound_certified == ref.islands[0].bound_certified


def test_a_face_float32_cannot_tell_from_a_line_is_repaired():
    """A disk with one face thinner than a float32 step at its coordinates: clean in float64,
    so only the float32 precision sends it to the repair, which leaves that face out."""
    import bd_uv.seams.needed as needed
    V, F = curved_grid(6)
    V = V + 1000.0                        # float32 steps of 6e-5 there
    f = F[len(F) // 2]
    V[f[2]] = 0.5 * (V[f[0]] + V[f[1]]) + [0.0, 0.0, 1e-6]   # the face's third corner on its edge
    assert (needed.clean_disk(V, F, None) is not None) == (one_disk.find(V, F) is not None)
    assert not needed.clean_disk(V, F, np.float32)
    res = bd_uv.unwrap(V, F, seams="needed", precision=np.float32)
    thin = len(F) // 2
    assert len(res.repair) == 1 and f"faces {thin})" in res.repair[0]
    (failed,) = [r for r in res.islands if r.status == "failed"]
    assert failed.faces.tolist() == [thin] and type(failed.error) is bd_uv.DegenerateFacesError


@pytest.mark.parametrize("name", ["grid", "nefertiti", "jagged"])
def test_finishs_measure_certifies_as_the_disk_certificates_own(name):
    """``bound="auto"``'s disk certificate takes the distortion ``finish`` measured from the
    same UVs: the same certificate as measured anew, and a distortion over the bound, or UVs
    whose boundary folds, are still refused."""
    V, F = DISKS[name]()
    F = np.asarray(F, np.int64)
    res = bd_uv.unwrap(V, F, bound="auto")
    (r,) = res.islands
    disk = one_disk.find(V, F)
    C = r.bound_certified
    anew = one_disk.certify(disk, res.corner_uv, C)
    assert anew is not None and _same(one_disk.certify(disk, res.corner_uv, C, r.distortion), anew)
    assert _same(anew, res.certificates[0])
    over = r.distortion.copy()
    over[len(over) // 2] = C * 1.01
    assert one_disk.certify(disk, res.corner_uv, C, over) is None
    folded = res.corner_uv.copy()
    folded[..., 0] = -folded[..., 0]        # mirrored: the loop winds clockwise
    assert one_disk.certify(disk, folded, C, r.distortion) is None


def test_auto_on_a_disk_leaves_to_the_general_path_what_it_does_not_search():
    """``disk_auto.minimise_disk`` answers only a flip-free conformal map within the limit on an
    island of up to AUTO_FACES faces; otherwise None (the general path bends, solves or
    searches on the whole map). Where it answers, its C is the map's max distortion as
    ``certify_islands`` measures it from the UVs, and the search lowered it below the conformal
    map's."""
    import time
    import bd_uv.solvers.bound_search as bs
    from bd_uv.unwrapping import disk_auto
    V, F = curved_grid()
    F = np.asarray(F, np.int64)
    disk = one_disk.find(V, F)
    _, u, _ = one_disk.unwrap_disk(V, F, disk, None, time.perf_counter())
    D0 = bd_uv.unwrap(V, F, bound=1000.0).islands[0].max_distortion     # the conformal map's
    assert disk_auto.minimise_disk(V, disk, u, 1.0 + 0.5 * (D0 - 1.0), 0.0) is None
    done = disk_auto.minimise_disk(V, disk, u, 1000.0, 0.0)
    (r,) = done.islands
    assert r.flags == ("projected",) and r.iterations > 0 and r.max_distortion < D0
    (c,) = certify_islands(V, F, done.corner_uv, done.face_island, [r.bound_certified])
    assert c.certified and c.max_distortion == r.max_distortion <= r.bound_certified
    old = disk_auto.AUTO_FACES
    try:
        disk_auto.AUTO_FACES = len(F) - 1
        assert disk_auto.minimise_disk(V, disk, u, 1000.0, 0.0) is None
    finally:
        disk_auto.AUTO_FACES = old
    # over ONE_PRODUCT_FACES faces (the general path's free iterations end there) and within
    # AUTO_FACES: searched here on the free unknowns, the general path's iterations and bound
    old = bs.ONE_PRODUCT_FACES
    try:
        bs.ONE_PRODUCT_FACES = len(F) - 1
        big = disk_auto.minimise_disk(V, disk, u, 1000.0, 0.0).islands[0]
    finally:
        bs.ONE_PRODUCT_FACES = old
    assert big.iterations == r.iterations and big.bound_certified == r.bound_certified
    assert np.abs(big.uv - r.uv).max() < 1e-12


@pytest.mark.parametrize("nx, ny", [(6, 5), (12, 9)])
def test_the_disk_conformal_map_is_lscm_pinned_bit_for_bit(nx, ny):
    """``disk_conformal.conformal`` (no scipy matrix made) gives ``lscm.lscm_pinned``'s map bit
    for bit: in qdldl's own order (no ranks) and in the vertices' ranks, on a small and a larger
    bumpy grid."""
    from bd_uv.solvers.lscm import face_geometry_of, lscm_pinned
    V, F = grid(nx, ny, lambda x, y: 0.3 * np.sin(3 * x) * np.cos(2 * y))   # not flat
    disk = one_disk.find(V, F.astype(np.int64))
    assert disk is not None
    isl = disk.island
    geom = face_geometry_of(disk.Z, disk.G, disk.area)
    idx = disk_conformal._far_pair(V.take(isl.vertices, axis=0), isl.loops[0])
    for ranks in (None, disk.ranks):
        want = lscm_pinned(geom.cbw(), geom.cb, isl.tris, len(isl.vertices), idx,
                           np.array([0.0, 1.0], complex),
                           (disk.twins[0], disk.twins[1], disk.loop), ranks)
        got = disk_conformal.conformal(V, disk, disk.Z, disk.G, ranks)
        assert got.tobytes() == want.tobytes()
        assert got[idx[0]] == 0.0 and got[idx[1]] == 1.0


def test_the_disk_conformal_map_falls_back_where_qdldl_wants_a_matrix(monkeypatch):
    """A qdldl that refuses bare arrays (a release wanting a scipy matrix) or is missing: the
    map is ``lscm_pinned``'s all the same (its own way), bit for bit."""
    from bd_uv.solvers.lscm import face_geometry_of, lscm_pinned
    V, F = grid(7, 6, lambda x, y: 0.3 * np.sin(3 * x) * np.cos(2 * y))
    disk = one_disk.find(V, F.astype(np.int64))
    isl = disk.island
    geom = face_geometry_of(disk.Z, disk.G, disk.area)
    idx = disk_conformal._far_pair(V.take(isl.vertices, axis=0), isl.loops[0])
    want = lscm_pinned(geom.cbw(), geom.cb, isl.tris, len(isl.vertices), idx,
                       np.array([0.0, 1.0], complex), (disk.twins[0], disk.twins[1], disk.loop))

    class Picky:
        @staticmethod
        def Solver(A, upper=False):
            return A.tocsc()                # what a bare CscArrays does not have
    for fake in (Picky, None):
        monkeypatch.setattr(disk_conformal, "qdldl", fake)
        got = disk_conformal.conformal(V, disk, disk.Z, disk.G, None)
        assert got.tobytes() == want.tobytes()


def test_a_disks_kept_values_are_made_once_and_are_the_functions_own():
    """``Disk``'s Z, G and ranks (``one_disk._kept``: a cached property without a lock) are made
    on first read, kept, and equal what their functions make of the disk afresh."""
    from bd_uv.geometry import gradient_operators, local_frame
    V, F = curved_grid(6)
    disk = one_disk.find(V, F.astype(np.int64))
    Z = disk.Z
    assert disk.Z is Z and disk.G is disk.G and disk.ranks is disk.ranks
    want_Z = local_frame(disk.e01, disk.e02)
    assert Z.tobytes() == want_Z.tobytes()
    assert disk.G.tobytes() == gradient_operators(want_Z).tobytes()
    assert isinstance(one_disk.Disk.Z, one_disk._kept) and "Z" in vars(disk)
