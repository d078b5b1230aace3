"""``ordered_ldl.Factor`` and its ``paired`` solve hand QDLDL views of a few shared buffers (one
address taken per buffer): the factor, its solves and the paired solve must be the bits of the
same C calls on one array each, as they were made before (recomputed here through ctypes)."""
import numpy as np
import pytest
import scipy.sparse as sp

from bd_uv.solvers import ordered_ldl
from bd_uv.solvers.lscm import face_geometry, _lscm_system
from bd_uv.mesh import checked_islands
from helpers import grid, load_off
from qdldl_marks import needs_ordered_ldl

pytestmark = needs_ordered_ldl


@pytest.fixture(autouse=True)
def _fresh_lib():
    ordered_ldl._lib.cache_clear()
    yield


def _reference(rows, cols, vals, n, perm):
    """The factor of the upper triangle (rows, cols, vals) eliminated in ``perm``, each array
    of its own, every address taken for every call (the code before the buffers)."""
    lib = ordered_ldl._lib()
    pinv = np.empty(n, np.int64)
    pinv[perm] = np.arange(n)
    r, c = pinv[rows], pinv[cols]
    U = sp.csc_matrix((np.asarray(vals, float), (np.minimum(r, c), np.maximum(r, c))),
                      shape=(n, n))
    U.sort_indices()
    Ap, Ai, Ax = (np.ascontiguousarray(a) for a in (U.indptr.astype(np.int64),
                                                     U.indices.astype(np.int64), U.data))
    work, Lnz, etree = (np.empty(n, np.int64) for _ in range(3))
    p = lambda a: a.ctypes.data      # noqa: E731
    lnz = lib.QDLDL_etree(n, p(Ap), p(Ai), p(work), p(Lnz), p(etree))
    Lp, Li, Lx = np.empty(n + 1, np.int64), np.empty(max(lnz, 1), np.int64), np.empty(max(lnz, 1))
    D, Dinv, bwork = np.empty(n), np.empty(n), np.empty(n, np.ubyte)
    iwork, fwork = np.empty(3 * n, np.int64), np.empty(n)
    pos = lib.QDLDL_factor(n, p(Ap), p(Ai), p(Ax), p(Lp), p(Li), p(Lx), p(D), p(Dinv), p(Lnz),
                           p(etree), p(bwork), p(iwork), p(fwork))
    assert pos >= 0

    def solve(b):
        x = np.ascontiguousarray(b[perm], np.float64)
        lib.QDLDL_solve(n, p(Lp), p(Li), p(Lx), p(Dinv), p(x))
        out = np.empty_like(x)
        out[perm] = x
        return out
    return lnz, Lp, Li[:lnz], Lx[:lnz], Dinv, solve


def _systems():
    V, F = load_off("nefertiti.off")
    for V, F in ((V, F), grid(7, 5)):
        (isl,) = checked_islands(V, np.asarray(F, np.int64))
        g = face_geometry(V, F[isl.faces])
        nv = len(isl.vertices)
        A, rhs, _, free = _lscm_system(g.cbw(), g.cb, isl.tris, nv, isl.loops[0][:2],
                                       np.array([0.0, 1.0], complex), triplets=True)
        yield A, rhs, ordered_ldl.vertex_ranks(isl.tris, nv)[free]


def test_the_factor_on_shared_buffers_is_the_factor_on_arrays_of_their_own():
    for A, rhs, keys in _systems():
        nf = len(keys)
        p = np.argsort(keys, kind="stable")
        for perm in (np.stack([p, p + nf], axis=1).ravel(), np.arange(A.n)):
            lnz, Lp, Li, Lx, Dinv, solve = _reference(A.rows, A.cols, A.vals, A.n, perm)
            f = ordered_ldl.Factor(A.rows, A.cols, A.vals, A.n, perm)
            assert f.lnz == lnz and f.factor()
            assert Lp.tobytes() == f.Lp.tobytes() and Li.tobytes() == f.Li[:lnz].tobytes()
            assert Lx.tobytes() == f.Lx[:lnz].tobytes() and Dinv.tobytes() == f.Dinv.tobytes()
            x = solve(rhs)
            assert x.tobytes() == f.solve(rhs).tobytes()
            # the answer solves the system (recomputed from the triplets, both triangles)
            M = sp.coo_matrix((A.vals, (A.rows, A.cols)), shape=(A.n, A.n)).tocsr()
            M = M + sp.triu(M, k=1).T
            assert np.abs(M @ x - rhs).max() <= 1e-8 * np.abs(rhs).max()


def test_the_paired_solve_on_shared_buffers_is_two_solves():
    for A, rhs, keys in _systems():
        # the free-free block of u alone (the upper-left half of the system) as a matrix of
        # its own, factorised in its own order, as the bound search's Laplacian is
        nf = len(keys)
        keep = (A.rows < nf) & (A.cols < nf)
        M = sp.csc_matrix((A.vals[keep], (A.rows[keep], A.cols[keep])), shape=(nf, nf))
        M.sort_indices()
        solve = ordered_ldl.solver_in_order(M)
        paired = solve.paired()
        b = np.stack([rhs[:nf], rhs[nf:]])
        paired.buffer[:] = b.ravel()
        paired()
        _, _, _, _, _, ref = _reference(A.rows[keep], A.cols[keep], A.vals[keep], nf,
                                        np.arange(nf))
        both = np.concatenate([ref(b[0]), ref(b[1])])
        assert paired.buffer.tobytes() == both.tobytes()
        assert solve(b[0]).tobytes() == both[:nf].tobytes()


def test_triplets_sharing_a_place_are_summed_with_repeats():
    """``Factor(repeats=True)``: an upper triangle given with places repeated (each entry split
    in two or three triplets, shuffled) is summed before the factorisation: the solve of the
    summed matrix (numpy's dense solve, recomputed), and that of the same matrix given once
    per place to rounding (its duplicates summed in another order)."""
    rng = np.random.default_rng(7)
    n = 40
    M = sp.random(n, n, density=0.15, random_state=3)
    M = (M + M.T + n * sp.eye(n)).tocoo()
    up = M.row <= M.col
    r, c, v = M.row[up].astype(np.int64), M.col[up].astype(np.int64), M.data[up]
    split = rng.integers(1, 4, len(v))
    rows, cols = r.repeat(split), c.repeat(split)
    parts = rng.random(len(rows)) + 0.5
    parts /= np.bincount(np.arange(len(v)).repeat(split), parts)[np.arange(len(v)).repeat(split)]
    vals = v.repeat(split) * parts
    order = rng.permutation(len(rows))
    rows, cols, vals = rows[order], cols[order], vals[order]
    perm = rng.permutation(n).astype(np.int64)
    f = ordered_ldl.Factor(rows, cols, vals, n, perm, repeats=True)
    assert not f.repeated() and f.lnz >= 0 and f.factor()
    b = rng.standard_normal(n)
    dense = M.toarray()
    x = f.solve(b)
    assert np.abs(x - np.linalg.solve(dense, b)).max() < 1e-10
    summed = sp.coo_array((vals, (rows, cols)), shape=(n, n)).tocsr().tocoo()
    g = ordered_ldl.Factor(summed.row.astype(np.int64), summed.col.astype(np.int64),
                           summed.data, n, perm)
    assert g.factor()
    assert np.abs(g.solve(b) - x).max() < 1e-12
