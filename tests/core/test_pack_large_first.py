"""bd_uv.packing.large_first: many charts, the largest laid out alone first, the small ones
rastered into the room left, all compacted; checked by code that shares nothing with it
(brute-force segment distances, an even-odd point-in-polygon test, the placed outlines
recomputed from the angles and shifts; through pack_islands, the whole layout check)."""
import numpy as np
import pytest

import bd_uv.packing.large_first as lf
import bd_uv.packing.square as sq
from bd_uv.packing import PackOptions, pack_islands
from bd_uv.packing.nest import Placement
from packing_checks import check_layout, inside, placed
from packing_sets import chart_set, segment_distances


def _least_gap(rings):
    """Least distance between two rings (n_i,2), brute force over their edges."""
    best = np.inf
    for a in range(len(rings)):  # per pair of rings
        for b in range(a + 1, len(rings)):
            p, q = rings[a], rings[b]
            I, J = np.meshgrid(np.arange(len(p)), np.arange(len(q)), indexing="ij")
            I, J = I.ravel(), J.ravel()
            d = segment_distances(p[I], np.roll(p, -1, axis=0)[I], q[J],
                                  np.roll(q, -1, axis=0)[J]).min()
            assert not inside(p[0], q) and not inside(q[0], p)
            best = min(best, float(d))
    return best


def _inside_and_apart(outlines, pl, s, options):
    """The placed outlines inside the square of side ``s`` by half the padding, and the padding
    apart (exact distances)."""
    rings = placed(outlines, pl.angle, pl.shift)
    edge = 0.5 * options.padding * s
    assert min(r.min() for r in rings) >= edge * (1 - 1e-9)
    assert max(r.max() for r in rings) <= s - edge * (1 - 1e-9)
    assert _least_gap(rings) >= options.padding * s * (1 - 1e-9)



def _spy_compaction(monkeypatch):
    """The (placement, side) each ``compact_square`` call of ``large_first`` starts from, listed
    as they come (the compaction itself runs as it would)."""
    starts = []
    compact = lf.compact_square

    def spy(outl, placement, side, *args, **kwargs):
        starts.append((placement, side))
        return compact(outl, placement, side, *args, **kwargs)

    monkeypatch.setattr(lf, "compact_square", spy)
    return starts

def test_many_charts_go_large_first_and_stay_certified(monkeypatch):
    """44 charts, one huge and 43 tiny: the square search takes the large-first way (it returns
    a layout), and the packed layout passes the independent layout check."""
    taken = []

    def spy(*args, **kwargs):
        got = lf.large_first(*args, **kwargs)
        taken.append(got is not None)
        return got

    monkeypatch.setattr(sq, "large_first", spy)
    V, F, uv, lab = chart_set("huge_tiny", 44, seed=5)
    options = PackOptions(resolution=1024, padding_px=4, solve_seconds=1.0)
    packed = pack_islands(V, F, uv, lab, options)
    assert taken == [True]
    cert = check_layout(V, F, uv, lab, packed, options)
    assert 0.05 < cert.coverage < 1.0


