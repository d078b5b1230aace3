"""The paths that make ``seams="auto"`` faster must not change what it certifies.

- ``solvers.threads``: blocks factored side by side give each block's own result, in order
  (``map_queue``: two at a time at most, a large one alone);
- ``chart_maps`` of two runs of charts (threads) equals the one-system solve;
- ``unwrap_islands`` with the search's known conformal maps certifies what ``unwrap`` certifies,
  and a wrong "known" map is not trusted: the UVs written are certified from scratch here;
- ``boundary_crossings`` (box pre-test, later edges only) counts what a pair-by-pair test counts,
  and ``cut_graph``'s percentile and compressed rows are numpy's and scipy's.
"""
import importlib
import os
import subprocess
import sys

import numpy as np
import pytest

from bd_uv.mesh import islands
from bd_uv.seams import unwrap_auto
from bd_uv.seams import charts as charts_mod
from bd_uv.seams import crossings
from bd_uv.seams.edges import edge_table
from bd_uv.seams.topology import charts
from bd_uv.solvers import threads
from bd_uv.options import UnwrapOptions
from bd_uv.unwrapping.unwrap import pin_arrays, unwrap, unwrap_islands
from helpers import reference_distortion
from seams_helpers import face_singular_values, sphere_cut, torus, uv_sphere


def test_map_blocks_keeps_order_and_each_result(monkeypatch):
    monkeypatch.setenv("BD_UV_THREADS", "2")
    out = threads.map_blocks(lambda x: x * x, range(7))
    assert out == [x * x for x in range(7)]
    monkeypatch.setenv("BD_UV_THREADS", "1")
    assert threads.map_blocks(lambda x: -x, [3, 4]) == [-3, -4]


def test_map_blocks_raises_after_every_block_finished(monkeypatch):
    monkeypatch.setenv("BD_UV_THREADS", "2")
    finished = []

    def work(x):
        if x == 0:
            raise ValueError("block 0")
        finished.append(x)
        return x
    with pytest.raises(ValueError, match="block 0"):
        threads.map_blocks(work, [0, 1, 2])
    assert sorted(finished) == [1, 2]


def test_map_queue_keeps_order_two_at_most_and_alone_items_alone(monkeypatch):
    """Every item's own result in order; never more than two at once, an ``alone`` item with
    nothing beside it; an item starts when one of the two running ends, not when both have:
    item 0 waits for item 3 to start (pairs would start 2 and 3 only after 0 ended). Recorded
    from the calls."""
    import threading
    monkeypatch.setenv("BD_UV_THREADS", "2")
    lock = threading.Lock()
    third = threading.Event()
    running, events, waited = set(), [], []

    def work(x):
        with lock:
            running.add(x)
            events.append((x, frozenset(running)))
        if x == 3:
            third.set()
        if x == 0:
            waited.append(third.wait(timeout=30))
        with lock:
            running.discard(x)
        return 10 * x
    alone = [False, False, False, False, True, False, False]
    assert threads.map_queue(work, range(7), alone) == [10 * x for x in range(7)]
    assert waited == [True]
    assert [x for x, _ in events] == list(range(7))                 # started in order
    seen = dict(events)
    assert max(len(s) for s in seen.values()) <= 2
    assert seen[4] == {4} and all(4 not in s for x, s in seen.items() if x != 4)
    assert 0 in seen[2] and 0 in seen[3]                            # beside the long item 0
    monkeypatch.setenv("BD_UV_THREADS", "1")
    assert threads.map_queue(lambda x: -x, [3, 4], [False, True]) == [-3, -4]


def test_map_queue_raises_after_every_started_item_finished(monkeypatch):
    import threading
    monkeypatch.setenv("BD_UV_THREADS", "2")
    failed = threading.Event()
    finished = []

    def work(x):
        if x == 1:
            failed.set()
            raise ValueError("item 1")
        failed.wait(timeout=30)             # item 0 ends after item 1 has raised
        finished.append(x)
        return x
    with pytest.raises(ValueError, match="item 1"):
        threads.map_queue(work, range(6), [False] * 6)
    # item 0 ran to its end before the error came out (at most an item or two more started
    # in the moment between item 1's raise and its lane recording it)
    assert finished[:1] == [0] and 1 not in finished and len(finished) < 5


