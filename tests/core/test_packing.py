"""bd_uv.packing: random chart sets packed, then checked by code that shares nothing with it
(exact triangle overlap test, brute-force edge distances, densities and turns from the corners)."""
import numpy as np
import pytest

from bd_uv.errors import BDError, PackError
from bd_uv.packing import PackOptions, layout_certificate, pack_islands, udim_tile, uv_islands
from overlap_shapes import overlapping_triangle_pairs
from packing_checks import check_layout
from packing_sets import chart_maps, chart_set, least_gap, texel_densities


@pytest.mark.parametrize("kind, k, res, pad, rotate", [
    ("boxes", 1, 256, 0, "any"),
    ("boxes", 30, 1024, 4, "any"),
    ("slivers", 25, 2048, 8, "90"),
    ("holes", 12, 512, 16, "none"),
    ("huge_tiny", 60, 8192, 2, "any"),
])
def test_random_chart_sets_pack_inside_apart_one_density_no_mirror(kind, k, res, pad, rotate):
    V, F, uv, lab = chart_set(kind, k, seed=k)
    before = uv.copy()
    options = PackOptions(resolution=res, padding_px=pad, rotate=rotate, solves=2)
    packed = pack_islands(V, F, uv, lab, options)
    assert np.array_equal(uv, before)                       # input untouched
    cert = check_layout(V, F, uv, lab, packed, options)
    assert 0.05 < cert.coverage < 1.0
    assert packed.solves >= (2 if k > 1 else 0) and packed.seconds > 0


def test_constructive_placement_only_is_certified_too():
    """solve_seconds=0 (``--pack-seconds 0``): spyrrow's first placement, no search; the layout is
    still inside, apart and of one density."""
    V, F, uv, lab = chart_set("holes", 12, seed=5)
    options = PackOptions(resolution=1024, padding_px=4, solve_seconds=0)
    packed = pack_islands(V, F, uv, lab, options)
    cert = check_layout(V, F, uv, lab, packed, options)
    assert 0.05 < cert.coverage < 1.0 and packed.solves >= 1
    with pytest.raises(PackError, match="solve_seconds"):
        PackOptions(solve_seconds=-1)


def test_nesting_time_is_adaptive_or_as_given():
    """None (the default): 4 ms sqrt(charts x faces), at most 60 ms a chart and 20 s, nothing
    for one chart; a number of seconds, fractional too, is taken as given; anything else
    refused."""
    auto = PackOptions()
    assert auto.search_seconds(1, 10_000) == 0.0
    assert auto.search_seconds(45, 5804, tiny=14) == pytest.approx(0.004 * (45 * 5804) ** 0.5)
    assert auto.search_seconds(29, 19536) == pytest.approx(0.06 * 29)    # camel's charts
    assert auto.search_seconds(5000, 10 ** 6) == 20.0
    assert PackOptions(solve_seconds=0.25).search_seconds(46, 5804) == 0.25
    for bad in ("1", -0.5, 1e9):
        with pytest.raises(PackError, match="solve_seconds"):
            PackOptions(solve_seconds=bad)


def test_adaptive_time_has_a_floor_for_a_few_charts():
    """Two charts or more get at least 0.5 s, or 0.1 s a chart below six: eight's 6 charts of
    634 faces would get 4 ms sqrt(6 x 634) = 0.25 s and get 0.5 s, fandisk's 4 would get 60 ms a
    chart and get 0.4 s; one chart still none, and a number of seconds given is still taken as
    given."""
    auto = PackOptions()
    assert 0.004 * (6 * 634) ** 0.5 < 0.5 and auto.search_seconds(6, 634) == 0.5
    assert auto.search_seconds(4, 12946) == pytest.approx(0.4)
    assert auto.search_seconds(3, 12946) == pytest.approx(0.3)
    assert auto.search_seconds(2) == pytest.approx(0.2)
    assert auto.search_seconds(1, 10 ** 6) == 0.0
    assert PackOptions(solve_seconds=0.1).search_seconds(6, 634) == 0.1


