"""A disk whose conformal start lies over itself or flips is unwrapped from its angle start
(``unwrapping.angle_start``: Linear ABF's angles, the boundary held below a full turn round each
vertex) as one certified island, not cut (issue 21 item 1).

Checked from the stored UVs alone, independently of the code under test: each face's distortion
and orientation from its Jacobian in its own 3D frame (numpy's SVD,
``unwrap_contract.distortion_and_flips``), as float64 and as float32; the boundary a simple polygon
wound counter-clockwise whose inside is exactly the triangles' union (shapely); the premise (the
conformal start lies over itself) from the boundary's exterior angles.
"""
import json

import numpy as np
import pytest

import bd_uv
from bd_uv.unwrapping import angle_start, one_disk
from helpers import load_off, rings
from unwrap_contract import assert_one_simple_disk, distortion_and_flips

# (seed face, faces at least) of cow.off: disks whose conformal map lies over itself; on main
# (4fd3e0a) auto cut them into 3 and 8 pieces, at C = 5 the first into 2
COW = [(5243, 400), (4848, 400)]


def _turns(z):
    """The turning number of the closed polygon z (n,) complex, from its exterior angles."""
    e = np.roll(z, -1) - z
    return int(round(np.angle(np.roll(e, -1) / e).sum() / (2 * np.pi)))


def _one_certified_island(V, F, res, disk, bound):
    (r,) = res.islands
    assert r.status == "certified" and "angle_start" in r.flags and r.overlap_free
    assert r.bound_certified <= bound
    uv = res.corner_uv
    for stored in (uv, uv.astype(np.float32).astype(np.float64)):
        D, flipped = distortion_and_flips(V, F, stored)
        assert not flipped.any() and D.max() <= r.bound_certified
    D = assert_one_simple_disk(V, F, uv, r, disk.island)
    return r, D


@pytest.mark.parametrize("seed, faces", COW)
def test_a_disk_whose_conformal_start_overlaps_is_one_certified_island_at_auto(seed, faces):
    V, F = rings(*load_off("cow.off"), seed, faces)
    disk = one_disk.find(V, F)
    _, u, _ = one_disk.unwrap_disk(V, F, disk, None, 0.0)
    D0, flipped0 = distortion_and_flips(V, F, np.stack([u.real, u.imag], 1)[disk.island.tris])
    assert flipped0.any() or _turns(u[disk.island.loops[0]]) != 1     # the premise
    res = bd_uv.unwrap(V, F, bound="auto")
    r, D = _one_certified_island(V, F, res, disk, np.inf)
    # below the conformal start's max, where it has one
    assert flipped0.any() or D.max() < D0.max()
    # the same call, the same bits
    assert np.array_equal(bd_uv.unwrap(V, F, bound="auto").corner_uv, res.corner_uv)


# (seed, faces, flag): at C = 5, the angle start certified as it is (within 5; main cut this
# disk into 2 pieces), or over 5 (max 25.9), auto's search from it unfolded within 5 (main: 4)
AT_FIVE = [(5243, 400, "initial"), (2628, 400, "unfolded")]


@pytest.mark.parametrize("seed, faces, way", AT_FIVE)
def test_a_number_c_takes_the_angle_start_where_it_fits_or_unfolds_from_it(seed, faces, way):
    V, F = rings(*load_off("cow.off"), seed, faces)
    disk = one_disk.find(V, F)
    res = bd_uv.unwrap(V, F, bound=5.0)
    r, D = _one_certified_island(V, F, res, disk, 5.0)
    assert r.bound_certified == 5.0 and D.max() < 5.0
    assert ("unfolded" in r.flags) == (way == "unfolded")
    if way == "unfolded":
        v = angle_start.angle_start(V, disk)
        Dv, _ = distortion_and_flips(V, F, np.stack([v.real, v.imag], 1)[disk.island.tris])
        assert Dv.max() > 5.0


