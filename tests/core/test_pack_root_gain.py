"""More time where the root sets the adaptive time on up to 50 charts (issue 18,
benchmarks/results/issue18-pack29-2026-11-29.md): ``root_gain`` is recomputed here from the
budget's rules, pack_islands asks square_layout for it, square_layout spends that many times
the seconds it is given (its compaction's budget, recomputed), and the layouts are certified by
``packing_checks.check_layout``. No test checks a time taken."""

import numpy as np
import pytest

import bd_uv.packing.atlas as atlas
import bd_uv.packing.square as square
from bd_uv.packing import PackOptions, pack_islands
from bd_uv.packing.options import ROOT_GAIN
from packing_checks import check_layout
from test_pack_coarse import _shares, _wavy_discs


def _root_gain(k, faces):
    """options.root_gain recomputed: 0.004 sqrt(k faces) above min(0.5, 0.1 k), at most 0.06 k
    and under 20 s, on 2 to 50 charts."""
    root = 0.004 * np.sqrt(k * max(faces, k))
    return ROOT_GAIN if 2 <= k <= 50 and min(0.5, 0.1 * k) < root <= 0.06 * k and root < 20 \
        else 1.0


@pytest.mark.parametrize("k, faces, gained", [
    (27, 968, True), (36, 7828, True), (45, 5804, True),   # suzanne, dino, cow: the root binds
    (42, 1000, True),                                       # igl-decimated-knight
    (10, 20088, False), (29, 19536, False),                 # rocker-arm, camel: the cut binds
    (6, 634, False),                                        # eight: the floor binds
    (116, 19994, False), (51, 5000, False),                 # over 50 charts
    (1, 10 ** 4, False), (2, 10, False)])                   # one chart; the floor
def test_root_gain_only_where_the_root_sets_the_time_on_up_to_50_charts(k, faces, gained):
    auto = PackOptions()
    assert auto.root_gain(k, faces) == _root_gain(k, faces)
    assert (auto.root_gain(k, faces) > 1) is gained
    assert PackOptions(solve_seconds=1.0).root_gain(k, faces) == 1.0
    assert PackOptions(solves=2).root_gain(k, faces) == 1.0
    assert ROOT_GAIN > 1


def test_the_pack_spends_the_gain_on_nesting_and_compaction(monkeypatch):
    """14 wavy discs of 100 faces: the root (0.56 s) above the floor and under the cut (0.84 s),
    recomputed. pack_islands asks square_layout for ROOT_GAIN with the adaptive time and for 1
    with a time given; the compaction's budget is COMPACT_SHARE of the seconds asked times the
    gain (14 charts: one solve's search longer than its first placement, so not the short
    search's share, recomputed); both layouts certified."""
    V, F, uv, lab = _wavy_discs(14, 5, n=100)
    k = 14
    assert _root_gain(k, len(F)) == ROOT_GAIN
    asked, budgets = [], []
    real, compact = atlas.square_layout, square.compact_square

    def spy(o, opt, tol, s, ex, **kw):
        asked.append((s, kw.get("gain")))
        return real(o, opt, tol, s, ex, **kw)
    monkeypatch.setattr(atlas, "square_layout", spy)
    monkeypatch.setattr(square, "compact_square",
                        lambda *a, **kw: budgets.append(a[5]) or compact(*a, **kw))
    for solve in (None, 0.8):
        options = PackOptions(seed=0, solve_seconds=solve)
        asked.clear()
        budgets.clear()
        check_layout(V, F, uv, lab, pack_islands(V, F, uv, lab, options), options)
        seconds, gain = asked[0]
        assert len(asked) == 1 and gain == (ROOT_GAIN if solve is None else 1.0)
        share = float(_shares(V, F, lab).max())
        assert seconds == pytest.approx(options.search_seconds(k, len(F), share))
        nesting = (1 - square.COMPACT_SHARE) * seconds * gain
        start = square.START_PER_CHART * k
        assert nesting - start >= square.SHORT_SEARCH * start
        assert budgets == [pytest.approx(square.COMPACT_SHARE * seconds * gain)]