def test_adaptive_time_grows_with_many_charts_that_are_not_tiny():
    """From 40 charts that are not tiny, at least 64 ms each: the Spider's 63 charts of 1,368
    faces (9 tiny) would get 4 ms sqrt(63 x 1,368) = 1.17 s and get 0.064 x 54 = 3.46 s;
    Wuson's 83 charts of 3,732 faces with 56 tiny keep the root (27 not tiny: 2.23 s); the
    root still wins where it is larger (cow's 45 charts of 5,804 faces, 14 tiny); 39 charts
    that are not tiny get the root; never above the 20 s cap."""
    auto = PackOptions()
    assert auto.search_seconds(63, 1368, tiny=9) == pytest.approx(0.064 * 54)
    assert 0.004 * (63 * 1368) ** 0.5 < 0.064 * 54
    assert auto.search_seconds(83, 3732, tiny=56) == pytest.approx(0.004 * (83 * 3732) ** 0.5)
    assert auto.search_seconds(45, 5804, tiny=14) == pytest.approx(0.004 * (45 * 5804) ** 0.5)
    assert auto.search_seconds(49, 500, tiny=10) == pytest.approx(0.004 * (49 * 500) ** 0.5)
    assert auto.search_seconds(900, 1000, tiny=100) == 20.0


def test_every_layout_the_search_reports_keeps_the_separation():
    """Every strip spyrrow reports on its way (each a candidate square) is checked here from the
    placed outlines: inside the strip, outlines at least the separation apart (GEOS distances)."""
    import shapely
    from bd_uv.packing.nest import nest, rotations
    from bd_uv.packing.outlines import chart_outlines
    V, F, uv, lab = chart_set("holes", 10, seed=7)
    options = PackOptions(solve_seconds=1)
    charts, _ = chart_outlines(V, F, uv, lab, 10, options)
    height, sep = 1.3 * np.sqrt(charts.area.sum()), 0.02
    reports = []
    final = nest(charts.outlines, height, sep, options, 1.0, reports)
    assert len(reports) >= 2 and reports[-1].width == pytest.approx(final.width)
    for pl in reports:  # per reported layout
        R = rotations(pl.angle)
        polys = [shapely.Polygon(xy @ R[i].T + pl.shift[i]) for i, xy in enumerate(charts.outlines)]
        lo = np.min([p.bounds[:2] for p in polys], axis=0)
        hi = np.max([p.bounds[2:] for p in polys], axis=0)
        assert lo.min() >= -1e-5 and hi[1] <= height + 1e-5 and hi[0] <= pl.width + 1e-5
        gaps = [polys[i].distance(polys[j]) for i in range(10) for j in range(i)]
        assert min(gaps) >= sep * (1 - 1e-4)


def test_two_thousand_tiny_charts():
    V, F, uv, lab = chart_set("boxes", 2000, seed=3)
    options = PackOptions(resolution=4096, padding_px=1, solves=1)
    packed = pack_islands(V, F, uv, lab, options)
    check_layout(V, F, uv, lab, packed, options)


def test_udim_spill_numbers_tiles_as_blender():
    assert [udim_tile(i)[0] for i in (0, 1, 9, 10, 11)] == [1001, 1002, 1010, 1011, 1012]
    assert [udim_tile(i)[1] for i in (0, 1, 9, 10, 11)] == [(0, 0), (1, 0), (9, 0), (0, 1), (1, 1)]
    V, F, uv, lab = chart_set("boxes", 24, seed=5)
    # the set's 3D area at 120 texels per unit is about three 256 px tiles; its largest chart fits
    options = PackOptions(resolution=256, padding_px=4, texel_density=120.0, udim=True, solves=1)
    packed = pack_islands(V, F, uv, lab, options)
    used = sorted(set(packed.tile.tolist()))
    assert used == list(range(1001, 1001 + len(used))) and len(used) >= 2
    check_layout(V, F, uv, lab, packed, options, tiles=used)
    assert packed.texel_density == pytest.approx(120.0, rel=1e-9)


def test_texel_density_that_does_not_fit_without_udim_is_a_clear_error():
    V, F, uv, lab = chart_set("boxes", 24, seed=5)
    with pytest.raises(PackError, match="do not fit the square"):
        pack_islands(V, F, uv, lab, PackOptions(resolution=256, texel_density=120.0))


def test_a_chart_larger_than_a_tile_is_a_clear_error():
    V, F, uv, lab = chart_set("huge_tiny", 3, seed=1)
    with pytest.raises(PackError, match="larger than a UDIM tile"):
        pack_islands(V, F, uv, lab, PackOptions(resolution=256, texel_density=1000.0, udim=True))


@pytest.mark.parametrize("kwargs, words", [
    (dict(resolution=0), "resolution"), (dict(padding_px=-1), "padding"),
    (dict(rotate="mirror"), "rotate"), (dict(udim=True), "texel density"),
    (dict(texel_density=0.0), "texel density"),
])
def test_bad_options_raise_typed_errors(kwargs, words):
    with pytest.raises(PackError, match=words) as err:
        PackOptions(**kwargs)
    assert isinstance(err.value, BDError)


