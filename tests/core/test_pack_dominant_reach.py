"""The longer nesting, ended at its square, where one chart dominates and the per-chart cut sets
the time (issue 18, benchmarks/results/issue18-pack26-2026-11-28.md): ``dominant_reach`` is
recomputed here from the budget's rules, ``reach`` and it never both apply, pack_islands asks
square_layout for it where the search can end early (not on a worker thread), and the layouts
are certified by ``packing_checks.check_layout``. No test checks a time taken."""

import numpy as np
import pytest

from bd_uv.packing import PackOptions
from bd_uv.packing.options import DOMINANT_REACH
from packing_checks import check_no_reach_on_a_thread, check_reach_asked
from test_pack_coarse import _shares, _wavy_discs


def _dominant_reach(k, faces, largest):
    """options.dominant_reach recomputed: 0.004 sqrt(k faces) above 0.06 k above min(0.5, 0.1 k),
    up to 30 charts, one over 0.3 of the area."""
    root, cut = 0.004 * np.sqrt(k * max(faces, k)), 0.06 * k
    dominant = k <= 30 and largest > 0.3
    return DOMINANT_REACH if (k >= 2 and dominant and min(root, 20.0) > cut > min(0.5, 0.1 * k)) \
        else 1.0


@pytest.mark.parametrize("k, faces, largest", [
    (10, 20088, 0.43), (12, 5856, 0.32),    # rocker-arm, spot: a chart dominates, the cut binds
    (20, 16618, 0.27),                      # igl-arm: none dominates (reach's)
    (27, 968, 0.31), (6, 634, 0.6),         # suzanne (the root binds), eight (the floor)
    (31, 10 ** 5, 0.9), (1, 10 ** 4, 1.0)])  # over 30 charts; one chart
def test_dominant_reach_only_where_a_chart_dominates_and_the_cut_sets_the_time(k, faces,
                                                                               largest):
    auto = PackOptions()
    assert auto.dominant_reach(k, faces, largest) == _dominant_reach(k, faces, largest)
    assert min(auto.reach(k, faces, largest), auto.dominant_reach(k, faces, largest)) == 1.0
    assert PackOptions(solve_seconds=1.0).dominant_reach(k, faces, largest) == 1.0
    assert PackOptions(solves=2).dominant_reach(k, faces, largest) == 1.0
    assert DOMINANT_REACH > 1


def _dominated():
    """10 wavy discs of 240 faces, the first three times the others' radius: the cut (0.6 s)
    below the root (0.62 s), and the first disc's share over 0.3 (recomputed)."""
    V, F, uv, lab = _wavy_discs(10, 4, big=3.0)
    share = float(_shares(V, F, lab).max())
    assert _dominant_reach(10, len(F), share) == DOMINANT_REACH
    return V, F, uv, lab


def test_where_a_chart_dominates_the_pack_nests_longer_ending_each_search_at_its_square(
        monkeypatch):
    check_reach_asked(monkeypatch, *_dominated(), DOMINANT_REACH)


def test_on_a_worker_thread_a_dominated_pack_keeps_its_time(monkeypatch):
    check_no_reach_on_a_thread(monkeypatch, *_dominated())
