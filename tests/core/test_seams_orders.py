"""Elimination orders reused by the seam search (``seams.orders``, ``solvers.ordered_ldl``) must
solve what qdldl's own order solves.

- ``ordered_ldl.Factor`` solves an LSCM system in any order to scipy's solution, and counts the
  entries of its factor as a dense Cholesky factor of the permuted matrix has them;
- ``Orders``: fresh charts get keys from AMD, a piece keeps its chart's keys, a union puts the
  vertices where its charts meet after every other vertex of it;
- ``chart_maps`` with orders (reused, refused and ordered afresh) gives qdldl's maps, and
  ``unwrap_auto`` the same seams with orders as without.
"""
import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from bd_uv.seams import unwrap_auto
from bd_uv.seams import charts as charts_mod
from bd_uv.seams import orders as orders_mod
from bd_uv.seams.bisect import FaceCentroids, bisect
from bd_uv.seams.edges import edge_table
from bd_uv.seams.topology import charts
from bd_uv.solvers import ordered_ldl
from bd_uv.solvers.lscm import Upper, _lscm_system, face_geometry
from seams_helpers import sphere_cut, uv_sphere
from qdldl_marks import needs_ordered_ldl

pytestmark = needs_ordered_ldl


def _bumpy_disk(k=7):
    """A k x k grid, heights from a fixed random field, two triangles a cell."""
    rng = np.random.default_rng(3)
    x, y = np.meshgrid(np.arange(k, dtype=float), np.arange(k, dtype=float), indexing="ij")
    V = np.stack([x.ravel(), y.ravel(), 0.3 * rng.standard_normal(k * k)], 1)
    i = np.arange(k * k).reshape(k, k)
    a, b, c, d = i[:-1, :-1], i[1:, :-1], i[1:, 1:], i[:-1, 1:]
    F = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3),
                        np.stack([a, c, d], -1).reshape(-1, 3)])
    return V, F


def _system(V, F):
    g = face_geometry(V, F)
    return _lscm_system(g.cbw(), g.cb, F, len(V), np.array([0, len(V) - 1]),
                        np.array([0.0, 1.0], np.complex128))


def _dense_fill(U, perm):
    """Entries below the diagonal of the Cholesky factor of P A P^T (A from its upper triangle),
    values replaced by random ones on a dominant diagonal: no cancellation."""
    n = U.shape[0]
    M = sp.triu(U, 1).tocoo()
    rng = np.random.default_rng(0)
    D = np.zeros((n, n))
    D[M.row, M.col] = D[M.col, M.row] = rng.uniform(0.1, 1.0, M.nnz)
    D[np.arange(n), np.arange(n)] = n
    L = np.linalg.cholesky(D[np.ix_(perm, perm)])
    return int(np.count_nonzero(np.tril(np.abs(L) > 1e-300, -1)))


def test_factor_solves_in_any_order_with_the_fill_its_etree_counts():
    V, F = _bumpy_disk()
    U, rhs, _, free = _system(V, F)
    n = U.shape[0]
    full = (U + sp.triu(U, 1).T).tocsc()
    want = spla.spsolve(full, rhs)
    cols = np.repeat(np.arange(n), np.diff(U.indptr))
    nf = len(free)
    amd = ordered_ldl.amd(U.indptr[:nf + 1], U.indices[:U.indptr[nf]], nf)
    assert np.array_equal(np.sort(amd), np.arange(nf))
    inter = np.argsort(np.concatenate([2 * np.argsort(amd), 2 * np.argsort(amd) + 1]),
                       kind="stable")
    for perm in (np.arange(n), np.random.default_rng(1).permutation(n), inter):
        f = ordered_ldl.Factor(U.indices.astype(np.int64), cols, U.data, n, perm)
        assert f.lnz == _dense_fill(U, perm)
        assert f.factor()
        np.testing.assert_allclose(f.solve(rhs), want, rtol=1e-9, atol=1e-12)
    # The vertex graph's AMD, u and v side by side, fills less than the natural order.
    natural = ordered_ldl.Factor(U.indices.astype(np.int64), cols, U.data, n, np.arange(n))
    ordered = ordered_ldl.Factor(U.indices.astype(np.int64), cols, U.data, n, inter)
    assert ordered.lnz < natural.lnz


