"""bd_uv.packing.tiny: where most charts are tiny, the small ones (under SMALL_SHARE of the area)
are dropped with them, smallest first while all the dropped ones hold under TINY_AREA_SHARE,
and the others nest for the time of every chart that is not tiny (issue 18,
benchmarks/results/issue18-pack29-2026-11-29.md). The selections are recomputed here by hand;
the layout is checked by code that shares nothing with the packer (``check_layout``)."""
import numpy as np

from bd_uv.packing import PackOptions, pack_islands
from bd_uv.packing.tiny import SMALL_EXTENT, SMALL_SHARE, TINY_AREA_SHARE, tiny_charts
from packing_checks import check_layout
from test_pack_tiny import _charts, _nestings


def test_small_charts_join_the_tiny_ones_only_past_the_gate():
    assert SMALL_SHARE == 3e-3 and TINY_AREA_SHARE == 0.05 and SMALL_EXTENT == 0.13
    # 10 large, 8 small (0.02 of 10.164: 0.197 % each) and 40 tiny (69 %): all 8 dropped
    area = np.r_[np.ones(10), np.full(8, 0.02), np.full(40, 1e-4)]
    assert np.array_equal(tiny_charts(area), np.arange(10, 58))
    # ... not those reaching SMALL_EXTENT (the tiny ones within TINY_EXTENT)
    ext = np.r_[np.full(10, 0.3), np.full(4, 0.2), np.full(4, 0.1), np.full(40, 0.01)]
    assert np.array_equal(tiny_charts(area, ext), np.arange(14, 58))
    # not past the gate (57 % tiny): nothing, small or tiny
    assert tiny_charts(np.r_[np.ones(22), np.full(8, 0.05), np.full(40, 1e-4)]) is None
    # 30 small of 0.1886 % each (5.66 % together) and 70 tiny (0.066 %): the first 26 fit under
    # 5 % with the tiny ones (26 x 0.1886 = 4.90 < 4.934; 27: 5.09)
    area = np.r_[np.ones(10), np.full(30, 0.02), np.full(70, 1e-4)]
    share = area / area.sum()
    assert 26 * share[10] < 0.05 - share[40:].sum() < 27 * share[10]
    assert np.array_equal(tiny_charts(area), np.r_[np.arange(10, 36), np.arange(40, 110)])
    # two charts are always left to pack: of 1 large and 2 small, one small one goes
    area = np.r_[np.ones(1), np.full(2, 0.002), np.full(10, 1e-5)]
    assert np.array_equal(tiny_charts(area), np.r_[1, np.arange(3, 13)])
    # smallest first: 25 small of 0.1899 % (4.747 %) fit with the tiny ones' 0.066 %, the one
    # of 0.2374 % before them would pass 5 %
    area = np.r_[np.ones(10), 0.025, np.full(25, 0.02), np.full(70, 1e-4)]
    share = area / area.sum()
    assert share[11:36].sum() < 0.05 - share[36:].sum() < share[10:36].sum()
    assert np.array_equal(tiny_charts(area), np.arange(11, 106))


def test_the_others_nest_for_the_time_of_every_chart_that_is_not_tiny(monkeypatch):
    """One 3x3 chart, five 1x1, four small 0.15x0.15 (0.16 % of the area each) and twenty
    tiny 0.03x0.03: the six nest alone for OTHERS_TIME times the time of the ten that are not
    tiny (two faces each), cut by the 3x3's share of the ten's area (recomputed from the
    sizes); the layout certified with every chart in it."""
    seen = _nestings(monkeypatch)
    sizes = np.r_[[[3.0, 3.0]], np.full((5, 2), 1.0), np.full((4, 2), 0.15),
                  np.full((20, 2), 0.03)]
    V, F, uv, lab = _charts(sizes, seed=4)
    area = sizes.prod(axis=1)
    assert np.all((area[6:10] / area.sum() > 1e-3) & (area[6:10] / area.sum() < SMALL_SHARE))
    options = PackOptions(seed=0)
    packed = pack_islands(V, F, uv, lab, options)
    check_layout(V, F, uv, lab, packed, options)
    share = 9.0 / (9.0 + 5.0 + 4 * 0.0225)
    assert len(seen) == 1 and seen[0][0] == 6
    assert np.isclose(seen[0][1], 2.0 * options.search_seconds(10, 10 * 2, share))