def test_halves_balances_work_and_refuses_small_or_single(monkeypatch):
    monkeypatch.setenv("BD_UV_THREADS", "2")
    assert threads.halves([5, 5, 5, 5], least=1) == 2
    j = threads.halves([100, 1, 1, 98], least=10)
    assert j in (1, 2) and min(sum([100, 1, 1, 98][:j]), sum([100, 1, 1, 98][j:])) >= 98
    assert threads.halves([100, 3], least=10) is None      # the smaller run is too small
    assert threads.halves([100], least=1) is None
    monkeypatch.setenv("BD_UV_THREADS", "1")
    assert threads.halves([5, 5, 5, 5], least=1) is None


def _sphere_charts():
    """The disk charts ``seams='auto'`` makes of a 32x16 UV sphere."""
    V, F, E, cut = sphere_cut()
    chs = [c for c in charts(F, E, cut) if c.kind == "disk"]
    assert len(chs) >= 2
    return V, F, chs


def test_chart_maps_in_two_threads_equal_one_system(monkeypatch):
    V, F, chs = _sphere_charts()
    monkeypatch.setenv("BD_UV_THREADS", "1")
    one = charts_mod.chart_maps(V, chs)
    monkeypatch.setenv("BD_UV_THREADS", "2")
    monkeypatch.setattr(charts_mod, "PARALLEL_VERTICES", 1)
    assert threads.halves([len(c.vertices) for c in chs], 1) is not None
    two = charts_mod.chart_maps(V, chs)
    np.testing.assert_allclose(two.u, one.u, atol=1e-9)
    np.testing.assert_allclose(two.max_stretch, one.max_stretch, rtol=1e-9)
    np.testing.assert_allclose(two.mean_distortion, one.mean_distortion, rtol=1e-9)
    # And with the mesh's face geometry computed once (the search's path).
    three = charts_mod.chart_maps(V, chs, charts_mod.face_geometry(V, F))
    np.testing.assert_allclose(three.u, one.u, atol=1e-9)
    # A batch above SEQUENTIAL_VERTICES factors its two runs one after the other: each run's
    # map is its own, so the same maps bit for bit as side by side.
    monkeypatch.setattr(charts_mod, "SEQUENTIAL_VERTICES", 0)
    four = charts_mod.chart_maps(V, chs)
    np.testing.assert_array_equal(four.u, two.u)
    np.testing.assert_array_equal(four.max_stretch, two.max_stretch)


def test_release_memory_trims_only_large_work(monkeypatch):
    """``trim.release_memory`` calls ``malloc_trim(0)`` from TRIM_FACES faces on, never below."""
    from bd_uv import trim
    calls = []
    monkeypatch.setattr(trim, "_trim", calls.append)
    trim.release_memory(trim.TRIM_FACES - 1)
    assert calls == []
    trim.release_memory(trim.TRIM_FACES)
    assert calls == [0]


# the child processes' start: numpy, bd_uv's trim and the resident set size in MB
RSS_PRELUDE = """if True:
        import numpy as np
        from bd_uv import trim
        def rss():
            with open("/proc/self/statm") as f:
                return int(f.read().split()[1]) * 4096 / 2**20"""


