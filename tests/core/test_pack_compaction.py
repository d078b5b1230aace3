"""bd_uv.packing.compact: the compaction after the nesting, checked by code that shares nothing
with it (brute-force segment distances, an even-odd point-in-polygon test, turns recomputed from
the placed outlines), and through ``pack_islands`` by the atlas's own independent checks."""
import numpy as np
import pytest

from bd_uv.packing import PackOptions, pack_islands
from bd_uv.packing.compact import compact_square
from bd_uv.packing.outlines import chart_outlines
from bd_uv.packing.square import square_layout
from packing_checks import check_layout, inside, placed
from packing_sets import chart_set, segment_distances


def _least_gap(rings):
    """Least distance between the boundaries of two different rings (brute force), and whether
    a ring lies inside another."""
    gap, nested = np.inf, False
    for i in range(len(rings)):  # per ring
        for j in range(i):  # per other ring
            a0, a1 = rings[i], np.roll(rings[i], -1, axis=0)
            b0, b1 = rings[j], np.roll(rings[j], -1, axis=0)
            I, J = np.meshgrid(np.arange(len(a0)), np.arange(len(b0)), indexing="ij")
            I, J = I.ravel(), J.ravel()
            gap = min(gap, float(segment_distances(a0[I], a1[I], b0[J], b1[J]).min()))
            nested |= inside(rings[i][0], rings[j]) or inside(rings[j][0], rings[i])
    return gap, nested


def _inside_and_apart(charts, pl, side, options, tol):
    """The placed outlines (checked: every one inside the square with half the padding plus
    the tolerance, any two the padding plus twice the tolerance apart, none inside another)."""
    rings = placed(charts.outlines, pl.angle, pl.shift)
    pts = np.concatenate(rings)
    edge = 0.5 * options.padding * side + tol
    assert pts.min() >= edge * (1 - 1e-9) and pts.max() <= side - edge * (1 - 1e-9)
    gap, nested = _least_gap(rings)
    assert gap >= (options.padding * side + 2 * tol) * (1 - 1e-9) and not nested
    return rings


@pytest.mark.parametrize("kind, k, rotate", [("boxes", 24, "any"), ("holes", 12, "any"),
                                              ("slivers", 10, "90"), ("boxes", 16, "none")])
def test_compaction_shrinks_the_square_and_keeps_the_padding(kind, k, rotate):
    """From spyrrow's first placement (no search, no compaction: the same every run), 25 linear
    programs: the square gets smaller, every outline stays inside it with half the padding plus
    the tolerance, any two outlines stay the padding plus twice the tolerance apart and none
    inside another; turns change only with rotate "any", and only by small angles."""
    V, F, uv, lab = chart_set(kind, k, seed=11)
    options = PackOptions(resolution=1024, padding_px=4, rotate=rotate, solves=1)
    charts, tol = chart_outlines(V, F, uv, lab, k, options)
    pl0, side0, _ = square_layout(charts.outlines, options, tol, 0.0)
    pl, side, steps = compact_square(charts.outlines, pl0, side0, options, tol, 1e9,
                                     max_programs=25)
    assert steps >= 1 and side < side0 * (1 - 1e-3)
    rings = _inside_and_apart(charts, pl, side, options, tol)
    assert pl.width == side
    turn = (pl.angle - pl0.angle + 180) % 360 - 180
    if rotate == "any":
        assert np.all(np.abs(turn) <= 25 * np.rad2deg(0.1) + 1e-9)
    else:
        assert np.all(turn == 0)
    # the placed outlines are the input's turned and moved: pairwise distances within a chart kept
    for xy, ring in zip(charts.outlines, rings):  # per chart
        assert np.allclose(np.linalg.norm(xy[1:] - xy[0], axis=1),
                           np.linalg.norm(ring[1:] - ring[0], axis=1), rtol=1e-12, atol=1e-12)