def test_the_angle_start_is_flip_free_turns_once_and_nearer_conformal_than_lscm():
    """On the first disk: its map from Linear ABF's angles has every face positive, a boundary
    turning once, and a lower max distortion than the conformal map's (which flips or wraps)."""
    V, F = rings(*load_off("cow.off"), *COW[1])
    disk = one_disk.find(V, F)
    v = angle_start.angle_start(V, disk)
    corner = np.stack([v.real, v.imag], 1)[disk.island.tris]
    D, flipped = distortion_and_flips(V, F, corner)
    assert not flipped.any() and _turns(v[disk.island.loops[0]]) == 1
    _, u, _ = one_disk.unwrap_disk(V, F, disk, None, 0.0)
    D0, _ = distortion_and_flips(V, F, np.stack([u.real, u.imag], 1)[disk.island.tris])
    assert D.max() < D0.max()


def _cow_disk_capped():
    """cow's rings as a disk, its island, vertex count, boundary loop and the caps holding the
    loop's first three vertices at 0.9 pi (the rest free)."""
    V, F = rings(*load_off("cow.off"), *COW[1])
    disk = one_disk.find(V, F)
    isl = disk.island
    nv = len(isl.vertices)
    loop = isl.loops[0]
    caps = np.full(nv, np.nan)
    caps[loop[:3]] = 0.9 * np.pi
    return disk, isl, nv, loop, caps


def test_linear_abf_angles_close_the_triangles_and_the_interior_vertices():
    """Linear ABF's angles: each triangle's add up to pi, each interior vertex's to 2 pi (the
    constraints are linear in the angles: met to rounding), every held boundary vertex's to
    its cap."""
    disk, isl, nv, loop, caps = _cow_disk_capped()
    A = angle_start.linear_abf(disk, caps)
    assert (A > 0).all() and np.allclose(A.sum(axis=1), np.pi, atol=1e-12)
    sums = np.bincount(isl.tris.ravel(), A.ravel(), nv)
    inner = np.ones(nv, dtype=bool)
    inner[loop] = False
    assert np.allclose(sums[inner], 2 * np.pi, atol=1e-9)
    assert np.allclose(sums[loop[:3]], 0.9 * np.pi, atol=1e-9)


def test_linear_abf_in_the_disks_vertex_order_solves_the_same_angles(monkeypatch):
    """The angle system factorised in the disk's vertex order (``Disk.ranks``: a vertex's angle
    sum, then its wheel; ``ordered_ldl.Factor`` from its triplets, the repeated places summed)
    and in qdldl's AMD order of a scipy matrix (the disk without an order) solve the same
    angles, to rounding; both close the constraints."""
    disk, isl, nv, loop, caps = _cow_disk_capped()
    assert disk.ranks is not None
    made = []
    real_factor = angle_start.ordered_ldl.Factor
    monkeypatch.setattr(angle_start.ordered_ldl, "Factor",
                        lambda *a, **k: made.append(1) or real_factor(*a, **k))
    ordered = angle_start.linear_abf(disk, caps)
    assert made == [1]
    disk.__dict__["ranks"] = None               # (``Disk.ranks`` is kept in its __dict__)
    amd = angle_start.linear_abf(disk, caps)
    assert made == [1]
    assert np.abs(ordered - amd).max() < 1e-12
    inner = np.ones(nv, dtype=bool)
    inner[loop] = False
    for A in (ordered, amd):
        sums = np.bincount(isl.tris.ravel(), A.ravel(), nv)
        assert np.allclose(sums[inner], 2 * np.pi, atol=1e-9)




