"""certify_islands and layout_overlaps on hand-checkable layouts, re-checked by an independent
triangle-overlap test (tests/core/overlap_shapes.py)."""
import json

import numpy as np
import pytest

from bd_uv.certificate import certificate_totals, certify_islands
from bd_uv.overlap import island_overlaps, layout_overlaps
from bd_uv.uv_boundary import uv_boundary
from overlap_shapes import figure8_uv, overlapping_triangle_pairs, spiral_uv


def square():
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    F = np.array([[0, 1, 2], [0, 2, 3]])
    return V, F, V[F][:, :, :2].copy()


def annulus(n=16, r0=1.0, r1=2.0):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    ring = np.stack([np.cos(t), np.sin(t)], 1)
    P = np.concatenate([r0 * ring, r1 * ring])
    i = np.arange(n)
    j = (i + 1) % n
    F = np.concatenate([np.stack([i, n + i, n + j], 1), np.stack([i, n + j, j], 1)])
    return np.concatenate([P, np.zeros((2 * n, 1))], 1), F, P[F]


def one(V, F, uv, bound, labels=None):
    labels = np.zeros(len(F), int) if labels is None else labels
    certs = certify_islands(V, F, uv, labels, np.atleast_1d(bound))
    return certs[0] if len(certs) == 1 else certs


def test_square_is_certified_and_its_summary_is_json():
    c = one(*square(), 1.0)
    assert c.certified and c.overlap_free and c.crossings == 0 and c.flipped == 0
    assert c.reason == "" and c.faces == 2
    assert c.max_distortion == pytest.approx(1.0) and c.mean_distortion == pytest.approx(1.0)
    s = json.loads(json.dumps(c.summary(), allow_nan=False))
    assert s["overlap_free"] is True and s["crossings"] == 0


def test_annulus_hole_inside_is_overlap_free_and_boundary_has_two_loops():
    V, F, uv = annulus()
    c = one(V, F, uv, 2.0)
    assert c.certified and c.overlap_free
    bd = uv_boundary(F, uv, np.zeros(len(F), int))
    assert len(bd.p) == 32                      # 16 outer + 16 inner edges, nothing interior
    # outer counter-clockwise, hole clockwise: the shoelace sums are +area(outer), -area(hole)
    area2 = np.cross(bd.p, bd.q)
    outer = np.linalg.norm(bd.p, axis=1) > 1.5
    assert area2[outer].sum() > 0 > area2[~outer].sum()


def test_seam_with_equal_uvs_is_interior_and_slit_is_boundary():
    V, F, uv = square()
    assert len(uv_boundary(F, uv, [0, 0]).p) == 4
    # Give the diagonal two different UVs on its two faces (a slit): 6 boundary edges.
    uv2 = uv.copy()
    uv2[1] += [0.0, 0.5]
    bd = uv_boundary(F, uv2, [0, 0])
    assert len(bd.p) == 6


def test_figure8_strip_is_not_overlap_free_and_the_independent_test_agrees():
    V, F, uv = figure8_uv()
    c = one(V, F, uv, 50.0)
    assert c.flipped == 0 and c.max_distortion < 50
    assert not c.overlap_free and c.crossings > 0 and not c.certified
    assert "crosses itself" in c.reason
    assert len(overlapping_triangle_pairs(uv)) > 0


@pytest.mark.parametrize("turns, overlaps", [(0.8, False), (2.5, True)])
def test_spiral_overlap_matches_independent_test(turns, overlaps):
    V, F, uv = spiral_uv(turns)
    c = one(V, F, uv, 100.0)
    assert c.flipped == 0
    assert c.overlap_free == (not overlaps)
    assert (len(overlapping_triangle_pairs(uv)) > 0) == overlaps


def test_float32_storage_is_measured_as_stored():
    V, F, uv = annulus()
    c64 = one(V, F, uv, 2.0)
    c32 = one(V, F, uv.astype(np.float32), 2.0)
    assert c32.certified and c32.overlap_free
    D32 = c32.max_distortion
    assert D32 != c64.max_distortion and D32 == pytest.approx(c64.max_distortion, rel=1e-5)
    # a bound at the exact float64 maximum does not survive float32 storage when it rises
    tight = one(V, F, uv.astype(np.float32), c64.max_distortion * (1 - 1e-3))
    assert not tight.certified and "max distortion" in tight.reason and tight.overlap_free