def test_compaction_leaves_a_layout_it_cannot_check_alone():
    """A layout that does not keep the padding (here: the square given too small) is returned
    as given, with no step."""
    V, F, uv, lab = chart_set("boxes", 8, seed=2)
    options = PackOptions(solves=1)
    charts, tol = chart_outlines(V, F, uv, lab, 8, options)
    pl0, side0, _ = square_layout(charts.outlines, options, tol, 0.0)
    pl, side, steps = compact_square(charts.outlines, pl0, 0.9 * side0, options, tol, 1e9,
                                     max_programs=5)
    assert steps == 0 and side == 0.9 * side0 and pl is pl0


@pytest.mark.parametrize("kind, k, res, pad", [("huge_tiny", 40, 2048, 4), ("holes", 20, 512, 8)])
def test_default_packing_with_compaction_is_certified(kind, k, res, pad):
    """The default path (one nesting solve, then compaction for half the time), packed and
    checked by the atlas's independent checks (exact triangle overlaps, brute-force gaps)."""
    V, F, uv, lab = chart_set(kind, k, seed=k)
    options = PackOptions(resolution=res, padding_px=pad, solve_seconds=1.0)
    packed = pack_islands(V, F, uv, lab, options)
    cert = check_layout(V, F, uv, lab, packed, options)
    assert 0.05 < cert.coverage < 1.0 and packed.solves == 1


def test_compaction_stops_at_the_widest_charts_least_square():
    """A right triangle (legs 1: its least square box is 1 x 1, at no turn) and a small square
    that fits beside its hypotenuse: no layout's side is below (1 + 2 tol) / (1 - padding).
    Given that side, the compaction stops within ``NEAR_LEAST`` of it, in fewer programs than
    without it, with every outline inside and the padding kept (checked here by brute force)."""
    from bd_uv.packing.nest import Placement
    options = PackOptions(resolution=1024, padding_px=4, rotate="any")
    tol = 1e-4
    tri = np.array([[-0.5, -0.5], [0.5, -0.5], [-0.5, 0.5]])
    box = 0.05 * np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    side0 = 1.3
    edge0 = 0.5 * options.padding * side0 + tol
    pl0 = Placement(np.zeros(2), np.array([[edge0 + 0.5, edge0 + 0.5],
                                           [side0 - edge0 - 0.07, side0 - edge0 - 0.07]]), side0)
    least = (1 + 2 * tol) / (1 - options.padding)
    runs = {}
    for bound in (0.0, least):  # without the least side, then with it
        runs[bound] = compact_square([tri, box], pl0, side0, options, tol, 1e9,
                                     max_programs=400, least_side=bound)
    pl, side, steps = runs[least]
    assert least * (1 - 1e-9) <= side <= least * (1 + 1e-3)
    assert steps < runs[0.0][2] and runs[0.0][1] >= least * (1 - 1e-9)
    rings = placed([tri, box], pl.angle, pl.shift)
    pts = np.concatenate(rings)
    edge = 0.5 * options.padding * side + tol
    assert pts.min() >= edge * (1 - 1e-9) and pts.max() <= side - edge * (1 - 1e-9)
    gap, nested = _least_gap(rings)
    assert gap >= (options.padding * side + 2 * tol) * (1 - 1e-9) and not nested


def test_a_first_layout_too_wide_for_its_square_is_nested_again_as_wide_as_high(monkeypatch):
    """When no layout of the first solve fits its square (here a row of four unit squares in a
    strip 2.7 high), the next strip is the one whose height squares the density reached:
    area / (height x width), recomputed here, not 5 % below it."""
    import bd_uv.packing.square as square
    from bd_uv.packing.nest import Placement
    options = PackOptions(resolution=1024, padding_px=4, solves=1)
    tol = 1e-4
    unit = 0.5 * np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    outlines = [unit.copy() for _ in range(4)]
    asked = []

    def fake(outlines_, sides, options_, tol_, seconds):
        asked.append(list(sides))
        if len(asked) == 1:    # a row: 4.6 wide
            shift = np.array([[0.6 + 1.15 * i, 1.0] for i in range(4)])
            return [[Placement(np.zeros(4), shift, 4.6)]], None
        edge = 0.5 * options.padding * 2.3 * 1.1 + tol
        shift = np.array([[x, y] for x in (0.5, 1.65) for y in (0.5, 1.65)]) + edge
        return [[Placement(np.zeros(4), shift, 2.3)]], None

    monkeypatch.setattr(square, "_solve_all", fake)
    square.square_layout(outlines, options, tol, 0.0)
    assert len(asked) == 2
    p, h = options.padding, square.HEADROOM
    side0 = asked[0][0]
    height = side0 + 2 * (p * side0 * h + 2 * tol - (0.5 * p * side0 * h + tol))
    dens = 4.0 / (height * 4.6)
    expect = max((np.sqrt(4.0 / dens) - 2 * tol) / (1 + p * h), 1.05 * side0)
    assert asked[1][0] == pytest.approx(expect, rel=1e-12)


