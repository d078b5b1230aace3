"""``trim.keep_freed_heap``: below TRIM_FACES faces, the first unwrap of a process sets glibc's mmap
and trim thresholds where glibc's own rule leaves them after a large run (32 MB, 64 MB), once; a
small unwrap's arrays then come from the heap it freed, and a repeated call faults (almost) no
pages in (issue 21: 300-3,000 page faults a C = 5 call on 1-4k-face disks before). Measured on the third
call: the second may still grow the heap to the call's peak. The page faults are the
kernel's count (``getrusage``'s ``ru_minflt``), in a child process of glibc's defaults."""
import os
import subprocess
import sys

import pytest

from bd_uv import trim


def test_the_thresholds_are_set_once_below_trim_faces_and_not_during_a_large_search(monkeypatch):
    calls = []
    monkeypatch.setattr(trim, "_mallopt", lambda p, v: calls.append((p, v)))
    monkeypatch.setattr(trim, "_kept", False)
    trim.keep_freed_heap(trim.TRIM_FACES)               # large work: its own thresholds
    assert calls == []
    with trim.large_blocks_mapped(trim.TRIM_FACES):
        del calls[:]
        trim.keep_freed_heap(100)                       # a large search holds them: not now
        assert calls == [] and not trim._kept
    del calls[:]
    trim.keep_freed_heap(100)
    trim.keep_freed_heap(200)
    assert calls == [(-3, 32 * 2**20), (-1, 64 * 2**20)] and trim._kept


CHILD = """if True:
    import hashlib, resource, sys
    import numpy as np
    sys.path.insert(0, {tests!r})
    import bd_uv
    from helpers import load_off, rings
    if {off}:
        sys.modules["bd_uv.unwrapping.unwrap"].keep_freed_heap = lambda faces: None
    V, F = rings(*load_off("three_peaks.off"), 2481, 1000)
    first = bd_uv.unwrap(V, F, bound=5.0)
    bd_uv.unwrap(V, F, bound=5.0)                       # the heap grown to the call's peak
    r0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    again = bd_uv.unwrap(V, F, bound=5.0)
    faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - r0
    assert np.array_equal(first.corner_uv, again.corner_uv)
    print(faults, hashlib.md5(first.corner_uv.tobytes()).hexdigest())
"""


def _child(off):
    here = os.path.dirname(os.path.abspath(__file__))
    env = {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_")}
    env.pop("GLIBC_TUNABLES", None)
    out = subprocess.run([sys.executable, "-c", CHILD.format(tests=here, off=off)],
                         capture_output=True, text=True, check=True, env=env).stdout.split()
    return int(out[0]), out[1]


def test_a_repeated_small_unwrap_faults_no_pages_in_and_maps_the_same():
    import ctypes.util
    if not sys.platform.startswith("linux") or "libc" not in (ctypes.util.find_library("c") or ""):
        pytest.skip("glibc only")
    before, uv_before = _child(True)
    if before < 100:
        pytest.skip(f"this allocator kept the freed memory itself ({before} page faults)")
    after, uv_after = _child(False)
    # ~0 on this machine; a CI venv's run gave 52 against 1,313 (its interpreter's own arrays):
    # the call's pages are no longer faulted in again, a few of the process's may be
    assert after <= max(20, before // 10), (before, after)
    assert uv_after == uv_before