def _glibc_defaults():
    """This environment without glibc's ``MALLOC_*`` tunables: any of them turns glibc's
    dynamic mmap threshold off, and dask.distributed sets ``MALLOC_TRIM_THRESHOLD_`` in the
    process that starts a local cluster (the batch's tests), so inside the whole suite these
    tests' children kept no freed memory and the tests skipped."""
    return {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_")}


def _glibc_or_skip():
    import ctypes.util
    if not sys.platform.startswith("linux") or "libc" not in (ctypes.util.find_library("c") or ""):
        pytest.skip("glibc only")


def test_release_memory_hands_freed_heap_back():
    """On glibc, heap memory numpy freed (after glibc raised its mmap threshold) stays resident
    until ``release_memory``; after it, the resident set is back near where it started."""
    _glibc_or_skip()
    code = RSS_PRELUDE + """
        big = np.ones(16 * 2**17); del big     # a freed 16 MB map raises the mmap threshold
        base = rss()
        held = [np.ones(2**17) for _ in range(100)]   # 100 MB in 1 MB arrays, from the heap
        last = np.ones(2**17)                  # keeps the heap's top in use
        del held
        freed = rss()
        trim.release_memory(trim.TRIM_FACES)
        print(base, freed, rss())
    """
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env=_glibc_defaults()).stdout.split()
    base, freed, after = map(float, out)
    if freed - base < 50:
        pytest.skip(f"this allocator returned the memory itself ({base:.0f} -> {freed:.0f} MB)")
    assert after - base < 0.2 * (freed - base), (base, freed, after)


def _islands_of(V, F, E, cut):
    isl = islands(V, F, E.ends[cut])
    chs = charts(F, E, cut)
    # The charts are the islands mesh.islands finds, numbered and ordered alike.
    assert [c.faces.tolist() for c in chs] == [i.faces.tolist() for i in isl]
    assert [c.vertices.tolist() for c in chs] == [i.vertices.tolist() for i in isl]
    return isl, chs


def _certify(V, F, res, C):
    """0 flips, max <= C from the stored corner UVs (numpy SVD), every face mapped."""
    assert np.all(np.isfinite(res.corner_uv))
    D, flipped = reference_distortion(V, F, res.corner_uv)
    _, s2, _ = face_singular_values(V, F, res.corner_uv)
    assert not flipped.any() and np.all(s2 > 0), "a flipped or degenerate face"
    assert D.max() <= C * (1 + 1e-9)
    return D


# unwrap_islands' options after the islands and pins.
OPTIONS = UnwrapOptions(method="lscm", bound=2.0, frames="auto", raise_bound=False, overlap="fail")


def _torus_charts():
    """A torus cut by seams='auto': its mesh, edge table, cut, islands and chart maps."""
    V, F, _, _ = torus(nu=24, nv=10)
    _, added, _ = unwrap_auto(V, F, bound=2.0, stretch=2.0)
    E = edge_table(V, F)
    cut = np.zeros(len(E.ends), dtype=bool)
    k = E.keys(added, len(V))
    cut[k[k >= 0]] = True
    isl, chs = _islands_of(V, F, E, cut)
    return V, F, E, cut, isl, charts_mod.chart_maps(V, chs)


def test_known_maps_certify_what_unwrap_certifies():
    V, F, E, cut, isl, cm = _torus_charts()
    known = {j: cm.u[cm.voff[j]:cm.voff[j + 1]] for j in range(len(isl))}
    fast = unwrap_islands(V, F, isl, pin_arrays(None, None, len(F)), OPTIONS, conformal=known)
    ref = unwrap(V, F, seams=E.ends[cut], bound=2.0, raise_bound=False, overlap="fail")
    assert fast.certified and ref.certified
    Df, Dr = _certify(V, F, fast, 2.0), _certify(V, F, ref, 2.0)
    np.testing.assert_allclose(Df, Dr, rtol=1e-7)
    assert all(r.overlap_free for r in fast.islands)


def test_a_wrong_known_map_is_not_trusted():
    V, F, E, cut, isl, cm = _torus_charts()
    # Mirrored maps: every face flipped. They must be replaced, never written as they are.
    known = {j: np.conj(cm.u[cm.voff[j]:cm.voff[j + 1]]) for j in range(len(isl))}
    res = unwrap_islands(V, F, isl, pin_arrays(None, None, len(F)), OPTIONS, conformal=known)
    for r in res.islands:
        if r.status == "certified":
            _certify(V, F[r.faces], type("R", (), {"corner_uv": res.corner_uv[r.faces]}), 2.0)
        else:
            assert np.all(np.isnan(res.corner_uv[r.faces]))
    assert any(r.status == "certified" for r in res.islands)