def test_flipped_face_fails_with_reason():
    V, F, uv = square()
    uv[1] = uv[1][::-1]
    c = one(V, F, uv, 10.0)
    assert not c.certified and c.flipped == 1 and "flipped" in c.reason


def test_island_nested_inside_itself_without_crossing_is_caught():
    # Two squares with one label: the small one lies inside the big one, no boundary crossing.
    V, F, uv = square()
    F2 = np.concatenate([F, F + 4])
    uv2 = np.concatenate([uv * 3, uv + 1.0])
    ov = island_overlaps(F2, uv2, np.zeros(4, int))
    assert ov.crossings[0] == 0 and ov.bad_loops[0] == 1 and not ov.overlap_free[0]
    assert len(overlapping_triangle_pairs(uv2)) > 0
    # apart, the two squares are one overlap-free island
    uv3 = np.concatenate([uv, uv + 2.0])
    assert island_overlaps(F2, uv3, np.zeros(4, int)).overlap_free[0]


def test_layout_overlaps_between_islands():
    V, F, uv = annulus()
    lab = np.r_[np.zeros(len(F), int), np.ones(len(F), int)]
    both = lambda b: np.concatenate([uv, b])
    assert layout_overlaps(both(uv + 0.5), lab).tolist() == [[0, 1]]     # boundaries cross
    assert layout_overlaps(both(uv + 5.0), lab).tolist() == []           # apart
    assert layout_overlaps(both(uv * 0.3), lab).tolist() == []           # inside the hole
    assert layout_overlaps(both(uv * 3.0), lab).tolist() == []           # around it, in its hole
    inside = uv * 0.1 + [1.5, 0.0]                                         # inside the ring
    assert layout_overlaps(both(inside), lab).tolist() == [[0, 1]]
    assert len(overlapping_triangle_pairs(both(inside))) > 0


def test_totals_use_area_weighted_mean():
    V, F, uv = square()
    V2 = np.concatenate([V, V * [2, 1, 1]])
    F2 = np.concatenate([F, F + 4])
    uv2 = np.concatenate([uv, uv + 3])           # second island: stretched 2x in 3D -> D = 2
    certs = certify_islands(V2, F2, uv2, [0, 0, 1, 1], [5.0, 5.0])
    t = certificate_totals(certs)
    assert t["certified"] == 2 and t["overlapping"] == 0
    assert t["mean_distortion"] == pytest.approx((1 * 1.0 + 2 * 2.0) / 3)
    assert t["max_distortion"] == pytest.approx(2.0)


def test_unlabelled_and_nonfinite_faces():
    V, F, uv = square()
    uv[0, 0] = np.nan
    c = one(V, F, uv, 5.0)
    assert not c.certified and c.flipped == 1
    certs = certify_islands(V, F, square()[2], [-1, 0], [5.0])
    assert certs[0].certified and certs[0].faces == 1



def test_an_island_without_uvs_beside_a_crossing_one_is_no_crash():
    """Issue 22's fuzz crash: a failed island (its faces' UVs NaN, as after a NaN vertex) next to
    an island whose boundary crosses itself left no clean island with boundary segments, and the
    winding check ran on nothing (ValueError from ``overlap._winding_ok``)."""
    V8, F8, uv8 = figure8_uv()
    Vs, Fs, uvs = square()
    V = np.concatenate([Vs, V8])
    F = np.concatenate([Fs, F8 + len(Vs)])
    uv = np.concatenate([np.full_like(uvs, np.nan), uv8])
    lab = np.concatenate([np.zeros(len(Fs), int), np.ones(len(F8), int)])
    failed, crossing = certify_islands(V, F, uv, lab, [5.0, 50.0])
    assert not failed.certified and failed.flipped == 2
    assert not crossing.certified and crossing.crossings > 0 and not crossing.overlap_free
    ov = island_overlaps(F, uv, np.where(lab == 0, -1, lab), 2)   # island 0 has no faces at all
    assert ov.crossings[1] > 0 and not ov.overlap_free[1] and ov.bad_loops.tolist() == [0, 0]

# ---- the shapes through bd_uv.unwrap, then certify / cut ---------------------------------

from overlap_shapes import folded_strip, helicoid_ribbon, spiral_strip  # noqa: E402

import bd_uv  # noqa: E402
from bd_uv.cut import split_overlapping  # noqa: E402
from bd_uv.layout import stored_layout  # noqa: E402


