"""Work the seam search saves without changing its charts.

- ``bisect.split_deep`` splits a piece again in the same round while its chart's map restricted
  to it breaks S by 4x, or breaks S at all when the piece holds ``MOST`` of its chart's faces,
  and a piece of a chart without a map while it holds more than ``big`` faces;
- ``rounds.refine`` maps a disk of more than ``MAP_SHARE_VERTICES`` vertices only where it holds
  ``MAP_SHARE`` of the mesh's (a scaled check: this one changes which seams come out on meshes
  of over ~125k vertices only);
- ``merge.merge_charts`` does not solve a union the search already mapped and split: the same
  charts come out with and without that shortcut.
"""
import numpy as np

from bd_uv.seams import auto as auto_mod
from bd_uv.seams import bisect as bisect_mod
from bd_uv.seams import merge as merge_mod
from bd_uv.seams.charts import MARGIN
from seams_helpers import record_mapped, uv_sphere


def _levels(monkeypatch, stretch, n=200, S=2.0, big=None):
    """The pieces ``split_deep`` hands to each level's ``bisect`` for one chart of n faces whose
    map has the same singular values (stretch, 1/stretch) on every face (so every piece's
    restricted stretch is ``stretch``), each piece split 10 % / 90 % by a stand-in ``bisect``."""
    calls = []

    def tenth(pieces, E, cut, A, cen, poly=None):
        calls.append([len(p) for p in pieces])
        return [(p[:max(1, len(p) // 10)], p[max(1, len(p) // 10):]) if len(p) > 1 else None
                for p in pieces]
    monkeypatch.setattr(bisect_mod, "bisect", tenth)
    faces = np.arange(n, dtype=np.int64)
    sigma = None if stretch is None else np.tile([stretch, 1.0 / stretch], (n, 1))
    done = bisect_mod.split_deep([(faces, sigma)], None, None, np.ones(n), None, S, big=big)
    return calls, done


def test_split_deep_splits_a_large_piece_again_while_its_map_breaks_s(monkeypatch):
    S = 2.0
    s = 3.0                                  # beyond S, within DEEPER S
    assert S * MARGIN < s < bisect_mod.DEEPER * S * MARGIN
    calls, done = _levels(monkeypatch, s, S=S)
    assert done.tolist() == [True]
    # 200 -> 20 + 180 (90 %: again) -> 18 + 162 (81 %: again) -> 16 + 146 (73 %: left to its
    # own map in the next round); the small pieces are never split again here.
    assert calls == [[200], [180], [162]]
    assert 162 / 200 >= bisect_mod.MOST > 146 / 200


def test_split_deep_far_beyond_s_splits_every_piece_and_within_s_none(monkeypatch):
    calls, _ = _levels(monkeypatch, 9.0)     # beyond DEEPER S: every piece of 2+ faces
    # (a piece of one face is never split: 2 -> 1 + 1 ends there)
    assert calls == [[200], [20, 180], [2, 18, 18, 162], [17, 17, 16, 146]]
    assert len(calls) == bisect_mod.SPLIT_DEPTH
    calls, _ = _levels(monkeypatch, 1.5)     # within S: one split, its pieces mapped next
    assert calls == [[200]]


def test_split_deep_splits_pieces_of_an_unmapped_chart_while_above_big(monkeypatch):
    # No map: once without ``big``; with it, every piece of more than ``big`` faces again, to
    # SPLIT_DEPTH levels: 200 -> 20 + 180 -> 18 + 162 -> 16 + 146 -> 14 + 132 (not again).
    calls, done = _levels(monkeypatch, None)
    assert calls == [[200]] and done.tolist() == [True]
    calls, done = _levels(monkeypatch, None, big=50)
    assert calls == [[200], [180], [162], [146]] and done.tolist() == [True]
    assert len(calls) == bisect_mod.SPLIT_DEPTH
    calls, _ = _levels(monkeypatch, None, big=170)      # 180 > 170 >= 162: two levels
    assert calls == [[200], [180]]
    # A chart with a map is not split deeper for its size: within S, one level as before.
    calls, _ = _levels(monkeypatch, 1.5, big=50)
    assert calls == [[200]]


def test_merging_skips_unions_the_search_failed_with_the_same_charts(monkeypatch):
    V, F, _ = uv_sphere(32, 16)
    runs = {}
    for skip in (True, False):
        solved, failed = [], {}
        chart_maps = merge_mod.chart_maps
        merge_charts = merge_mod.merge_charts

        def recorded(V_, chs, *a, **k):
            solved.extend(merge_mod.chart_key(c) for c in chs)
            return chart_maps(V_, chs, *a, **k)

        def merging(*a, **k):
            failed.update(k.get("failed") or {})
            if not skip:
                k["failed"] = None
            return merge_charts(*a, **k)
        monkeypatch.setattr(merge_mod, "chart_maps", recorded)
        monkeypatch.setattr(auto_mod, "merge_charts", merging)
        result, added, info = auto_mod.unwrap_auto(V, F, bound=2.0, stretch=2.0)
        monkeypatch.undo()
        assert all(r.status == "certified" for r in result.islands)
        runs[skip] = (solved, failed, added, info["charts"])
    with_skip, without = runs[True], runs[False]
    # Without the shortcut merging solves a union the search had mapped and split ...
    again = [k for k in without[0] if k in without[1]]
    assert len(again) >= 1
    # ... with it, never, and it solves every other union it solved before, and no more.
    assert not any(k in with_skip[1] for k in with_skip[0])
    assert with_skip[0] == [k for k in without[0] if k not in without[1]]
    np.testing.assert_array_equal(with_skip[2], without[2])
    assert with_skip[3] == without[3]


def test_rounds_map_a_mid_size_disk_only_where_it_holds_a_share_of_the_mesh(monkeypatch):
    """``rounds.refine`` splits unmapped a disk of more than ``MAP_SHARE_VERTICES`` vertices that
    holds less than ``MAP_SHARE`` of the mesh's (scaled to a 2,000-vertex sphere, whose first
    round maps its two halves of ~1,150 and ~900 vertices), maps the others up to
    ``MAP_VERTICES``, and every chart still certifies."""
    from bd_uv.seams import rounds as rounds_mod
    V, F, _ = uv_sphere(64, 32)
    nv = len(V)
    runs = {}
    for low in (None, 300):
        mapped = record_mapped(monkeypatch, rounds_mod)
        if low is not None:
            monkeypatch.setattr(rounds_mod, "MAP_SHARE_VERTICES", low)
            monkeypatch.setattr(rounds_mod, "MAP_SHARE", 0.7)
        result, added, info = auto_mod.unwrap_auto(V, F, bound=2.0, stretch=2.0)
        monkeypatch.undo()
        assert all(r.status == "certified" for r in result.islands)
        # every face in exactly one certified island, each within the bound
        faces = np.concatenate([r.faces for r in result.islands])
        assert np.array_equal(np.sort(faces), np.arange(len(F)))
        assert max(r.max_distortion for r in result.islands) <= 2.0
        runs[low] = mapped
    share = 0.7 * nv
    assert any(300 < n < share for n in runs[None])       # the default maps such disks ...
    assert not any(300 < n < share for n in runs[300])    # ... the scaled rule never does,
    assert any(n <= 300 for n in runs[300])               # but maps their pieces