def test_fan_runs_give_the_graph_search_cut_mesh_and_charts():
    """Cut vertices read off the fans (no graph search) equal the corner graph's components,
    numbering and chart order included, for random cuts and face subsets of closed, open and
    genus-1 meshes; a mesh that is not an oriented manifold has no fans."""
    import dataclasses
    from bd_uv.seams.topology import cut_mesh
    rng = np.random.default_rng(7)
    Vt, Ft, _, _ = torus(nu=20, nv=8)
    Vs, Fs, _ = uv_sphere(12, 6)
    Vo, Fo = Vs, Fs[Vs[Fs].mean(axis=1)[:, 2] < 0.5]      # an open cap (boundary fans)
    for V, F in ((Vt, Ft), (Vs, Fs), (Vo, Fo)):
        E = edge_table(V, F)
        assert E.fans is not None
        E0 = dataclasses.replace(E, fans=None)
        for trial in range(12):
            cut = rng.random(len(E.ends)) < (0.0, 0.05, 0.3, 0.8)[trial % 4]
            faces = None if trial % 3 == 0 else np.sort(
                rng.choice(len(F), int(rng.integers(1, len(F))), replace=False))
            a, b = cut_mesh(F, E, cut, faces), cut_mesh(F, E0, cut, faces)
            assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
            ca, cb = charts(F, E, cut, faces), charts(F, E0, cut, faces)
            assert [(c.faces.tolist(), c.vertices.tolist(), c.tris.tolist(), c.kind,
                     [lp.tolist() for lp in c.loops]) for c in ca] == \
                [(c.faces.tolist(), c.vertices.tolist(), c.tris.tolist(), c.kind,
                  [lp.tolist() for lp in c.loops]) for c in cb]
    # Two faces running their shared edge the same way: not oriented, no fans.
    F2 = np.array([[0, 1, 2], [0, 1, 3]])
    V2 = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0.1]], dtype=float)
    assert edge_table(V2, F2).fans is None


def test_boundary_crossings_all_pairs_equals_the_grid(monkeypatch):
    """Short loops test every pair of their edges; the count equals the grid's (random star
    loops, some self-crossing, some random polygons), and a bow-tie counts 1."""
    rng = np.random.default_rng(1)
    for _ in range(120):
        loops, pts, off = [], [], 0
        for _ in range(int(rng.integers(1, 5))):
            L = int(rng.integers(3, 50))
            t = np.sort(rng.random(L)) * 2 * np.pi
            z = (1 + rng.random(L) * rng.choice([0.0, 0.3, 1.5])) * np.exp(1j * t)
            if rng.random() < 0.2:
                z = rng.random(L) + 1j * rng.random(L)
            pts.append(z)
            loops.append(np.arange(off, off + L))
            off += L
        uv = np.concatenate(pts)
        monkeypatch.setattr(crossings, "ALL_PAIRS", 10 ** 9)
        every = crossings.boundary_crossings(uv, loops)
        monkeypatch.setattr(crossings, "ALL_PAIRS", -1)
        grid = crossings.boundary_crossings(uv, loops)
        assert np.array_equal(every, grid)
    bowtie = np.array([0, 1 + 1j, 1, 1j])      # edges 0 and 2 cross at (0.5, 0.5)
    monkeypatch.setattr(crossings, "ALL_PAIRS", 10 ** 9)
    assert crossings.boundary_crossings(bowtie, [np.arange(4)]).tolist() == [1]


