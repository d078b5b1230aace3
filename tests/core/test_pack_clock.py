"""``Packed.seconds`` is the packing: pack_islands imports the libraries it calls before it reads
its clock (issue 18, benchmarks/results/issue18-pack29-2026-11-29.md: rocker-arm's pack, the
first of a bench run, counted their first import). No test checks a time taken."""

import sys
import time as real_time

import bd_uv.packing.atlas as atlas
from bd_uv.packing import PackOptions, pack_islands
from packing_checks import check_layout
from test_pack_coarse import _wavy_discs


def test_the_clock_starts_once_the_libraries_are_imported(monkeypatch):
    """pack_islands imports spyrrow, shapely and scipy's parts before it reads its clock, so
    ``Packed.seconds`` leaves a first import in the process out."""
    order = []

    class Clock:
        @staticmethod
        def perf_counter():
            order.append("clock")
            return real_time.perf_counter()

    load = atlas._load_libraries
    monkeypatch.setattr(atlas, "_load_libraries", lambda: order.append("load") or load())
    monkeypatch.setattr(atlas, "time", Clock)
    V, F, uv, lab = _wavy_discs(3, 1)
    options = PackOptions(seed=0)
    check_layout(V, F, uv, lab, pack_islands(V, F, uv, lab, options), options)
    assert order[:2] == ["load", "clock"] and order.count("load") == 1
    for name in ("spyrrow", "shapely", "scipy.optimize", "scipy.fft", "scipy.spatial",
                 "scipy.sparse"):
        assert name in sys.modules