def test_the_system_as_triplets_is_its_csc_and_factors_to_the_same_bits():
    """``_lscm_system(triplets=True)``: the same entries as its csc matrix, in no order;
    ``ordered_solver`` factors them as they come, to the bits of the sorted entries (in any
    triplet order), and compresses them itself where it refuses the order (AMD afresh)."""
    V, F = _bumpy_disk()
    U, rhs, _, free = _system(V, F)
    g = face_geometry(V, F)
    T, rhs2, _, free2 = _lscm_system(g.cbw(), g.cb, F, len(V), np.array([0, len(V) - 1]),
                                     np.array([0.0, 1.0], np.complex128), triplets=True)
    n = U.shape[0]
    assert T.n == n and np.array_equal(rhs, rhs2) and np.array_equal(free, free2)
    assert len(T.rows) == U.nnz and np.all(T.rows <= T.cols)
    dense = np.zeros((n, n))
    dense[T.rows, T.cols] = T.vals
    assert np.array_equal(dense, U.toarray())
    C = T.csc()
    assert np.array_equal(C.indptr, U.indptr) and np.array_equal(C.indices, U.indices)
    assert np.array_equal(C.data, U.data)
    keys = np.random.default_rng(2).permutation(len(free))
    sorted_ = Upper(U.indices.astype(np.int64),
                                    np.repeat(np.arange(n), np.diff(U.indptr)), U.data, n)
    p = np.random.default_rng(3).permutation(len(T.rows))
    shuffled = Upper(T.rows[p], T.cols[p], T.vals[p], n)
    want = spla.spsolve((U + sp.triu(U, 1).T).tocsc(), rhs)
    xs = []
    for A in (sorted_, T, shuffled):
        solve, fill, rank = orders_mod.ordered_solver(A, keys, 0.0)
        assert fill > 0 and rank is None
        xs.append(solve(rhs))
    assert all(np.array_equal(x, xs[0]) for x in xs)
    np.testing.assert_allclose(xs[0], want, rtol=1e-9, atol=1e-12)
    # A budget no order meets: refused, ordered afresh by AMD of the u block, still solved.
    solve, fill, rank = orders_mod.ordered_solver(shuffled, keys, 1e-9)
    assert rank is not None and np.array_equal(np.sort(rank), np.arange(len(free)))
    np.testing.assert_allclose(solve(rhs), want, rtol=1e-9, atol=1e-12)


def test_a_zero_pivot_is_refused():
    # [[0, 1], [1, 2]] by its upper triangle, the zero diagonal entry stored.
    f = ordered_ldl.Factor(np.array([0, 0, 1]), np.array([0, 1, 1]), np.array([0.0, 1.0, 2.0]),
                           2, np.arange(2))
    assert f.lnz == 1
    assert not f.factor()
    # A column without its diagonal entry: no elimination tree, no factor.
    f = ordered_ldl.Factor(np.array([0, 1]), np.array([1, 1]), np.array([1.0, 2.0]), 2,
                           np.arange(2))
    assert f.lnz < 0 and not f.factor()


def _cut_grid():
    """The bumpy grid cut down the middle column of edges: two disk charts."""
    V, F = _bumpy_disk(8)
    E = edge_table(V, F)
    x = V[:, 0]
    a, b = E.ends[:, 0], E.ends[:, 1]
    cut = (x[a] == 4) & (x[b] == 4)
    return V, F, E, cut


def test_orders_fresh_pieces_and_unions():
    V, F, E, cut = _cut_grid()
    whole = charts(F, E, np.zeros(len(E.ends), bool))
    halves = charts(F, E, cut)
    assert len(whole) == 1 and len(halves) == 2
    o = orders_mod.Orders(len(V), len(F))
    # Fresh: every vertex keyed, the keys a permutation of 0..n-1, one block.
    vk, fresh = o.keys(whole, np.array([0, len(whole[0].vertices)]))
    assert fresh.all() and np.array_equal(np.sort(vk), np.arange(len(V)))
    assert np.array_equal(o.key[whole[0].vertices], vk) and (o.block == o.block[0]).all()
    # A piece keeps its chart's keys (the order restricted to it).
    voff = np.cumsum([0] + [len(c.vertices) for c in halves])
    vk2, fresh2 = o.keys(halves, voff)
    assert not fresh2.any()
    assert np.array_equal(vk2, o.key[np.concatenate([c.vertices for c in halves])])
    # Two blocks: the halves ordered afresh, then their union.
    o = orders_mod.Orders(len(V), len(F))
    o.keys(halves, voff)
    assert len(np.unique(o.block[halves[0].faces])) == 1
    assert o.block[halves[0].faces[0]] != o.block[halves[1].faces[0]]
    before = o.key.copy()
    vk3, _ = o.keys(whole, np.array([0, len(whole[0].vertices)]))
    seam = np.flatnonzero(np.isin(whole[0].vertices, np.unique(E.ends[cut])))
    rest = np.setdiff1d(np.arange(len(vk3)), seam)
    assert len(seam) == 8                       # the cut column's vertices
    assert vk3[seam].min() > vk3[rest].max()   # eliminated last
    # ... and keyed after every key given before, the union one block now.
    assert o.key[whole[0].vertices[seam]].min() > before.max()
    assert (o.block == o.block[0]).all()


