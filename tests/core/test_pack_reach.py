"""A longer nesting ended by its progress where the per-chart cut set the time (issue 18,
benchmarks/results/issue18-pack24-2026-11-28.md): where ``options.reach`` applies (recomputed
here from the budget's rules), each search ends once its layout is no wider than its strip is
high (:mod:`bd_uv.packing.early_stop`: on the main thread, by Python's SIGINT flag). These tests
check the flag and the layouts, never the time taken; packs are certified by
``packing_checks.check_layout``."""
import threading
import time

import numpy as np
import pytest
import shapely

from bd_uv.packing import PackOptions
from bd_uv.packing import early_stop
from bd_uv.packing.nest import FEASIBLE
from bd_uv.packing.options import REACH
from packing_checks import check_no_reach_on_a_thread, check_reach_asked
from test_pack_coarse import _shares, _wavy_discs


def _reach(k, faces, largest=0.0):
    """options.reach recomputed: 0.004 sqrt(k faces) above 0.06 k above min(0.5, 0.1 k), and
    no chart over 0.3 of the area (up to 30 charts)."""
    root, cut = 0.004 * np.sqrt(k * max(faces, k)), 0.06 * k
    dominant = k <= 30 and largest > 0.3
    return REACH if (k >= 2 and not dominant and min(root, 20.0) > cut > min(0.5, 0.1 * k)) \
        else 1.0


@pytest.mark.parametrize("k, faces, largest", [
    (20, 16618, 0.27), (17, 12064, 0.22),   # igl-arm, igl-elephant: the cut binds
    (10, 20088, 0.43),                      # rocker-arm: a chart dominates
    (27, 968, 0.31), (36, 7828, 0.35),      # suzanne, dino: the root binds
    (45, 5804, 0.31), (8, 2000, 0.1),       # cow (root); 8 charts: the floor binds
    (31, 10 ** 5, 0.9), (1, 10 ** 4, 1.0)])  # many charts, one dominant; one chart
def test_reach_only_where_the_per_chart_cut_sets_the_time(k, faces, largest):
    assert PackOptions().reach(k, faces, largest) == _reach(k, faces, largest)
    assert PackOptions(solve_seconds=1.0).reach(k, faces, largest) == 1.0
    assert PackOptions(solves=2).reach(k, faces, largest) == 1.0
    assert REACH > 1


def _items(k, seed):
    import spyrrow
    rng = np.random.default_rng(seed)
    items = []
    for i in range(k):  # per item: a random convex-ish hexagon
        t = np.sort(rng.uniform(0, 2 * np.pi, 6))
        r = rng.uniform(0.4, 1.0, 6)
        items.append(spyrrow.Item(str(i), [(float(a), float(b)) for a, b in
                                           zip(r * np.cos(t), r * np.sin(t))], demand=1,
                                  allowed_orientations=None))
    return items


def _solve(items, height, seconds, narrow):
    import spyrrow
    from datetime import timedelta
    inst = spyrrow.StripPackingInstance("t", height, items)
    cfg = spyrrow.StripPackingConfig(early_termination=True, seed=0, total_computation_time=None,
                                     exploration_time=0, compression_time=0, num_workers=1)
    cfg.exploration_time = timedelta(seconds=0.8 * seconds)
    cfg.compression_time = timedelta(seconds=0.2 * seconds)
    return early_stop.solve_until(inst, cfg, spyrrow.ProgressQueue(), FEASIBLE, narrow)


def _disjoint(sol, items):
    """Every placed item, turned and moved (recomputed from the placements), overlaps no other
    beyond rounding."""
    shapes = []
    for p in sol.placed_items:  # per item
        xy = np.array(items[int(p.id)].shape, dtype=float)
        a = np.deg2rad(p.rotation)
        R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        shapes.append(shapely.Polygon(xy @ R.T + np.array(p.translation)))
    return len(shapes) == len(items) and all(
        shapes[i].intersection(shapes[j]).area < 1e-6 * shapes[i].area
        for i in range(len(shapes)) for j in range(i))


def test_a_search_on_the_main_thread_ends_at_the_first_layout_narrow_enough():
    """Asked 20 s, with any feasible layout narrow enough: the search is ended (the flag), its
    layout is no wider than the first one reported, every item is placed and none overlaps; no
    KeyboardInterrupt reaches the caller."""
    assert early_stop.can_stop()
    items = _items(12, 1)
    sol, drained, ended = _solve(items, 4.0, 20.0, np.inf)
    assert ended
    first = [s for kind, s in drained if int(kind) in FEASIBLE][0]
    assert sol.width <= first.width + 1e-9
    assert _disjoint(sol, items)
    time.sleep(0.01)   # (a stray interrupt would be raised here)


def test_off_the_main_thread_the_search_is_not_ended():
    """In another thread nothing trips the flag: the search runs its (short) time."""
    out = []
    th = threading.Thread(target=lambda: out.append((early_stop.can_stop(),
                                                     _solve(_items(6, 2), 3.0, 0.2, np.inf))))
    th.start()
    th.join()
    can, (sol, drained, ended) = out[0]
    assert not can and not ended
    assert _disjoint(sol, _items(6, 2))