def test_a_layout_drifted_off_the_low_corner_is_moved_back_and_its_square_cut():
    """Two squares left in the middle of a square with room on every side (the drift a short
    compaction left on Blender's torus at seed 2): with no program run, the layout comes back
    moved as one to the low corner and the side cut to its extent plus the padding, computed
    here; the two squares keep their offset, the padding and the edges."""
    from bd_uv.packing.nest import Placement
    options = PackOptions(resolution=1024, padding_px=4, rotate="any")
    tol = 1e-4
    box = 0.5 * np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    pl0 = Placement(np.zeros(2), np.array([[1.0, 1.2], [2.2, 1.3]]), 4.0)
    pl, side, steps = compact_square([box, box], pl0, 4.0, options, tol, 1e9, max_programs=0)
    assert steps == 0
    extent = max(2.2 + 0.5 - (1.0 - 0.5), 1.3 + 0.5 - (1.2 - 0.5))     # 2.2 wide, 1.1 high
    assert np.isclose(side, (extent + 2 * tol) / (1 - options.padding), rtol=1e-9)
    rings = placed([box, box], pl.angle, pl.shift)
    pts = np.concatenate(rings)
    edge = 0.5 * options.padding * side + tol
    assert np.isclose(pts.min(axis=0), edge, rtol=1e-9).all()
    assert pts.max() <= side - edge * (1 - 1e-9)
    assert np.allclose(pl.shift[1] - pl.shift[0], [1.2, 0.1], rtol=0, atol=1e-12)
    gap, nested = _least_gap(rings)
    assert gap >= (options.padding * side + 2 * tol) * (1 - 1e-9) and not nested


def test_tiny_charts_packed_close_do_not_turn_when_their_programs_are_infeasible():
    """One large chart and 199 tiny ones (a few texels each, like a model's bolts): a tiny
    chart's turn needs more room than the gaps spyrrow leaves among them, so programs that let
    every chart turn are infeasible and the compaction stalled (20 programs: the side 0.6 %
    smaller). From the first infeasible program the tiny charts of tight pairs only move (HOLD):
    the side 2 % smaller, every outline inside, every gap the padding, none inside another."""
    k = 200
    V, F, uv, lab = chart_set("huge_tiny", k, seed=4)
    options = PackOptions(resolution=1024, padding_px=4, rotate="any", solves=1)
    charts, tol = chart_outlines(V, F, uv, lab, k, options)
    pl0, side0, _ = square_layout(charts.outlines, options, tol, 0.0)
    pl, side, steps = compact_square(charts.outlines, pl0, side0, options, tol, 1e9,
                                     max_programs=20)
    assert steps >= 5 and side < side0 * (1 - 0.015)
    rings = _inside_and_apart(charts, pl, side, options, tol)
    for xy, ring in zip(charts.outlines, rings):  # per chart: turned and moved, not mirrored
        e0, e1 = xy[1] - xy[0], ring[1] - ring[0]
        f0, f1 = xy[2] - xy[0], ring[2] - ring[0]
        assert np.isclose(e0[0] * f0[1] - e0[1] * f0[0], e1[0] * f1[1] - e1[1] * f1[0],
                          rtol=1e-9, atol=1e-15)