def _sphere_charts():
    return sphere_cut()


@pytest.mark.parametrize("slack", [orders_mod.SLACK, 1e-9])
def test_chart_maps_with_orders_are_qdldls(monkeypatch, slack):
    """Pieces reuse their chart's order, unions their charts'; with a slack of ~0 every reused
    order is refused and the system ordered afresh: the maps are qdldl's in every case."""
    monkeypatch.setattr(charts_mod, "SLACK", slack)
    V, F, E, cut = _sphere_charts()
    whole = [c for c in charts(F, E, cut) if c.kind == "disk"]
    assert len(whole) >= 2
    o = orders_mod.Orders(len(V), len(F))
    for chs in (whole, whole):                  # fresh, then reused as they are
        got = charts_mod.chart_maps(V, chs, orders=o)
        want = charts_mod.chart_maps(V, chs)
        np.testing.assert_allclose(got.u, want.u, atol=1e-9)
        np.testing.assert_allclose(got.max_stretch, want.max_stretch, rtol=1e-9)
    assert o.fill > 0
    # The first chart split in two by the search's own bisection (pieces), and the union of
    # two neighbouring charts whose shared seam merging would remove.
    trial = cut.copy()
    A = face_geometry(V, F).area
    assert bisect([np.sort(whole[0].faces)], E, trial, A, FaceCentroids(V, F))[0] is not None
    pieces = charts(F, E, trial, whole[0].faces)
    assert len(pieces) == 2 and all(c.kind == "disk" for c in pieces)
    label = np.full(len(F), -1)
    for j, c in enumerate(whole):
        label[c.faces] = j
    inner = E.faces[:, 1] >= 0
    la, lb = label[E.faces[inner, 0]], label[E.faces[inner, 1]]
    joined = None
    for j in range(1, len(whole)):
        shared = np.flatnonzero(inner)[((la == 0) & (lb == j)) | ((la == j) & (lb == 0))]
        if not len(shared):
            continue
        merged = cut.copy()
        merged[shared] = False
        u = charts(F, E, merged, np.concatenate([whole[0].faces, whole[j].faces]))
        if len(u) == 1 and u[0].kind == "disk":
            joined = u
            break
    assert joined is not None
    for chs in (pieces, joined):
        got = charts_mod.chart_maps(V, chs, orders=o)
        want = charts_mod.chart_maps(V, chs)
        np.testing.assert_allclose(got.u, want.u, atol=1e-9)
        np.testing.assert_allclose(got.max_stretch, want.max_stretch, rtol=1e-9)


def test_unwrap_auto_adds_the_same_seams_with_orders_as_without(monkeypatch):
    V, F, _ = uv_sphere(32, 16)
    _, with_orders, info = unwrap_auto(V, F, bound=2.0, stretch=2.0)
    monkeypatch.setattr(orders_mod.Orders, "of", classmethod(lambda cls, n, m: None))
    _, without, info2 = unwrap_auto(V, F, bound=2.0, stretch=2.0)
    assert np.array_equal(with_orders, without)
    assert info["charts"] == info2["charts"]


def test_bisect_with_orders_cuts_as_without():
    """The Fiedler systems: charts ordered afresh, then their pieces in the restricted order;
    the same cuts as qdldl's order gives (decisions are made on rounded values)."""
    V, F, E, cut = _sphere_charts()
    whole = [np.sort(c.faces) for c in charts(F, E, cut) if c.kind == "disk"]
    A, cen = face_geometry(V, F).area, FaceCentroids(V, F)
    o = orders_mod.Orders(len(V), len(F))
    a, b = cut.copy(), cut.copy()
    sides = bisect(whole, E, a, A, cen, orders=o)
    bisect(whole, E, b, A, cen)
    assert np.array_equal(a, b)
    assert (o.face_key[np.concatenate(whole)] >= 0).all()
    pieces = [p for two in sides if two is not None for p in two]
    assert len(pieces) >= 4
    assert (o.face_keys(pieces, np.concatenate(pieces)) >= 0).all()     # reused, not fresh
    blocks = o.blocks
    a2, b2 = a.copy(), a.copy()
    bisect(pieces, E, a2, A, cen, orders=o)
    bisect(pieces, E, b2, A, cen)
    assert np.array_equal(a2, b2) and a2.sum() > a.sum()
    assert o.blocks == blocks                   # no piece ordered afresh