def _crossing_pairs_brute(uv, loop):
    """Pairs of non-adjacent edges of a closed loop that meet (touching counts), by the
    textbook closed-segment test (orientations, then an endpoint on the other segment) on
    every pair: the reference for ``boundary_crossings``."""
    L = len(loop)
    pts = [complex(uv[v]) for v in loop]

    def orient(a, b, c):
        return (b.real - a.real) * (c.imag - a.imag) - (b.imag - a.imag) * (c.real - a.real)

    def on(a, b, c):                        # c, on the line ab, within the segment
        return (min(a.real, b.real) <= c.real <= max(a.real, b.real)
                and min(a.imag, b.imag) <= c.imag <= max(a.imag, b.imag))

    count = 0
    for i in range(L):
        for j in range(i + 1, L):
            if j == i + 1 or (i == 0 and j == L - 1):
                continue                    # edges sharing a corner
            p1, q1, p2, q2 = pts[i], pts[(i + 1) % L], pts[j], pts[(j + 1) % L]
            d1, d2 = orient(p2, q2, p1), orient(p2, q2, q1)
            d3, d4 = orient(p1, q1, p2), orient(p1, q1, q2)
            count += bool((d1 * d2 < 0 and d3 * d4 < 0)
                          or (d1 == 0 and on(p2, q2, p1)) or (d2 == 0 and on(p2, q2, q1))
                          or (d3 == 0 and on(p1, q1, p2)) or (d4 == 0 and on(p1, q1, q2)))
    return count


def test_boundary_crossings_count_what_every_pair_test_counts(monkeypatch):
    """Both of ``boundary_crossings``' paths (every later edge of the loop; grid cells), with
    their bounding-box pre-test, count what a pair-by-pair orientation test counts, on loops
    with integer corners (exact arithmetic: crossings, touching corners, collinear overlaps)."""
    rng = np.random.default_rng(7)
    for _ in range(60):
        loops, pts, off = [], [], 0
        for _ in range(int(rng.integers(1, 4))):
            L = int(rng.integers(3, 25))
            z = rng.integers(0, 6, L) + 1j * rng.integers(0, 6, L)
            pts.append(z.astype(np.complex128))
            loops.append(np.arange(off, off + L))
            off += L
        uv = np.concatenate(pts)
        want = [_crossing_pairs_brute(uv, lp) for lp in loops]
        for limit in (10 ** 9, -1):
            monkeypatch.setattr(crossings, "ALL_PAIRS", limit)
            assert crossings.boundary_crossings(uv, loops).tolist() == want


def test_cut_graph_helpers_equal_numpy_and_scipy():
    """``cut_graph``'s percentile and compressed rows are numpy's and scipy's to the bit."""
    import scipy.sparse as sp
    cg = importlib.import_module("bd_uv.seams.cut_graph")
    rng = np.random.default_rng(3)
    for _ in range(2000):
        x = rng.random(int(rng.integers(1, 200))) * 10.0 ** rng.uniform(-6, 6)
        if rng.random() < 0.3:
            x = np.round(x, 1)
        assert cg._percentile10(x) == float(np.percentile(x, 10))
    for _ in range(50):
        n = int(rng.integers(1, 40))
        k = int(rng.integers(0, 120))
        r, c = rng.integers(0, n, k), rng.integers(0, n, k)
        v = rng.random(k)
        got = cg._csr(v, r, c, n)
        want = sp.csr_matrix(sp.coo_array((v, (r, c)), shape=(n, n)))
        want.sum_duplicates()
        assert np.array_equal(got.indptr, want.indptr)
        assert np.array_equal(got.indices, want.indices)
        assert np.allclose(got.data, want.data, rtol=1e-15, atol=0)


def test_search_holds_the_callers_arrays_read_only_and_centroids_per_split():
    """``check_arrays(share=True)`` (the seam search) hands back the caller's float64 / int64
    arrays as read-only views (writing raises, nothing is copied), converts any other dtype
    as before; ``FaceCentroids`` gives the rows of ``V[F].mean(axis=1)`` bit for bit."""
    from bd_uv.mesh import check_arrays
    from bd_uv.seams.bisect import FaceCentroids
    V, F = torus(nu=12, nv=8)[:2]
    V, F = np.asarray(V, np.float64), np.asarray(F, np.int64)
    Vs, Fs = check_arrays(V, F, share=True)
    assert np.shares_memory(Vs, V) and np.shares_memory(Fs, F)
    assert not Vs.flags.writeable and not Fs.flags.writeable and V.flags.writeable
    with pytest.raises(ValueError):
        Vs[0, 0] = 1.0
    V32, F32 = check_arrays(V.astype(np.float32), F.astype(np.int32), share=True)
    assert V32.dtype == np.float64 and F32.dtype == np.int64 and V32.flags.writeable
    Vc, Fc = check_arrays(V, F)
    assert not np.shares_memory(Vc, V) and not np.shares_memory(Fc, F)
    rows = np.array([5, 0, len(F) - 1, 17])
    whole = V[F].mean(axis=1)
    np.testing.assert_array_equal(FaceCentroids(V, F)[rows], whole[rows])