class _Queue:
    def __init__(self, reports):
        self.reports = list(reports)

    def drain(self):
        out, self.reports = self.reports, []
        return out


class _Sol:
    def __init__(self, width):
        self.width = width


def test_a_trip_the_search_did_not_see_gives_the_last_feasible_report():
    """A solve that ends without handling the trip (here: Python code that gets the
    KeyboardInterrupt itself): the last feasible report drained is the result, the flag is set
    and nothing is raised."""
    reports = [(FEASIBLE[0], _Sol(3.0)), (1, _Sol(2.0)), (FEASIBLE[1], _Sol(2.5))]

    class Slow:
        def solve(self, cfg, queue):
            for _ in range(20000):   # until the trip lands (at most 20 s)
                time.sleep(0.001)
            return _Sol(9.0)
    sol, drained, ended = early_stop.solve_until(Slow(), None, _Queue(reports), FEASIBLE, 2.8)
    assert ended and sol.width == 2.5 and len(drained) == 3
    time.sleep(0.01)


def test_a_users_ctrl_c_during_the_search_is_raised_not_dropped():
    """A SIGINT that the watcher did not trip (the user's Ctrl-C: simulated from a timer, with
    no report narrow enough to trip one) ends the solve and reaches the caller as a
    KeyboardInterrupt; spyrrow itself drops it. Python's own handler is back afterwards."""
    import _thread
    import signal
    reports = [(FEASIBLE[0], _Sol(3.0))]

    class Slow:   # as spyrrow: the signal ends its search, the error is dropped
        def solve(self, cfg, queue):
            try:
                for _ in range(20000):   # until the interrupt lands (at most 20 s)
                    time.sleep(0.001)
            except KeyboardInterrupt:
                pass
            return _Sol(9.0)
    timer = threading.Timer(0.05, _thread.interrupt_main)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        early_stop.solve_until(Slow(), None, _Queue(reports), FEASIBLE, 0.0)
    timer.join()
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_with_sigint_ignored_the_search_is_ended_and_a_sigint_from_outside_stays_ignored():
    """A process started in the background by a shell script (``cmd &``) has SIGINT ignored and
    Python installs no handler: the search is still ended at its first layout narrow enough;
    an OS SIGINT sent during a solve nothing trips is ignored, as the process asked (no
    KeyboardInterrupt, the solve runs to its end); SIGINT is ignored again afterwards."""
    import os
    import signal
    prior = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        assert early_stop.can_stop()
        items = _items(12, 1)
        sol, drained, ended = _solve(items, 4.0, 20.0, np.inf)
        assert ended and _disjoint(sol, items)
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        got = []

        class Slow:
            def solve(self, cfg, queue):
                for _ in range(300):   # 0.3 s at least: the signal lands at 0.05 s
                    time.sleep(0.001)
                got.append(True)
                return _Sol(9.0)
        timer = threading.Timer(0.05, os.kill, (os.getpid(), signal.SIGINT))
        timer.start()
        sol, drained, ended = early_stop.solve_until(
            Slow(), None, _Queue([(FEASIBLE[0], _Sol(3.0))]), FEASIBLE, 0.0)
        timer.join()
        assert got and not ended and sol.width == 9.0
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        time.sleep(0.01)
    finally:
        signal.signal(signal.SIGINT, prior)


def test_with_sigint_ignored_the_pack_still_nests_longer(monkeypatch):
    """The wavy discs below packed with SIGINT ignored (a background job): pack_islands asks
    square_layout for REACH as with Python's handler, the layout certified."""
    import signal
    k = 10
    V, F, uv, lab = _wavy_discs(k, 8)
    assert _reach(k, len(F), float(_shares(V, F, lab).max())) == REACH
    prior = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        check_reach_asked(monkeypatch, V, F, uv, lab, REACH)
    finally:
        signal.signal(signal.SIGINT, prior)


def test_where_it_applies_the_pack_nests_longer_ending_each_search_at_its_square(monkeypatch):
    """10 wavy discs of 240 faces (the cut, 0.6 s, below the root's 0.62 s; no chart over 0.3
    of the area, recomputed): pack_islands asks square_layout for REACH, each solve is asked to
    end at its square, and the layout is certified; with a time given, neither."""
    k = 10
    V, F, uv, lab = _wavy_discs(k, 8)
    share = float(_shares(V, F, lab).max())
    assert _reach(k, len(F), share) == REACH
    check_reach_asked(monkeypatch, V, F, uv, lab, REACH)


def test_on_a_worker_thread_the_pack_keeps_its_time(monkeypatch):
    """The same discs packed on a thread (Blender's operator, a Dask worker): the search could
    not be ended there, so pack_islands asks for no reach (it would run all of it)."""
    k = 10
    V, F, uv, lab = _wavy_discs(k, 8)
    assert _reach(k, len(F), float(_shares(V, F, lab).max())) == REACH
    check_no_reach_on_a_thread(monkeypatch, V, F, uv, lab)