@pytest.mark.parametrize("shape", [helicoid_ribbon, spiral_strip, folded_strip])
def test_unwrapped_shapes_are_never_certified_with_an_overlap(shape):
    """unwrap() certifies overlap from the final UVs: an island that overlaps itself comes back
    cut into overlap-free pieces (UVs unchanged), each piece naming the mesh edges cut."""
    V, F = shape()
    res = bd_uv.unwrap(V, F, bound=5.0)
    assert all(r.status == "certified" for r in res.islands)
    C = res.islands[0].bound_certified
    certs = certify_islands(V, F, res.corner_uv, res.face_island, [C] * len(res.islands))
    for r, c in zip(res.islands, certs):
        assert c.certified and c.overlap_free and r.overlap_free
        assert len(overlapping_triangle_pairs(res.corner_uv[r.faces])) == 0   # independent test
    assert np.array_equal(np.sort(np.concatenate([r.faces for r in res.islands])),
                          np.arange(len(F)))
    if len(res.islands) == 1:
        assert "cut" not in res.islands[0].flags
        return
    cut = res.islands[0].cut_edges
    assert all("cut" in r.flags and np.array_equal(r.cut_edges, cut) for r in res.islands)
    assert len(cut) > 0 and "cut into" in res.islands[0].message
    # the cut edges are mesh edges joining two different pieces
    E = {tuple(sorted(e)) for f in F for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}
    assert all(tuple(sorted(e)) in E for e in cut.tolist())
    faces_at = [set(np.flatnonzero((F == a).any(1) & (F == b).any(1))) for a, b in cut.tolist()]
    assert all(len({res.face_island[f] for f in fs}) == 2 for fs in faces_at)


def overlapping_result():
    """A one-island UnwrapResult whose certified-looking map overlaps itself: a strip laid along
    1.6 turns of a spiral (flip-free, boundary crossing itself)."""
    V, F, uv = spiral_uv(1.6)
    vuv = np.zeros((len(V), 2))
    vuv[F.ravel()] = uv.reshape(-1, 2)
    D = bd_uv.conformal_distortion(V, F, uv)
    C = float(D.max()) * 1.01
    isl = bd_uv.IslandResult(0, np.arange(len(F)), np.arange(len(V)), F, uv=vuv,
                             status="certified", bound_requested=C, bound_certified=C,
                             max_distortion=float(D.max()), distortion=D)
    return V, F, bd_uv.UnwrapResult(uv, np.zeros(len(F), dtype=np.int64), [isl], 0.0, "lscm"), C


def test_split_overlapping_cuts_an_overlapping_map_into_certified_pieces():
    V, F, res, C = overlapping_result()
    uv = res.corner_uv
    assert not certify_islands(V, F, uv, np.zeros(len(F), dtype=np.int64), [C])[0].overlap_free
    pieces, cut = split_overlapping(V, F, uv, np.arange(len(F)))
    assert len(pieces) >= 2 and len(cut) > 0
    lab = np.full(len(F), -1)
    for i, p in enumerate(pieces):
        lab[p] = i
    for c, p in zip(certify_islands(V, F, uv, lab, [C] * len(pieces)), pieces):
        assert c.certified and c.overlap_free
        assert len(overlapping_triangle_pairs(uv[p])) == 0


def test_split_overlapping_keeps_a_peripheral_polygon_whole():
    """The cut starts from a peripheral polygon: when the polygon alone is overlap-free but no
    ball around it is, the first piece is the whole polygon, not one of its triangles (one UV
    per face-vertex, as USD and Blender store them, cannot hold a polygon split between pieces:
    OpenChessSet's rooks, stored with max distortion 1,700). A fan around one vertex, open, its
    angles 80, 80, 80, 170, 100 and 100 degrees (610 in all, so it overlaps itself), the last two
    triangles one quad."""
    angles = np.radians([80, 80, 80, 170, 100, 100])
    theta = np.concatenate([[0.0], np.cumsum(angles)])
    ring = np.stack([np.cos(theta), np.sin(theta)], 1)
    V = np.zeros((len(ring) + 1, 3))
    V[1:, 0] = theta   # an unrolled cone: the surface only names the triangles here
    V[1:, 1] = 1.0
    F = np.array([[0, i + 1, i + 2] for i in range(len(angles))])
    uv = np.concatenate([np.zeros((len(F), 1, 2)), ring[F[:, 1:] - 1]], axis=1)
    assert (np.cross(uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]) > 0).all()   # none flipped
    groups = np.array([0, 1, 2, 3, 4, 4])
    pieces, cut = split_overlapping(V, F, uv, np.arange(len(F)), groups)
    piece_of = np.full(len(F), -1)
    for i, p in enumerate(pieces):
        piece_of[p] = i
    assert piece_of[4] == piece_of[5]          # the quad stays whole
    assert len(pieces) >= 2
    for p in pieces:                           # every piece overlap-free, checked on its own
        assert len(overlapping_triangle_pairs(uv[p])) == 0
    # cut edges join different pieces and never run inside the quad (its diagonal: 0-6)
    assert not any(sorted(e) == [0, 6] for e in cut.tolist())