def test_flipped_chart_is_refused_and_input_untouched():
    V, F, uv, lab = chart_set("boxes", 3, seed=2)
    uv[lab == 1] = uv[lab == 1][:, [0, 2, 1]]               # chart 1 mirrored: faces flipped
    before = uv.copy()
    with pytest.raises(PackError, match="flipped"):
        pack_islands(V, F, uv, lab)
    assert np.array_equal(uv, before)


def test_certificate_sees_an_overlap_and_a_short_gap():
    V, F, uv, lab = chart_set("boxes", 4, seed=4)
    options = PackOptions(solves=1)
    packed = pack_islands(V, F, uv, lab, options)
    out = packed.corner_uv.copy()
    # chart 1 moved onto chart 0: the certificate fails it
    c0 = out[lab == 0].reshape(-1, 2).mean(0)
    c1 = out[lab == 1].reshape(-1, 2).mean(0)
    moved = out.copy()
    moved[lab == 1] += c0 - c1
    cert = layout_certificate(V, F, moved, lab, packed.tile, 1024, 4)
    assert not cert.certified and len(cert.overlaps) >= 1
    # padding asked for larger than the layout keeps: certified False, gap reported
    cert = layout_certificate(V, F, out, lab, packed.tile, 1024, 64)
    assert not cert.certified and "least gap" in cert.reason


def test_a_chart_with_no_uv_area_has_an_unbounded_density_spread():
    """A chart whose UVs are collapsed onto a line (any UV map's degenerate island) has texel
    density 0: the spread is infinite, said as null in the JSON report (not Infinity, which
    strict JSON readers refuse), and with no divide-by-zero warning."""
    import json
    import warnings
    V, F, uv, lab = chart_set("boxes", 3, seed=1)
    packed = pack_islands(V, F, uv, lab, PackOptions(solves=1))
    out = packed.corner_uv.copy()
    flat = out[lab == 2]
    flat[..., 1] = flat[..., 1].mean()                      # chart 2: zero UV area
    out[lab == 2] = flat
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cert = layout_certificate(V, F, out, lab, packed.tile, 1024, 4)
    assert cert.density_spread == np.inf
    summary = json.loads(json.dumps(cert.summary(), allow_nan=False))
    assert summary["density_spread"] is None
    fine = layout_certificate(V, F, packed.corner_uv, lab, packed.tile, 1024, 4)
    assert 1.0 <= fine.density_spread < 1.001 and fine.summary()["density_spread"] >= 1.0


def test_a_face_flipped_or_collapsed_as_stored_fails_the_layout_certificate():
    """Every face turns counter-clockwise as packed; the certificate counts the faces that do
    not as stored: one chart mirrored (all its faces), and one sliver thinner than float32's
    step at its place (it collapses in float32 and the certificate of the float32 UVs says so,
    while the float64 UVs pass)."""
    V, F, uv, lab = chart_set("boxes", 3, seed=1)
    packed = pack_islands(V, F, uv, lab, PackOptions(solves=1))
    out = packed.corner_uv
    assert layout_certificate(V, F, out, lab, packed.tile, 1024, 4).flipped_faces == 0
    mirrored = out.copy()
    c = mirrored[lab == 1]
    c[..., 0] = 2 * c[..., 0].mean() - c[..., 0]             # chart 1 mirrored in place
    mirrored[lab == 1] = c
    cert = layout_certificate(V, F, mirrored, lab, packed.tile, 1024, 4)
    assert cert.flipped_faces == int((lab == 1).sum()) and not cert.certified
    assert f"{cert.flipped_faces} face(s) flipped or collapsed as stored" in cert.reason
    assert cert.summary()["flipped_faces"] == cert.flipped_faces
    # a sliver: chart 0's first face 1e-9 thin along a float32-exact edge near 0.5, far below
    # float32's 6e-8 step there (only the flip count is read: the face may now overlap)
    thin = out.copy()
    f = int(np.flatnonzero(lab == 0)[0])
    thin[f] = [[0.5, 0.5], [0.75, 0.5], [0.625, 0.5 + 1e-9]]
    twice = np.cross(thin[f, 1] - thin[f, 0], thin[f, 2] - thin[f, 0])
    assert twice > 0                                        # counter-clockwise in float64
    assert layout_certificate(V, F, thin, lab, packed.tile, 1024, 4).flipped_faces == 0
    s32 = thin.astype(np.float32)
    e = s32[f].astype(np.float64)
    assert not np.cross(e[1] - e[0], e[2] - e[0]) > 0       # gone in float32
    cert = layout_certificate(V, F, s32, lab, packed.tile, 1024, 4)
    assert cert.flipped_faces == 1 and not cert.certified