def test_an_unchecked_qdldl_release_takes_qdldls_own_order(monkeypatch):
    # the ctypes signatures are trusted for the checked release only: another one is never
    # called through them (a wrong argument list would crash the process, not raise)
    monkeypatch.setattr(ordered_ldl, "_version", lambda: "0.2.0")
    ordered_ldl._lib.cache_clear()
    try:
        assert not ordered_ldl.available()
        V, F, _ = uv_sphere(32, 16)
        res, added, _ = unwrap_auto(V, F, bound=2.0, stretch=2.0)
        assert all(r.status == "certified" for r in res.islands) and len(added)
    finally:
        monkeypatch.undo()            # the real version again, so the cache left behind is true
        ordered_ldl._lib.cache_clear()
    assert ordered_ldl.available() == (ordered_ldl._version() in ordered_ldl.TESTED)
    assert ordered_ldl.available()    # the pinned qdldl: later tests take the ordered path


def test_qdldls_release_is_read_beside_the_module_as_importlib_metadata_reads_it():
    """``_version`` looks for a tested release's dist-info folder beside the module before it
    imports ``importlib.metadata`` (that import cost a process's first search ~12 ms): the same
    release as the metadata gives, and the metadata's answer where the folder is not there."""
    from importlib.metadata import version
    assert ordered_ldl._version() == version("qdldl")
    real = ordered_ldl.TESTED
    try:
        ordered_ldl.TESTED = ("0.0.0",)          # no such folder: the metadata decides
        assert ordered_ldl._version() == version("qdldl")
    finally:
        ordered_ldl.TESTED = real


def test_fiedler_triplets_factor_as_the_compressed_system_and_repeats_are_summed():
    """``fiedler_solver`` with every key given factors the triplets as they come: the bits of
    the compressed matrix, in any triplet order; triplets sharing a place are summed first
    (``upper()``), and keys of -1 are ordered afresh and handed back."""
    rng = np.random.default_rng(5)
    k = 40
    a = rng.integers(0, k, 120)
    b = (a + rng.integers(1, k, 120)) % k                 # no loops
    pairs = np.stack([np.minimum(a, b), np.maximum(a, b)], 1)
    pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
    keep = np.r_[True, np.any(pairs[1:] != pairs[:-1], axis=1)]
    w = rng.uniform(0.5, 2.0, len(pairs))
    rhs = rng.standard_normal(k)

    def system(pairs, w):
        deg = np.bincount(pairs.ravel(), np.repeat(w, 2), minlength=k) + 0.1
        idx = np.arange(k)
        rows = np.concatenate([pairs[:, 0], idx])
        cols = np.concatenate([pairs[:, 1], idx])
        vals = np.concatenate([-w, deg])

        def upper():
            from bd_uv.seams.compressed import compressed
            return sp.csc_matrix(compressed(cols, rows, vals, k), shape=(k, k))
        full = sp.coo_matrix((vals, (rows, cols)), shape=(k, k)).tocsc()
        return rows, cols, vals, upper, (full + sp.triu(full, 1).T).tocsc()

    keys = rng.permutation(k)
    # Distinct pairs: as given, shuffled, and through the compressed matrix: the same bits.
    rows, cols, vals, upper, full = system(pairs[keep], w[keep])
    want = spla.spsolve(full, rhs)
    p = rng.permutation(len(rows))
    x1 = orders_mod.fiedler_solver(rows, cols, vals, keys.copy(), upper)(rhs)
    x2 = orders_mod.fiedler_solver(rows[p], cols[p], vals[p], keys.copy(), upper)(rhs)
    U = upper()
    f = ordered_ldl.Factor(U.indices.astype(np.int64), np.repeat(np.arange(k), np.diff(U.indptr)),
                           U.data, k, np.argsort(keys))
    assert not f.repeated() and f.factor()
    assert np.array_equal(x1, x2) and np.array_equal(x1, f.solve(rhs))
    np.testing.assert_allclose(x1, want, rtol=1e-9, atol=1e-12)
    # Repeated pairs (as two faces sharing two edges would give): summed, not factored twice.
    assert (~keep).any()
    rows, cols, vals, upper, full = system(pairs, w)
    assert ordered_ldl.Factor(rows, cols, vals, k, np.argsort(keys)).repeated()
    x = orders_mod.fiedler_solver(rows, cols, vals, keys.copy(), upper)(rhs)
    np.testing.assert_allclose(x, spla.spsolve(full, rhs), rtol=1e-9, atol=1e-12)
    # Keys of -1: ordered afresh (AMD), the keys handed back.
    fresh = np.full(k, -1)
    x = orders_mod.fiedler_solver(rows, cols, vals, fresh, upper)(rhs)
    assert np.array_equal(np.sort(fresh), np.arange(k))
    np.testing.assert_allclose(x, spla.spsolve(full, rhs), rtol=1e-9, atol=1e-12)