def test_large_blocks_mapped_only_for_large_work_and_restored_once(monkeypatch):
    """``trim.large_blocks_mapped`` sets glibc's thresholds from TRIM_FACES faces on (never
    below), once for nested blocks, and leaves them where glibc's own rule ends (32 MB, 64 MB)."""
    from bd_uv import trim
    calls = []
    monkeypatch.setattr(trim, "_mallopt", lambda p, v: calls.append((p, v)))
    with trim.large_blocks_mapped(trim.TRIM_FACES - 1):
        pass
    assert calls == []
    with trim.large_blocks_mapped(trim.TRIM_FACES):
        with trim.large_blocks_mapped(10 * trim.TRIM_FACES):
            assert calls == [(-3, trim.MAP_BYTES), (-1, 128 * 1024)]
        assert len(calls) == 2
    assert calls[2:] == [(-3, 32 * 2**20), (-1, 64 * 2**20)]


def test_large_blocks_mapped_returns_freed_arrays_at_once():
    """On glibc, inside ``large_blocks_mapped`` the arrays numpy frees leave the resident set at
    their free, where outside (after glibc raised its mmap threshold) they stay resident."""
    _glibc_or_skip()
    code = RSS_PRELUDE + """
        def churn():
            base = rss()
            held = [np.ones(2**20) for _ in range(13)]   # 104 MB in 8 MB arrays (>= MAP_BYTES)
            last = np.ones(2**20)                  # keeps the heap's top in use
            del held
            return rss() - base, last
        big = np.ones(2**21); del big          # a freed 16 MB map raises the mmap threshold
        outside = churn()[0]
        trim.release_memory(trim.TRIM_FACES)
        with trim.large_blocks_mapped(trim.TRIM_FACES):
            inside = churn()[0]
        print(outside, inside)
    """
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env=_glibc_defaults()).stdout.split()
    outside, inside = map(float, out)
    if outside < 50:
        pytest.skip(f"this allocator returned the memory itself ({outside:.0f} MB kept)")
    assert inside < 10, (outside, inside)


def test_fiedler_vectors_in_bounded_runs_are_each_charts_own(monkeypatch):
    """A batch above ``SEQUENTIAL_NODES`` nodes is factored in runs of charts of at most
    ``RUN_NODES`` nodes (a larger chart alone), two at a time: each chart's vector is the
    one it gets alone (recomputed here chart by chart)."""
    from bd_uv.seams import fiedler
    sizes = [(6, 9), (4, 5), (8, 8), (3, 12), (7, 6), (5, 5)]
    pairs, cen, off = [], [], [0]
    for a, b in sizes:
        i = np.arange(a * b).reshape(a, b) + off[-1]
        pairs += [np.stack([i[:, :-1].ravel(), i[:, 1:].ravel()], 1),
                  np.stack([i[:-1].ravel(), i[1:].ravel()], 1)]
        y, x = np.mgrid[0:a, 0:b]
        cen.append(np.stack([x.ravel(), 1.3 * y.ravel(), 0.1 * (x * y).ravel()], 1))
        off.append(off[-1] + a * b)
    pairs, cen, off = np.concatenate(pairs), np.concatenate(cen).astype(float), np.array(off)
    k = off[-1]
    w = 1.0 + 0.01 * (np.arange(len(pairs)) % 7)
    mass = 1.0 + 0.1 * (np.arange(k) % 3)
    group = np.repeat(np.arange(len(sizes)), np.diff(off))
    alone = []
    for j in range(len(sizes)):
        sel = group[pairs[:, 0]] == j
        lo, hi = off[j], off[j + 1]
        alone.append(fiedler._fiedler_block(pairs[sel] - lo, w[sel], mass[lo:hi], cen[lo:hi],
                                            np.array([0, hi - lo]), np.zeros(hi - lo, int)))
    blocks = []
    real = fiedler._fiedler_block

    def spy(pairs_, w_, mass_, *a, **kw):
        blocks.append(len(mass_))
        return real(pairs_, w_, mass_, *a, **kw)
    monkeypatch.setattr(fiedler, "_fiedler_block", spy)
    monkeypatch.setattr(fiedler, "SEQUENTIAL_NODES", 10)
    monkeypatch.setattr(fiedler, "RUN_NODES", 80)
    for n in ("1", "2"):
        monkeypatch.setenv("BD_UV_THREADS", n)
        blocks.clear()
        x = fiedler.fiedler_vectors(pairs, w, mass, cen, off, group)
        # runs: 54+20 | 64 | 36+42 | 25 nodes, none above 80
        assert sorted(blocks) == [25, 64, 74, 78]
        np.testing.assert_allclose(x, np.concatenate(alone), rtol=0, atol=1e-9)