def test_uv_islands_follow_shared_uvs_not_shared_vertices():
    # two triangles sharing mesh edge (1, 2): one island when the UVs agree along it, two when not
    F = np.array([[0, 1, 2], [2, 1, 3]])
    uv = np.array([[[0, 0], [1, 0], [0, 1]], [[0, 1], [1, 0], [1, 1]]], float)
    assert uv_islands(F, uv).tolist() == [0, 0]
    cut = uv.copy()
    cut[1] += 5.0
    assert uv_islands(F, cut).tolist() == [0, 1]
    nan = uv.copy()
    nan[0, 0] = np.nan
    assert uv_islands(F, nan).tolist() == [-1, 0]
    V, F, uv, lab = chart_set("holes", 7, seed=1)
    assert np.array_equal(uv_islands(F, uv), lab)


def test_a_duplicate_face_joins_its_twins_island_and_leaves_it_whole():
    # A quad (two triangles) given twice with the same UVs, and a second quad apart: the copy
    # must not cut its twin's diagonal (used four times) nor travel alone when packed.
    F = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [1, 2, 0], [0, 2, 3]])
    quad = np.array([[[0, 0], [1, 0], [1, 1]], [[0, 0], [1, 1], [0, 1]]], float)
    other = np.array([[[3, 0], [4, 0], [3, 1]]], float)
    uv = np.concatenate([quad, other, quad[:1][:, [1, 2, 0]], quad[1:]])
    assert uv_islands(F, uv).tolist() == [0, 0, 1, 0, 0]
    moved = uv.copy()
    moved[3:] += 7.0          # the copy's UVs elsewhere: not its twin's island
    lab = uv_islands(F, moved)
    assert lab[3] not in lab[:3] and lab[4] not in lab[:3]


def test_pinned_charts_do_not_move_and_the_rest_pack_beside_them():
    V, F, uv, lab = chart_set("boxes", 14, seed=7)
    targets = {0: ((0.05, 0.05), 0.3), 1: ((0.6, 0.1), 0.25), 2: ((0.1, 0.7), 0.2)}
    for c, (at, size) in targets.items():     # pinned charts put somewhere in the square
        P = uv[lab == c]
        lo, hi = P.reshape(-1, 2).min(0), P.reshape(-1, 2).max(0)
        uv[lab == c] = (P - lo) * (size / (hi - lo).max()) + at
    pinned = np.zeros(14, bool)
    pinned[list(targets)] = True
    options = PackOptions(resolution=512, padding_px=6, solves=1)
    packed = pack_islands(V, F, uv, lab, options, pinned=pinned)
    out = packed.corner_uv.astype(np.float32).astype(np.float64)
    keep = pinned[lab]
    assert np.array_equal(packed.corner_uv[keep], uv[keep])          # bit for bit
    assert out.min() >= 0 and out.max() <= 1
    pairs = overlapping_triangle_pairs(out)
    assert not np.any(lab[pairs[:, 0]] != lab[pairs[:, 1]])
    assert least_gap(out, lab, reach=12 / 512) * 512 >= 6 * (1 - 1e-4)
    d = texel_densities(V, F, packed.corner_uv, lab)[~pinned]
    assert np.allclose(d, d[0], rtol=1e-9)
    J = chart_maps(uv[~keep], packed.corner_uv[~keep])
    assert np.all(np.linalg.det(J) > 0)
    cert = layout_certificate(V, F, out, lab, packed.tile, 512, 6)
    assert cert.certified, cert.reason


def test_pinned_chart_outside_the_square_is_a_clear_error():
    V, F, uv, lab = chart_set("boxes", 4, seed=8)
    pinned = np.array([True, False, False, False])
    with pytest.raises(PackError, match="outside the unit square"):
        pack_islands(V, F, uv + 10.0, lab, PackOptions(), pinned=pinned)