def test_stored_layout_cuts_packs_and_recertifies():
    """The write paths' safety net: a result holding an overlapping island is cut, packed and
    re-certified as stored (unwrap() itself never returns one)."""
    V, F, res, C = overlapping_result()
    lay = stored_layout(V, F, res, pack=True, cut=True, dtype=np.float32)
    t = lay.totals()
    assert t["overlapping_unwrapped"] == 1 and t["cut_islands"] == 1 and t["cut_edges"] > 0
    assert t["certified"] == t["islands"] >= 2 and t["layout_overlaps"] == 0
    assert (lay.face_island >= 0).all() and lay.corner_uv.min() >= 0 and lay.corner_uv.max() <= 1
    assert np.array_equal(lay.corner_uv, lay.corner_uv.astype(np.float32))   # as stored
    assert len(overlapping_triangle_pairs(lay.corner_uv)) == 0
    (e,) = lay.island_entries(res)
    assert e["status"] == "certified" and e["overlap_free"] and e["pieces"] >= 2
    assert e["crossings"] > 0 and len(e["cut_edges"]) == t["cut_edges"]
    json.dumps(e, allow_nan=False)
    # refusing the cut: the island fails and nothing is written
    lay = stored_layout(V, F, res, pack=True, cut=False)
    (e,) = lay.island_entries(res)
    assert e["status"] == "failed" and e["overlap_free"] is False
    assert "crosses itself" in e["message"] and (lay.face_island == -1).all()
    uv, F_uv = lay.vertex_uv(F)
    assert len(uv) == 0 and (F_uv == -1).all()


def test_an_island_whose_pieces_partly_fail_as_stored_says_which_part_is_written():
    """A cut island whose pieces do not all certify as stored (the recut path: rounding made a
    piece cross itself): the pieces that pass are written, and the island's entry says how many,
    not "not written" (the entry had said so while their faces kept their UVs)."""
    import dataclasses
    V, F, res, C = overlapping_result()
    lay = stored_layout(V, F, res, pack=True, cut=True, dtype=np.float32)
    assert len(lay.certificates) >= 2 and all(c.certified for c in lay.certificates)
    failing = dataclasses.replace(lay.certificates[0], certified=False,
                                  reason="1 flipped or collapsed face(s)")
    lay = dataclasses.replace(lay, certificates=[failing] + lay.certificates[1:])
    (e,) = lay.island_entries(res)
    k = len(lay.certificates)
    assert e["status"] == "failed" and e["pieces"] == k
    assert f"{k - 1} of its {k} pieces written, 1 not" in e["message"]
    assert "flipped" in e["message"]
    # every piece failing: nothing of the island is written, and it says so
    lay = dataclasses.replace(lay, certificates=[dataclasses.replace(c, certified=False,
                                                                     reason="x")
                                                 for c in lay.certificates])
    (e,) = lay.island_entries(res)
    assert "island 0: not written" in e["message"]


def test_a_cut_never_splits_a_polygon():
    """With face_groups (the polygon each triangle comes from, as Blender hands them over), the
    pieces of an overlapping island hold whole polygons: a Blender polygon has one UV per corner,
    so a cut through its diagonal could not be stored."""
    V, F = helicoid_ribbon()
    h = len(F) // 2
    quads = np.arange(len(F)) % h                  # triangles q and q + h make quad q
    assert np.array_equal(F[:h, 0], F[h:, 0]) and np.array_equal(F[:h, 2], F[h:, 1])
    res = bd_uv.unwrap(V, F, bound=5.0, face_groups=quads)
    assert all(r.status == "certified" and r.overlap_free for r in res.islands)
    assert len(res.islands) >= 2
    assert np.all(res.face_island[:h] == res.face_island[h:])