def test_edge_table_edges_and_fans_equal_numpys_sorts():
    # ``edge_table`` finds the edges (np.unique of the vertex pair keys), each edge's faces (a
    # stable argsort of the corners by edge) and the fans' order (a lexsort by fan start and
    # rank) by radix passes: recomputed here with numpy's own on a torus, a UV sphere and an
    # open cap, array for array.
    Vt, Ft, _, _ = torus(nu=24, nv=10)
    Vs, Fs, _ = uv_sphere(14, 7)
    Vo, Fo = Vs, Fs[Vs[Fs].mean(axis=1)[:, 2] < 0.5]
    for V, F in ((Vt, Ft), (Vs, Fs), (Vo, Fo)):
        E = edge_table(V, F)
        n = len(V)
        a, b = F.ravel(), np.roll(F, -1, axis=1).ravel()
        uniq, inv = np.unique(np.minimum(a, b) * n + np.maximum(a, b), return_inverse=True)
        inv = inv.ravel()
        assert np.array_equal(E.ends, np.stack([uniq // n, uniq % n], 1))
        assert np.array_equal(E.face_edges.ravel(), inv)
        order = inv.argsort(kind="stable")
        first = inv[order].searchsorted(np.arange(len(uniq)))
        assert np.array_equal(E.faces[:, 0], order[first] // 3)
        two = np.bincount(inv) == 2
        assert np.array_equal(E.faces[two, 1], order[first[two] + 1] // 3)
        assert (E.faces[~two, 1] == -1).all()
        # Each fan listed from its start, in turn: corner order[i + 1] is where order[i] turns
        # (``next``), the fans by their start corner, as a lexsort by (start, rank) lists them.
        fans = E.fans
        assert fans is not None
        o, start = fans.order, fans.starts
        for s, e in zip(start[:-1].tolist(), start[1:].tolist()):
            fan = o[s:e]
            assert (fans.next[fan[:-1]] == fan[1:]).all()
            assert (F.ravel()[fan] == F.ravel()[fan[0]]).all()
        firsts = o[start[:-1]]
        ring = fans.ring[start[:-1]]
        # a closed fan starts at its least corner; an open one where the boundary does (no
        # corner turns to it)
        prev = np.full(3 * len(F), -1)
        on = fans.next >= 0
        prev[fans.next[on]] = np.flatnonzero(on)
        for c, closed, s, e in zip(firsts.tolist(), ring.tolist(), start[:-1].tolist(),
                                   start[1:].tolist()):
            assert c == (o[s:e].min() if closed else c) and (closed or prev[c] < 0)
        assert np.array_equal(np.sort(o), np.arange(3 * len(F)))
        assert (np.diff(firsts) > 0).all()      # the fans by their start corner
