"""The compaction started on a spare core while a square-ending search goes on
(:mod:`bd_uv.packing.ahead`, issue 18, benchmarks/results/issue18-pack31-2026-11-29.md), and
that search run without spyrrow's compression phase (``square.SQUARE_COMPRESS``). These tests
check which layout is compacted, on which clock, and the layouts (certified by
``packing_checks.check_layout``), never the time taken."""
import threading
import time
from datetime import timedelta

import numpy as np
import pytest

import bd_uv.packing.ahead as ahead
from bd_uv.packing.ahead import Ahead
from bd_uv.packing.nest import Placement, nest
from packing_checks import check_layout
from test_pack_coarse import _shares, _wavy_discs


def _best(i):
    """A (Placement, side) pair told apart by ``i``."""
    return Placement(np.array([float(i)]), np.array([[i, 0.0]]), 1.0), 1.0 + i


class _Compactions:
    """A stand-in compaction: records each start (layout, clock), runs until cancelled or
    released, gives ('done', i) for the layout of index i."""

    def __init__(self):
        self.started, self.cancelled = [], []
        self.release = threading.Event()
        self.go = threading.Semaphore(0)

    def __call__(self, best, clock, cancel):
        i = int(best[0].angle[0])
        self.started.append((i, clock))
        self.go.release()
        while not (cancel.is_set() or self.release.is_set()):
            time.sleep(0.001)
        if cancel.is_set():
            self.cancelled.append(i)
        return ("done", i)


@pytest.fixture
def quiet0(monkeypatch):
    monkeypatch.setattr(ahead, "QUIET", 0.0)


def test_the_newest_layout_offered_is_compacted_and_kept_when_the_search_ends_on_it(quiet0):
    """Offered layout 0, then 1: the compaction of 0 is cancelled, 1 is compacted on the
    thread's CPU clock, and finish(1) gives its result (equal arrays are the same layout)."""
    c = _Compactions()
    a = Ahead(c)
    a.start_after(0.0)
    a.offer(_best(0))
    assert c.go.acquire(timeout=20)
    a.offer(_best(1))
    assert c.go.acquire(timeout=20)
    c.release.set()
    pl, side = _best(1)
    assert a.finish((Placement(pl.angle.copy(), pl.shift.copy(), pl.width), side)) == ("done", 1)
    assert [i for i, _ in c.started] == [0, 1] and c.cancelled == [0]
    assert all(clock is time.thread_time for _, clock in c.started)


def test_a_search_ending_on_another_layout_gets_nothing_and_stops_the_thread(quiet0):
    """Offered layout 0; the search ends on layout 2 (never offered: it came after the last
    drain): finish gives None (the caller compacts 2 itself) and 0's compaction is cancelled."""
    c = _Compactions()
    a = Ahead(c)
    a.start_after(0.0)
    a.offer(_best(0))
    assert c.go.acquire(timeout=20)
    assert a.finish(_best(2)) is None
    assert c.cancelled == [0]


@pytest.mark.parametrize("quiet, after", [(3600.0, 0.0), (0.0, None), (0.0, 3600.0)])
def test_a_layout_offered_before_its_time_is_compacted_at_the_end(monkeypatch, quiet, after):
    """A layout offered before the search's time is over (none given yet, or far off), or
    within the quiet time, has not started when the search ends on it: finish starts it at
    once and gives its result; cancel() stops a thread with none."""
    monkeypatch.setattr(ahead, "QUIET", quiet)
    c = _Compactions()
    c.release.set()
    a = Ahead(c)
    if after is not None:
        a.start_after(time.perf_counter() + after)
    a.offer(_best(0))
    a.offer(_best(1))
    time.sleep(0.05)   # (the thread waits: for the search's time, or the quiet time)
    assert a.finish(_best(1)) == ("done", 1)
    assert [i for i, _ in c.started] == [1]
    b = Ahead(c)
    b.offer(_best(3))
    b.cancel()
    assert [i for i, _ in c.started] == [1]