def test_faces_rebuilt_again_and_the_systems_places_kept_give_the_maps_made_anew_to_the_bit():
    """Between the angle start's solves only the faces where a corner's scale changed are
    rebuilt (``_rebuilt`` given the last ones) and, in qdldl's own order, the conformal
    system's values are patched at the places they touch (``lscm_patch``) and put in the places
    the disk's first system's were converted to (``disk_conformal._canonical``, kept in
    ``Disk.factors``, its factorisation refilled): through three solves of growing scales the
    faces and the maps are those made anew (every face rebuilt, a new disk: its system
    assembled and converted, a new factorisation), bit for bit."""
    from bd_uv.unwrapping.disk_conformal import conformal
    V, F = rings(*load_off("cow.off"), *COW[1])
    disk = one_disk.find(V, F)
    isl = disk.island
    tris, loop, nv = isl.tris, isl.loops[0], len(isl.vertices)
    angles = angle_start.linear_abf(disk, np.full(nv, np.nan))
    scale = np.ones(nv)
    last, steps = None, [(), (loop[5:6], 0.9), (loop[[5, 20, 21, 22]], 0.95)]
    for i, step in enumerate(steps):
        if step:
            scale[step[0]] *= step[1]
        before = None if last is None else last[0].copy()
        last = angle_start._rebuilt(angles, scale, tris, disk.area, last)
        s, Z, G, geom, rebuilt = last
        full = angle_start._rebuilt(angles, scale, tris, disk.area)
        assert np.array_equal(s, full[0]) and np.array_equal(Z, full[1])
        assert np.array_equal(G, full[2]) and np.array_equal(geom.cb, full[3].cb)
        assert np.array_equal(geom.zarea, full[3].zarea)
        if before is not None:      # a few faces rebuilt, not all
            assert 0 < (s != before).any(axis=1).sum() < len(tris) // 20
        u = conformal(V, disk, Z, G, None, geom, rebuilt)
        anew = conformal(V, one_disk.find(V, F), full[1], full[2], None)
        assert np.isfinite(u).all() and np.array_equal(u, anew)
        assert (disk.factors["csc"][3] is not None) == (i > 0)     # the places taken, kept
    assert not np.array_equal(u, conformal(V, disk, disk.Z, disk.G, None))   # other shapes


def test_a_patched_lscm_system_is_the_one_assembled_anew_to_the_bit():
    """``lscm_patch.PatchedLSCM``: after faces are rebuilt (interior and boundary ones, then
    one with a pinned corner, then none) its triplets and right-hand side are
    ``_lscm_system``'s of the new faces, bit for bit, in the same order."""
    from bd_uv.solvers.lscm import _lscm_system, face_geometry_of
    from bd_uv.solvers.lscm_patch import PatchedLSCM
    from bd_uv.unwrapping.disk_conformal import _far_pair
    V, F = rings(*load_off("cow.off"), *COW[1])
    disk = one_disk.find(V, F)
    isl = disk.island
    tris, loop, nv = isl.tris, isl.loops[0], len(isl.vertices)
    idx = _far_pair(V.take(isl.vertices, axis=0), loop)
    val, sides = np.array([0.0, 1.0], complex), (disk.twins[0], disk.twins[1], disk.loop)
    Z, G = disk.Z.copy(), disk.G.copy()
    geom = face_geometry_of(Z, G, disk.area)
    kept = PatchedLSCM(geom, tris, nv, idx, val, sides)
    rng = np.random.default_rng(3)
    edge = np.isin(tris, loop).any(axis=1).nonzero()[0]
    pin = np.isin(tris, idx).any(axis=1).nonzero()[0]
    for faces in (np.concatenate([edge[:4], [7, 300]]), edge[10:30], pin[:1], edge[:0]):
        A3 = np.abs(angle_start.corner_angles(Z[faces])) * rng.uniform(0.8, 1.2, (len(faces), 3))
        Z[faces] = angle_start.from_angles(A3 * (np.pi / A3.sum(axis=1))[:, None],
                                           disk.area[faces])
        G[faces] = angle_start.gradient_operators(Z[faces])
        fresh = face_geometry_of(Z, G, disk.area)
        geom.cb[faces], geom.zarea[faces] = fresh.cb[faces], fresh.zarea[faces]
        A, rhs, u, free = kept.rebuilt(geom, faces.astype(np.int64))
        B, rhs_b, u_b, free_b = _lscm_system(fresh.cbw(), fresh.cb, tris, nv, idx, val, sides,
                                             triplets=True)
        assert np.array_equal(A.rows, B.rows) and np.array_equal(A.cols, B.cols)
        assert np.array_equal(A.vals, B.vals) and np.array_equal(rhs, rhs_b)
        assert np.array_equal(u, u_b) and np.array_equal(free, free_b)