@pytest.mark.parametrize("candidates", ["sweep", "tree"])
def test_touching_pairs_is_exact_on_degenerate_integer_segments(candidates, monkeypatch):
    """Integer grid segments (many collinear, touching and shared-end pairs) against an exact
    integer brute force, the candidates from the sweep along x and from the STRtree (where the
    sweep would form too many)."""
    from bd_uv import segments
    from bd_uv.overlap import touching_pairs
    if candidates == "tree":
        monkeypatch.setattr(segments, "_box_pairs", lambda lo, hi, group, limit: None)
    rng = np.random.default_rng(3)
    P = rng.integers(0, 6, (150, 2, 2))
    P = P[np.any(P[:, 0] != P[:, 1], axis=1)]

    def orient(a, b, c):
        v = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        return (v > 0) - (v < 0)

    def on(a, b, c):  # c on segment ab, given collinear
        return (min(a[0], b[0]) <= c[0] <= max(a[0], b[0])
                and min(a[1], b[1]) <= c[1] <= max(a[1], b[1]))

    def meet(s, t):
        a, b, c, d = s[0].tolist(), s[1].tolist(), t[0].tolist(), t[1].tolist()
        o1, o2, o3, o4 = orient(a, b, c), orient(a, b, d), orient(c, d, a), orient(c, d, b)
        if o1 != o2 and o3 != o4 and 0 not in (o1, o2, o3, o4):
            return True
        return (o1 == 0 and on(a, b, c)) or (o2 == 0 and on(a, b, d)) \
            or (o3 == 0 and on(c, d, a)) or (o4 == 0 and on(c, d, b))

    want = {(i, j) for i in range(len(P)) for j in range(i + 1, len(P)) if meet(P[i], P[j])}
    scale = 2.0 ** -7 * 3.0  # exact in binary, small coordinates
    got = touching_pairs(P[:, 0] * scale + 0.5, P[:, 1] * scale + 0.5)
    got_int = touching_pairs(P[:, 0].astype(float), P[:, 1].astype(float))
    assert {tuple(x) for x in got_int.tolist()} == want
    assert {tuple(x) for x in got.tolist()} == want
    # searched group by group (one group here, then every segment its own group but two)
    grouped = touching_pairs(P[:, 0] * scale + 0.5, P[:, 1] * scale + 0.5,
                             np.zeros(len(P), dtype=np.int64))
    assert {tuple(x) for x in grouped.tolist()} == want
    alone = np.arange(len(P))
    alone[1] = 0
    assert {tuple(x) for x in touching_pairs(P[:, 0] * 1.0, P[:, 1] * 1.0, alone).tolist()} \
        == want & {(0, 1)}
    # random groups: the pairs within one group, each once, i < j
    g = rng.integers(0, 5, len(P))
    got = touching_pairs(P[:, 0] * 1.0, P[:, 1] * 1.0, g)
    assert len({tuple(x) for x in got.tolist()}) == len(got)
    assert {tuple(x) for x in got.tolist()} == {(i, j) for i, j in want if g[i] == g[j]}


def test_an_island_with_non_finite_uvs_is_not_overlap_free():
    """Issue 22: an island whose UVs are all NaN (a failed island) was reported overlap-free: its
    faces leave no boundary to cross, but nothing proves it one-to-one. One NaN face is enough."""
    V, F, uv = square()
    certs = certify_islands(V, F, np.full_like(uv, np.nan), [0, 0], [5.0])
    assert not certs[0].overlap_free and not certs[0].certified
    assert certs[0].summary()["overlap_free"] is False
    one = uv.copy()
    one[1, 2] = [np.inf, 0.0]
    c = certify_islands(V, F, one, [0, 0], [5.0])[0]
    assert not c.overlap_free and c.crossings == 0 and not c.certified
    # beside a placed island: only the unplaced one loses overlap_free
    F2 = np.concatenate([F, F + len(V)])
    V2 = np.concatenate([V, V + [3.0, 0, 0]])
    uv2 = np.concatenate([uv, np.full_like(uv, np.nan)])
    ov = island_overlaps(F2, uv2, [0, 0, 1, 1], 2)
    assert ov.overlap_free.tolist() == [True, False] and ov.crossings.tolist() == [0, 0]
    placed, unplaced = certify_islands(V2, F2, uv2, [0, 0, 1, 1], [5.0, 5.0])
    assert placed.certified and placed.overlap_free
    assert not unplaced.overlap_free and not unplaced.certified
    assert certificate_totals([placed, unplaced])["overlapping"] == 1