def test_a_chart_too_thin_for_spyrrow_is_nested_grown(capfd):
    """A bishop of the ASWF's OpenChessSet has a chart 1.9e-3 long and 3e-9 high: spyrrow found
    no pole of inaccessibility for it and panicked ("no pole found with 10 levels of recursion"),
    failing the whole mesh. Nested grown by a hair instead: every outline inside the strip, the
    grown ones apart, so the charts themselves are too (checked on their placed outlines)."""
    import shapely
    from bd_uv.packing import PackOptions
    from bd_uv.packing.nest import nest, rotations
    sliver = np.array([[-0.00092851144, -1.4638434e-9], [0.00092851144, -6.656209e-10],
                       [0.0005803199, -5.097549e-10], [0.00092851114, 1.4638434e-9]])
    box = np.array([[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]])
    outlines = [sliver * 50, box, box * 0.5, sliver]
    pl = nest(outlines, 1.0, 0.0, PackOptions(), 0.0)
    # nested grown from the start: spyrrow never sees it, so no panic text reaches stderr
    # (Rust prints it there even when the panic is caught and retried)
    assert "panicked" not in capfd.readouterr().err
    placed = [xy @ rotations(a).T + s for xy, a, s in zip(outlines, pl.angle, pl.shift)]
    for q in placed:
        assert np.isfinite(q).all() and q[:, 1].min() >= -1e-9 and q[:, 1].max() <= 1 + 1e-9
    polys = [shapely.Polygon(q) for q in placed]
    for i in range(len(polys)):
        for j in range(i):
            assert not polys[i].intersects(polys[j]) or polys[i].intersection(polys[j]).area == 0


@pytest.mark.parametrize("apart", [0.0, 1e-9])
def test_an_outline_passing_a_point_twice_is_nested_grown(capfd, apart):
    """A chart whose outline touches itself at one point (two triangles joined at a vertex; some
    of OpenChessSet's bishop charts): spyrrow panics ("Simple polygon has non-consecutive
    duplicate vertices"), and Rust prints that on stderr even though the panic is caught and the
    charts retried. Nested grown from the start instead: no panic text, every outline in the
    strip, the placed outlines at least the separation apart (GEOS distances). ``apart``: the
    two passes 1e-9 apart, one point in float32, which spyrrow reads."""
    import shapely
    from bd_uv.packing import PackOptions
    from bd_uv.packing.nest import nest, rotations
    pinched = np.array([[0, 0], [0.2, -0.1], [0.2, 0.1], [0, 0], [-0.2, 0.1], [-0.2, -0.1]],
                       dtype=float) + [0.25, 0.125]
    pinched[3, 0] += apart
    assert len(np.unique(pinched.astype(np.float32), axis=0)) == 5
    box = np.array([[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]])
    outlines = [pinched, box, box * 0.5]
    pl = nest(outlines, 1.0, 0.01, PackOptions(), 0.0)
    assert "panicked" not in capfd.readouterr().err
    placed = [xy @ rotations(a).T + s for xy, a, s in zip(outlines, pl.angle, pl.shift)]
    for q in placed:
        assert q[:, 1].min() >= -1e-9 and q[:, 1].max() <= 1 + 1e-9
    parts = [shapely.MultiPolygon([shapely.Polygon(q[:3]), shapely.Polygon(q[3:])])
             if len(q) == 6 else shapely.Polygon(q) for q in placed]
    for i in range(len(parts)):
        for j in range(i):
            assert parts[i].distance(parts[j]) >= 0.01 * (1 - 1e-9)


def test_outlines_finer_than_the_separation_nest_without_a_panic(capfd):
    """A chart of OpenChessSet (49 points, 28 pairs of them closer together than the
    separation): spyrrow's own offset of it by half the separation made a polygon with duplicate
    vertices and panicked ("Simple polygon has non-consecutive duplicate vertices"); the panic was
    caught and the charts nested again grown, but Rust printed its text on stderr. The outlines
    now go to spyrrow grown by shapely, with no separation of spyrrow's: one solve, no panic
    text, every outline in the strip and the placed outlines the separation apart (GEOS)."""
    import os
    import shapely
    from bd_uv.packing.nest import nest, rotations
    path = os.path.join(os.path.dirname(__file__), "..", "data", "chess_chart_outline.txt")
    chart = np.loadtxt(path)
    sep, height = 0.0008310183253844458, 0.03
    box = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * 0.004
    outlines = [chart, box, box * 0.5, chart[::-1] * [-1, 1]]
    pl = nest(outlines, height, sep, PackOptions(), 0.0)
    assert "panicked" not in capfd.readouterr().err
    placed = [xy @ rotations(a).T + s for xy, a, s in zip(outlines, pl.angle, pl.shift)]
    edge = 0.5 * sep * (1 - 1e-6)
    for q in placed:
        assert q[:, 1].min() >= edge and q[:, 1].max() <= height - edge
    polys = [shapely.Polygon(q) for q in placed]
    for i in range(len(polys)):
        for j in range(i):
            assert polys[i].distance(polys[j]) >= sep * (1 - 1e-9)