def test_the_square_grows_until_the_small_charts_fit(monkeypatch):
    """Six 1 x 1.5 boxes laid out (by a stand-in for the nesting) in a square of side 3.4 that
    they fill but for bands 0.1 and 0.2 wide, and thirty 0.2 x 0.2 squares (the boxes hold 88 %
    of the area: the six large charts): the square grows until the small ones fit, and the
    layout handed to the compaction and the one it returns keep every chart inside with half
    the padding and every two charts the padding apart (brute force)."""
    unit = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    outlines = [unit * [1.0, 1.5] for _ in range(6)] + [0.2 * unit for _ in range(30)]
    options = PackOptions(resolution=64, padding_px=1.0)
    tol = 1e-6
    S = 3.4
    centres = np.array([[0.6 + 1.1 * (i % 3), 0.85 + 1.6 * (i // 3)] for i in range(6)])

    def nested(outl, opt, seconds, exact):
        assert len(outl) == 6 and opt.padding_px == options.padding_px * lf.LARGE_HEADROOM
        return Placement(np.zeros(6), centres.copy(), S), S, 1

    monkeypatch.setattr(lf, "WIDE_SHARE", lf.LARGE_SHARE)   # (no second nesting: see below)
    starts = _spy_compaction(monkeypatch)
    pl, side, solves = lf.large_first(outlines, None, options, tol, 0.5, nested)
    assert solves == 1 and len(starts) == 1
    start, start_side = starts[0]
    assert start_side > S * lf.GROW ** 2      # grown: the band above the squares was too small
    for layout, s in ((start, start_side), (pl, side)):  # the raster's layout, the compacted one
        rings = placed(outlines, layout.angle, layout.shift)
        assert side <= start_side
        edge = 0.5 * options.padding * s
        assert min(r.min() for r in rings) >= edge * (1 - 1e-9)
        assert max(r.max() for r in rings) <= s - edge * (1 - 1e-9)
        assert _least_gap(rings) >= options.padding * s * (1 - 1e-9)


def test_a_long_chart_is_nested_with_the_large_ones(monkeypatch):
    """Six 1 x 1.5 boxes (88 % of the area), a 2.0 x 0.05 strip (1 %) and thirty 0.2 x 0.2
    squares: the strip, longer than ``LONG`` of the side the area would fill at ``DENSITY``
    (recomputed here from the corners), goes to the nesting with the boxes, the squares do not;
    the layout keeps every chart inside with half the padding and every two the padding apart
    (brute force)."""
    unit = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    boxes = [unit * [1.0, 1.5] for _ in range(6)]
    strip = unit * [2.0, 0.05]
    small = [0.2 * unit for _ in range(30)]
    outlines = boxes + small[:15] + [strip] + small[15:]
    options = PackOptions(resolution=64, padding_px=1.0)
    tol = 1e-6
    side = np.sqrt((6 * 1.5 + 2.0 * 0.05 + 30 * 0.04) / lf.DENSITY)
    assert np.hypot(2.0, 0.05) >= lf.LONG * side > np.hypot(0.2, 0.2)
    given = []

    def nested(outl, opt, seconds, exact):
        given.append(outl)
        return sq.square_layout(outl, opt, tol, seconds, exact, split=False)

    monkeypatch.setattr(lf, "WIDE_SHARE", lf.LARGE_SHARE)
    pl, s, _ = lf.large_first(outlines, None, options, tol, 0.3, nested)
    assert len(given) == 1 and len(given[0]) == 7
    assert sum(o is strip for o in given[0]) == 1
    assert sum(any(o is b for b in boxes) for o in given[0]) == 6
    _inside_and_apart(outlines, pl, s, options)


def test_the_large_layout_is_turned_where_the_small_charts_needed_much_growth(monkeypatch):
    """Six 1 x 1.9 boxes laid out (by a stand-in for the nesting) in a square of side 4.2 with
    a free strip 0.8 wide along its left edge, and four 0.9 x 0.9 squares: as laid out, the
    squares fit only once the square has grown ~20 % (the right edge's band, 0.2 wide, grows with
    it: 9 growths or more); turned by a half turn, the strip meets that band and 4 growths do. The
    layout handed to the compaction is the turned one at the smaller side, and it and the
    compacted one keep every chart inside with half the padding and every two the padding
    apart (brute force)."""
    unit = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    outlines = [unit * [1.0, 1.9] for _ in range(6)] + [0.9 * unit for _ in range(4)]
    options = PackOptions(resolution=64, padding_px=1.0)
    tol = 1e-6
    S = 4.2
    centres = np.array([[1.3 + 1.1 * (i % 3), 1.1 + 2.0 * (i // 3)] for i in range(6)])

    def nested(outl, opt, seconds, exact):
        return Placement(np.zeros(6), centres.copy(), S), S, 1

    monkeypatch.setattr(lf, "LARGE_SHARE", 0.7)
    monkeypatch.setattr(lf, "WIDE_SHARE", 0.7)
    monkeypatch.setattr(lf, "LONG", 9.0)
    starts = _spy_compaction(monkeypatch)
    pl, side, solves = lf.large_first(outlines, None, options, tol, 0.3, nested)
    start, start_side = starts[0]
    assert start_side <= S * lf.GROW ** 4 * (1 + 1e-9)
    assert np.allclose(start.angle[:6], 180.0)
    # as laid out (no turn): 9 growths or more
    monkeypatch.setattr(lf, "QUARTERS", 1)
    starts.clear()
    lf.large_first(outlines, None, options, tol, 0.3, nested)
    assert starts[-1][1] >= S * lf.GROW ** 9 * (1 - 1e-9)
    for layout, s in ((start, start_side), (pl, side)):  # the raster's layout, the compacted one
        rings = placed(outlines, layout.angle, layout.shift)
        edge = 0.5 * options.padding * s
        assert min(r.min() for r in rings) >= edge * (1 - 1e-9)
        assert max(r.max() for r in rings) <= s - edge * (1 - 1e-9)
        assert _least_gap(rings) >= options.padding * s * (1 - 1e-9)


def _share_count(outlines, share):
    """The least n such that the n largest outlines (shoelace areas) hold ``share`` of the
    area, at least ``LARGE_LEAST``."""
    area = sorted((0.5 * abs(float(np.sum(o[:, 0] * np.roll(o[:, 1], -1)
                                         - np.roll(o[:, 0], -1) * o[:, 1]))) for o in outlines),
                  reverse=True)
    total, n, held = sum(area), 0, 0.0
    while held < share * total:
        held += area[n]
        n += 1
    return max(n, lf.LARGE_LEAST)


@pytest.mark.parametrize("S, second", [(3.4, True), (4.2, False)])
def test_small_charts_grown_into_a_band_send_more_charts_to_the_nesting(S, second):
    """Six 1 x 1.5 boxes laid out (by a stand-in for the first nesting) in a square of side S,
    and thirty 0.2 x 0.2 squares. At S = 3.4 the boxes fill it but for bands 0.1 and 0.2 wide:
    the squares fit only in a band grown around them, which leaves the square looser (the
    charts' area over its area) than the boxes left theirs by more than ``LOOSE`` of it (0.78 ->
    0.70 at the least growth), so the largest charts holding
    ``WIDE_SHARE`` of the area (their count recomputed here from the corners) are nested
    again, by the real nesting, and the rest rastered around them. At S = 4.2 the squares fit
    in the free strip: one nesting. Either way the layout keeps every chart inside with half
    the padding and every two the padding apart (brute force)."""
    unit = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    boxes = [unit * [1.0, 1.5] for _ in range(6)]
    outlines = boxes + [0.2 * unit for _ in range(30)]
    options = PackOptions(resolution=64, padding_px=1.0)
    tol = 1e-6
    centres = np.array([[0.6 + 1.1 * (i % 3), 0.85 + 1.6 * (i // 3)] for i in range(6)])
    given = []

    def nested(outl, opt, seconds, exact):
        given.append(outl)
        if len(given) == 1:
            return Placement(np.zeros(6), centres.copy(), S), S, 1
        return sq.square_layout(outl, opt, tol, seconds, exact, split=False)

    pl, s, _ = lf.large_first(outlines, None, options, tol, 0.3, nested)
    assert [len(g) for g in given] == ([6, _share_count(outlines, lf.WIDE_SHARE)] if second
                                       else [6])
    assert _share_count(outlines, lf.LARGE_SHARE) == 6
    if second:
        assert sum(any(o is b for b in boxes) for o in given[1]) == 6
    _inside_and_apart(outlines, pl, s, options)