# (seed, faces) of cow.off: the conformal start lies over itself and the angle start's max is
# over ``bound_limit`` (1,000; about 3,700 here): gated by that limit, auto cut this disk into 24
# pieces at C 2.045 (main 19a8c44); searched from, it is one island
OVER_LIMIT = (159, 1200)


def test_an_angle_start_over_bound_limit_is_searched_from_not_cut():
    V, F = rings(*load_off("cow.off"), *OVER_LIMIT)
    disk = one_disk.find(V, F)
    v = angle_start.angle_start(V, disk)
    Dv, flipped = distortion_and_flips(V, F, np.stack([v.real, v.imag], 1)[disk.island.tris])
    limit = bd_uv.UnwrapOptions().bound_limit
    assert not flipped.any() and Dv.max() > limit          # the premise
    assert _turns(v[disk.island.loops[0]]) == 1
    res = bd_uv.unwrap(V, F, bound="auto")
    r, D = _one_certified_island(V, F, res, disk, limit)
    assert D.max() < 2.05


# (seed, faces) of cow.off whose least C from the angle start (one island, 2.489) holds in
# float64 but not once packed and stored as float32 (a horn's tip shrunk below float32's step)
HORN_TIP = (3177, 400)


def test_an_angle_start_map_that_float32_would_break_gives_way_to_the_conformal_start(
        monkeypatch):
    from bd_uv.layout import stored_layout
    import importlib
    unwrap_module = importlib.import_module("bd_uv.unwrapping.unwrap")   # the module
    V, F = rings(*load_off("cow.off"), *HORN_TIP)
    res = bd_uv.unwrap(V, F, bound="auto")
    assert not any("angle_start" in r.flags for r in res.islands)
    assert all(r.status == "certified" for r in res.islands)
    # the premise: the one island its angle start gives fails as packed and stored
    with monkeypatch.context() as m:
        m.setattr(unwrap_module, "predicted_to_fail", lambda V, F, res, disk=None: [])
        one = bd_uv.unwrap(V, F, bound="auto")
    (r,) = one.islands
    assert "angle_start" in r.flags and r.status == "certified"
    assert not all(c.certified for c in stored_layout(V, F, one, dtype=np.float32).certificates)
    # and recomputed: scaled into the unit square (as a packer does) and rounded to float32
    u = one.corner_uv - one.corner_uv.min(axis=(0, 1))
    u = (u / u.max()).astype(np.float32).astype(np.float64)
    D, flipped = distortion_and_flips(V, F, u)
    assert flipped.any() or D.max() > r.bound_certified
    # what it gives instead: the conformal start's way, bit for bit
    with monkeypatch.context() as m:
        m.setattr(angle_start, "better_start", lambda *a, **k: (None, None, False))
        plain = bd_uv.unwrap(V, F, bound="auto")
    assert np.array_equal(plain.corner_uv, res.corner_uv, equal_nan=True)


@pytest.mark.parametrize("seed, faces", COW + [AT_FIVE[1][:2]])
def test_with_the_command_lines_time_budget_the_disk_stays_one_certified_island(seed, faces):
    """``--bound auto`` on the command line has a time budget (``arguments.TIME_BUDGET``), so
    Dinkelbach steps refine the searched map: from the angle start, and never into a map that
    lies over itself (b620c89 cut these disks into 3, 8 and 12 pieces: the steps' maps overlapped
    and the overlap repair cut them). The conic step's C may be lower, never higher than the
    search's alone by more than one unit of C's rounding (C - 1 to 4 significant digits): the
    call without a budget lowers its mean within its max last (``energy_within``'s
    ``weighted_lowered``), which can move that max by less (cow 5243/400: 1.442825 against the
    budget's 1.442877, C 1.4429 against 1.443)."""
    from bd_uv.arguments import TIME_BUDGET
    V, F = rings(*load_off("cow.off"), seed, faces)
    disk = one_disk.find(V, F)
    res = bd_uv.unwrap(V, F, bound="auto", time_budget=TIME_BUDGET)
    r, D = _one_certified_island(V, F, res, disk, np.inf)
    (plain,) = bd_uv.unwrap(V, F, bound="auto").islands
    unit = 10.0 ** (np.floor(np.log10(plain.bound_certified - 1.0)) - 3)
    assert r.bound_certified <= plain.bound_certified + unit * (1 + 1e-9)
    assert D.max() <= r.bound_certified