def test_a_compaction_failing_on_the_thread_is_left_to_the_caller(quiet0):
    """A compaction that raises on the thread: finish gives None (the caller compacts the layout
    itself and meets the error there, on its own thread); the thread has ended."""
    def broken(best, clock, cancel):
        raise ValueError("broken compaction")
    a = Ahead(broken)
    a.start_after(0.0)
    a.offer(_best(0))
    time.sleep(0.05)
    assert a.finish(_best(0)) is None
    assert not a._thread.is_alive()


def test_without_compression_the_search_asks_spyrrow_for_its_exploration_only(monkeypatch):
    """nest(compress=False): spyrrow's config gets the exploration's 4/5 of the time and no
    compression; by default 4/5 and 1/5. Both layouts keep every outline in the strip."""
    import spyrrow
    seen = []
    real = spyrrow.StripPackingConfig

    def config(*a, **kw):
        cfg = real(*a, **kw)
        seen.append(cfg)
        return cfg
    monkeypatch.setattr(spyrrow, "StripPackingConfig", config)
    square = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    from bd_uv.packing import PackOptions
    for compress, cmpr in ((False, 0.0), (True, 0.1)):
        seen.clear()
        pl = nest([square, 0.5 * square, 0.7 * square], 4.0, 0.1, PackOptions(seed=0), 0.5,
                  compress=compress)
        assert len(seen) == 1
        assert seen[0].exploration_time == timedelta(seconds=0.4)
        assert seen[0].compression_time == timedelta(seconds=cmpr)
        assert np.all(pl.shift[:, 1] >= 1.0 - 1e-6) and np.all(pl.shift[:, 1] <= 3.0 + 1e-6)


def test_the_reach_pack_compacts_on_the_thread_the_layout_it_keeps(monkeypatch):
    """10 wavy discs of 240 faces (the reach path, coarse outlines, recomputed in
    test_pack_reach): the square-ending search runs without compression and offers its better
    layouts; the layout the search ends with is compacted once, on the thread's clock when the
    thread had it (else on the process's), and the pack is certified."""
    import os

    import bd_uv.packing.square as square
    from bd_uv.packing import PackOptions, pack_islands
    if (os.cpu_count() or 1) <= square.SPARE_CORES:
        pytest.skip("one core: nothing is compacted ahead")
    V, F, uv, lab = _wavy_discs(10, 8)
    assert float(_shares(V, F, lab).max()) < 0.3
    asks, clocks, kept = [], [], []
    real_nest, real_compact = square.nest, square.compact_square
    monkeypatch.setattr(square, "nest", lambda *a, **kw: asks.append(
        (kw.get("compress"), kw.get("progress") is not None)) or real_nest(*a, **kw))
    monkeypatch.setattr(square, "compact_square", lambda *a, **kw: clocks.append(
        kw.get("clock")) or real_compact(*a, **kw))
    finish = Ahead.finish
    monkeypatch.setattr(Ahead, "finish", lambda self, best: kept.append(
        finish(self, best)) or kept[-1])
    options = PackOptions(seed=0)
    check_layout(V, F, uv, lab, pack_islands(V, F, uv, lab, options), options)
    assert asks[0] == (False, True)
    assert len(kept) == 1
    # the kept layout's compaction ran on the thread (and cancelled ones maybe before it), or
    # the search ended on a layout the thread did not have and it was compacted after it
    assert clocks[-1] is (time.thread_time if kept[0] is not None else time.process_time)
    assert all(c is time.thread_time for c in clocks[:-1])
    # with a time given (no reach): the compression phase, nothing ahead
    asks.clear()
    clocks.clear()
    kept.clear()
    options = PackOptions(seed=0, solve_seconds=0.3)
    check_layout(V, F, uv, lab, pack_islands(V, F, uv, lab, options), options)
    assert asks and all(a == (True, False) for a in asks)
    assert not kept and all(c is time.process_time for c in clocks)