def test_with_the_time_budget_a_disk_the_steps_cut_takes_the_call_without_one(tmp_path):
    """Cow 1522/400: under the command line's time budget its angle start's map is predicted to
    fail in float32 and the conformal start's conic steps lie over themselves, so the overlap
    repair cut the disk into 25 pieces (39a0aec); the call without a budget keeps it one island
    and is taken: the same map, and the command line (whose ``--bound auto`` has the budget;
    ``--seams none``: the island as it is, where the default seams give its horn tip, whose
    texel density varies too much to texture, seams of its own) writes it as one island,
    checked here from the OBJ's UVs as written."""
    from bd_uv.arguments import TIME_BUDGET
    from test_repair import run_command_line, written_corner_uv
    V, F = rings(*load_off("cow.off"), 1522, 400)
    disk = one_disk.find(V, F)
    res = bd_uv.unwrap(V, F, bound="auto", time_budget=TIME_BUDGET)
    plain = bd_uv.unwrap(V, F, bound="auto")
    (r,) = res.islands
    assert r.status == "certified" and r.overlap_free
    assert np.array_equal(res.corner_uv, plain.corner_uv)
    D, flipped = distortion_and_flips(V, F, res.corner_uv)
    assert not flipped.any() and D.max() <= r.bound_certified
    assert_one_simple_disk(V, F, res.corner_uv, r, disk.island)
    run, out, rep = run_command_line(tmp_path, V, F, "--bound", "auto", "--seams", "none")
    assert run.returncode == 0, run.stderr
    (island,) = json.loads(rep.read_text())["islands"]
    assert island["status"] == "certified"
    D, flipped = distortion_and_flips(V, F, written_corner_uv(out))
    assert not flipped.any() and D.max() <= island["bound_certified"]

@pytest.mark.parametrize("budget", [False, True])
def test_a_disk_auto_cut_is_kept_whole_at_a_number_a_little_above(budget):
    """Cow 2338/400 (a horn): its least-C map from the angle start (3.70) was predicted to fail
    once stored in float32 and the conformal start's way cut the disk into 6 pieces (39a0aec,
    with and without the command line's time budget). ``bound="auto"`` now keeps it one island
    at a number a little above the least C (``unwrap.ABOVE``): certified, reported as asked for
    "auto", flagged, checked here from its UVs in float64 and scaled into the unit square and
    rounded to float32 (as a packer stores them), one simple disk."""
    from bd_uv.arguments import TIME_BUDGET
    V, F = rings(*load_off("cow.off"), 2338, 400)
    disk = one_disk.find(V, F)
    res = bd_uv.unwrap(V, F, bound="auto", time_budget=TIME_BUDGET if budget else None)
    (r,) = res.islands
    assert r.status == "certified" and "kept_whole" in r.flags and r.bound_requested == "auto"
    assert r.bound_certified < 1.25 * 3.75          # a little above the least C, not the limit
    u = res.corner_uv - res.corner_uv.min(axis=(0, 1))
    for stored in (res.corner_uv, (u / u.max()).astype(np.float32).astype(np.float64)):
        D, flipped = distortion_and_flips(V, F, stored)
        assert not flipped.any() and D.max() <= r.bound_certified
    assert_one_simple_disk(V, F, res.corner_uv, r, disk.island)

@pytest.mark.parametrize("seed, faces, fewer, lower",
                         [(2222, 800, 20, False), (5243, 400, 0, True)])
def test_the_angle_starts_search_ends_at_a_tested_map_that_lies_over_itself(
        monkeypatch, seed, faces, fewer, lower):
    """``strategies.OVERLAP_ENDS``: every ``target_watch.CHECK_EVERY``-th new best of a target is
    tested; the search ends at one that lies over itself, one that does not is kept. cow.off's
    2222/800 (807 faces): the same map in 40 iterations instead of 60; 5243/400 (406 faces):
    a tested map lays the disk out below the one kept without the test (C 1.4432, 1.5032). One
    certified island both ways, checked from the UVs."""
    from bd_uv.unwrapping import strategies
    V, F = rings(*load_off("cow.off"), seed, faces)
    disk = one_disk.find(V, F)
    res = bd_uv.unwrap(V, F, bound="auto")
    monkeypatch.setattr(strategies, "OVERLAP_ENDS", False)
    ref = bd_uv.unwrap(V, F, bound="auto")
    r, _ = _one_certified_island(V, F, res, disk, res.islands[0].bound_certified)
    q, _ = _one_certified_island(V, F, ref, disk, ref.islands[0].bound_certified)
    assert q.iterations - r.iterations == fewer
    if lower:
        assert r.max_distortion < q.max_distortion - 0.05
    else:
        assert np.array_equal(res.corner_uv, ref.corner_uv)



@pytest.mark.parametrize("seed,flags", [(HORN_TIP, [0]), (COW[0], [])])
def test_float32_prediction_from_the_disks_geometry_is_the_meshs(seed, flags, monkeypatch):
    """``rounding.predicted_to_fail`` given the mesh's ``Disk`` (its frames, areas and edges
    read, not made again) flags what it flags without it, and its per-face bound is the same
    bits: on the horn tip's map from its angle start (flagged: float32 breaks it, recomputed by
    SVD as in the test above) and on a cow disk's (not flagged)."""
    import importlib
    from bd_uv.mesh import check_arrays
    from bd_uv.unwrapping import rounding
    unwrap_module = importlib.import_module("bd_uv.unwrapping.unwrap")   # the module
    V, F = check_arrays(*rings(*load_off("cow.off"), *seed))
    disk = one_disk.find(V, F)
    with monkeypatch.context() as m:    # the angle start's map kept, whatever it predicts
        m.setattr(unwrap_module, "predicted_to_fail", lambda V, F, res, disk=None: [])
        one = bd_uv.unwrap(V, F, bound="auto")
    (r,) = one.islands
    assert "angle_start" in r.flags and r.status == "certified"
    assert rounding.predicted_to_fail(V, F, one) == flags
    assert rounding.predicted_to_fail(V, F, one, disk=disk) == flags
    h = rounding.float_step(np.float32, 1.0)
    bound = rounding.rounding_distortion(V, F, one.corner_uv, h)
    assert np.array_equal(bound, rounding.rounding_distortion(
        V, F, one.corner_uv, h, disk.G, (disk.e01, disk.e02)))
    if flags:           # the premise, from the stored UVs: scaled into the unit square, rounded
        u = one.corner_uv - one.corner_uv.min(axis=(0, 1))
        u = (u / u.max()).astype(np.float32).astype(np.float64)
        D, flipped = distortion_and_flips(V, F, u)
        assert flipped.any() or D.max() > r.bound_certified


def test_the_conformal_factor_kept_for_auto_is_refilled_by_the_angle_starts_first_solve(
        monkeypatch):
    """With ``bound="auto"`` the disk's conformal map keeps its factorisation in its vertices'
    order (``one_disk.unwrap_disk``: ``Disk.factors``), and the angle start's first solve, of
    the same places with other shapes, refills it rather than factorising anew: the map is the
    one a disk with nothing kept solves, bit for bit, and a numeric C keeps nothing."""
    from bd_uv.solvers import ordered_ldl
    from bd_uv.unwrapping.disk_conformal import conformal
    V, F = rings(*load_off("cow.off"), *COW[1])
    disk = one_disk.find(V, F, ordered_ldl.AUTO_RANKED_VERTICES)
    one_disk.unwrap_disk(V, F, disk, None, 0.0)
    kept = disk.factors["ranked"][0]
    nv = len(disk.island.vertices)
    angles = angle_start.linear_abf(disk, np.full(nv, np.nan))
    shapes = angle_start._rebuilt(angles, np.ones(nv), disk.island.tris, disk.area)
    made, refilled = [], []
    init, refill = ordered_ldl.Factor.__init__, ordered_ldl.Factor.refill
    with monkeypatch.context() as m:
        m.setattr(ordered_ldl.Factor, "__init__", lambda f, *a, **k: made.append(
            init(f, *a, **k)))
        m.setattr(ordered_ldl.Factor, "refill", lambda f, vals: refilled.append(f) or refill(
            f, vals))
        u = conformal(V, disk, shapes[1], shapes[2], disk.ranks, shapes[3], shapes[4])
    assert made == [] and refilled == [kept]
    fresh = one_disk.find(V, F, ordered_ldl.AUTO_RANKED_VERTICES)
    anew = conformal(V, fresh, shapes[1], shapes[2], fresh.ranks, shapes[3], shapes[4])
    assert np.isfinite(u).all() and np.array_equal(u, anew)
    numeric = one_disk.find(V, F, ordered_ldl.AUTO_RANKED_VERTICES)
    one_disk.unwrap_disk(V, F, numeric, 5.0, 0.0)
    assert "ranked" not in numeric.factors


@pytest.mark.parametrize("seed, faces", COW + [AT_FIVE[1][:2]])
def test_auto_from_the_angle_start_on_the_disks_geometry_is_the_general_paths_map(
        seed, faces, monkeypatch):
    """``bound="auto"`` from a disk's angle start searches on the ``Disk``'s own geometry
    (``disk_angle``), not an island problem of it: the same iterations, flags and certified C as
    the general path (``disk_angle`` refused), the UVs equal to rounding (the general path's
    copy is normalised to unit area), the means to 1e-12; the map certified from its stored
    UVs here (numpy's SVD, float64 and float32; one simple boundary)."""
    import importlib
    from bd_uv.unwrapping import disk_angle
    V, F = rings(*load_off("cow.off"), seed, faces)
    calls = []
    real = disk_angle.minimise_from_angles
    unwrap_module = importlib.import_module("bd_uv.unwrapping.unwrap")
    with monkeypatch.context() as m:
        m.setattr(unwrap_module.disk_angle, "minimise_from_angles",
                  lambda *a, **k: calls.append(1) or real(*a, **k))
        res = bd_uv.unwrap(V, F, bound="auto")
    with monkeypatch.context() as m:
        m.setattr(unwrap_module.disk_angle, "minimise_from_angles", lambda *a, **k: None)
        ref = bd_uv.unwrap(V, F, bound="auto")
    (r,), (g,) = res.islands, ref.islands
    assert calls == [1]
    assert "angle_start" in r.flags and r.flags == g.flags and r.iterations == g.iterations
    assert r.bound_certified == g.bound_certified
    assert abs(r.mean_distortion - g.mean_distortion) <= 1e-12
    extent = np.ptp(ref.corner_uv.reshape(-1, 2), axis=0).max()
    assert np.abs(res.corner_uv - ref.corner_uv).max() <= 1e-9 * extent
    _one_certified_island(V, F, res, one_disk.find(V, F), r.bound_certified)


def test_a_mean_left_over_the_angle_starts_is_lowered_within_the_max(monkeypatch):
    """``energy_within.weighted_lowered``: on cow.off's 406-face disk (COW[0]) auto's map from
    the angle start has a mean 1.1338 (measured, ``LOWER`` off), over the angle start's by more
    than LOWER_RISE (3 %): lowered within its max by the ADMM on the |alpha|^-2 weighted energy,
    mean 1.1226 at the same C. Both checked from the stored UVs (numpy SVD, the area-weighted mean
    of the faces' distortion, the boundary a simple polygon)."""
    from bd_uv.unwrapping import energy_within
    V, F = rings(*load_off("cow.off"), *COW[0])
    disk = one_disk.find(V, F)
    P = V[F]
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    got = {}
    for on in (False, True):
        monkeypatch.setattr(energy_within, "LOWER", on)
        res = bd_uv.unwrap(V, F, bound="auto")
        r, D = _one_certified_island(V, F, res, disk, np.inf)
        got[on] = (float(area @ D / area.sum()), r.bound_certified, "mean_lowered" in r.flags)
    (m0, c0, low0), (m1, c1, low1) = got[False], got[True]
    assert not low0 and low1
    assert m1 < 1.125 < 1.13 < m0 and c1 <= c0
