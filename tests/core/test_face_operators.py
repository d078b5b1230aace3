"""geometry.components and solvers.face_operators against the scipy computations they replace."""
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

import bd_uv.geometry as geometry
from bd_uv.geometry import components, local_coordinates
from bd_uv.energies import jacobian_operators
from bd_uv.solvers.face_operators import alpha_beta_lift, face_gradients, laplacian_blocks


def _scipy_components(n, a, b):
    return connected_components(sp.coo_array((np.ones(len(a)), (a, b)), shape=(n, n)),
                                directed=False)


def test_components_match_scipy_on_random_graphs_and_paths():
    rng = np.random.default_rng(3)
    for t in range(300):
        n = int(rng.integers(1, 400))
        if t % 3 == 0:          # a path in random order: the most rounds of hooking
            p = rng.permutation(n)
            a, b = p[:-1], p[1:]
        else:
            e = int(rng.integers(0, 2 * n))
            a, b = rng.integers(0, n, e), rng.integers(0, n, e)
        count, labels = components(n, a, b)
        ref_count, ref_labels = _scipy_components(n, a, b)
        assert count == ref_count
        assert np.array_equal(labels, ref_labels)


def test_components_fall_back_to_scipy(monkeypatch):
    rng = np.random.default_rng(4)
    n = 300
    a, b = rng.integers(0, n, 200), rng.integers(0, n, 200)
    ref = _scipy_components(n, a, b)
    for name, value in (("HOOK_ROUNDS", 1), ("HOOK_VERTICES", 10)):
        monkeypatch.setattr(geometry, name, value)
        count, labels = components(n, a, b)
        assert count == ref[0] and np.array_equal(labels, ref[1])


def _grid_island(nx=7, ny=5):
    """A bumpy grid (with right angles: exact zero gradient coefficients) as (P, tris)."""
    x, y = np.meshgrid(np.arange(nx, dtype=float), np.arange(ny, dtype=float))
    P = np.c_[x.ravel(), y.ravel(), 0.2 * np.sin(x.ravel()) * np.cos(0.7 * y.ravel())]
    i, j = np.meshgrid(np.arange(nx - 1), np.arange(ny - 1))
    a = (j * nx + i).ravel()
    tris = np.r_[np.c_[a, a + 1, a + nx + 1], np.c_[a, a + nx + 1, a + nx]].astype(np.int64)
    return P, tris


def test_laplacian_blocks_and_lift_match_sparse_products():
    P, tris = _grid_island()
    nv = len(P)
    ops = jacobian_operators(local_coordinates(P, tris), tris, nv)
    Gx = sp.csr_array((ops.Are + ops.Bre)[:, :nv])
    Gy = sp.csr_array((ops.Bim - ops.Aim)[:, :nv])
    gx, gy = face_gradients(Gx, Gy, tris)
    fixed = np.array([0, 9, 20])
    free = np.setdiff1d(np.arange(nv), fixed)
    L_ff, L_fF = laplacian_blocks(gx, gy, ops.area, tris, free, fixed, nv)
    W = sp.diags_array(ops.area)
    L = (Gx.T @ W @ Gx + Gy.T @ W @ Gy).tocsr()
    scale = abs(L).max()
    assert abs(L[free][:, free] - L_ff).max() <= 1e-13 * scale
    assert abs(L[free][:, fixed] - L_fF).max() <= 1e-13 * scale
    assert L_ff.has_canonical_format
    B, BtA = alpha_beta_lift(gx, gy, ops.area, tris, free, nv)
    rng = np.random.default_rng(5)
    u, v = rng.normal(size=nv), rng.normal(size=nv)
    ux, uy, vx, vy = Gx @ u, Gy @ u, Gx @ v, Gy @ v
    lifted = (B @ np.r_[u, v]).reshape(4, -1)
    assert np.allclose(lifted, [ux + vy, vx - uy, ux - vy, vx + uy], atol=1e-12)
    # the right-hand side operator: B_free^T diag(A, A, A, A) / 2
    y = rng.normal(size=4 * len(tris))
    full = B.T @ (np.tile(ops.area, 4) * y) / 2
    assert np.allclose(BtA @ y, np.r_[full[free], full[free + nv]], atol=1e-12)


def test_summed_csc_is_scipys_conversion_bit_for_bit():
    """``laplacian_blocks``' conversion (scipy's compiled steps called straight) gives the very
    arrays of ``sp.csc_array((v, (r, c)))``: index types, order and the sums of duplicates, in
    triplets given in any order, sorted or not, with or without duplicates."""
    from bd_uv.solvers.face_operators import _summed_csc
    rng = np.random.default_rng(7)
    for t in range(60):
        nr, nc = int(rng.integers(1, 40)), int(rng.integers(1, 40))
        n = int(rng.integers(0, 300))
        r, c = rng.integers(0, nr, n), rng.integers(0, nc, n)
        if t % 3 == 0:          # sorted by column then row, duplicates adjacent
            o = np.lexsort((r, c))
            r, c = r[o], c[o]
        v = rng.standard_normal(n) * 10.0 ** rng.integers(-8, 8, n)
        ref = sp.csc_array((v, (r, c)), shape=(nr, nc))
        ref.sum_duplicates()
        got = _summed_csc(v, r.astype(np.int64), c.astype(np.int64), nr, nc)
        assert got.shape == ref.shape and got.has_canonical_format
        assert got.indptr.dtype == ref.indptr.dtype and got.indices.dtype == ref.indices.dtype
        assert np.array_equal(got.indptr, ref.indptr)
        assert np.array_equal(got.indices, ref.indices)
        assert got.data.tobytes() == ref.data.tobytes()


def test_bare_block_arrays_and_their_product_are_scipys_bit_for_bit():
    """``laplacian_block_arrays`` (no scipy matrix made) holds the very arrays of
    ``laplacian_blocks``' matrices, and its ``times`` gives scipy's product ``M @ X`` bit for bit
    (the global step's fixed share of the right-hand side), on fixed sets of several sizes."""
    from bd_uv.solvers.face_operators import laplacian_block_arrays
    P, tris = _grid_island(9, 6)
    nv = len(P)
    ops = jacobian_operators(local_coordinates(P, tris), tris, nv)
    Gx = sp.csr_array((ops.Are + ops.Bre)[:, :nv])
    Gy = sp.csr_array((ops.Bim - ops.Aim)[:, :nv])
    gx, gy = face_gradients(Gx, Gy, tris)
    rng = np.random.default_rng(11)
    for nfix in (1, 2, 5, 17):
        fixed = rng.choice(nv, nfix, replace=False)
        free = rng.permutation(np.setdiff1d(np.arange(nv), fixed))    # any order of the free
        mats = laplacian_blocks(gx, gy, ops.area, tris, free, fixed, nv)
        bare = laplacian_block_arrays(gx, gy, ops.area, tris, free, fixed, nv)
        for M, b in zip(mats, bare):
            assert M.shape == b.shape
            assert np.array_equal(M.indptr, b.indptr) and np.array_equal(M.indices, b.indices)
            assert M.data.tobytes() == b.data.tobytes()
            X = rng.standard_normal((b.shape[1], 2)) * 10.0 ** rng.integers(-3, 3)
            # a transposed view, as the search passes its fixed vertices' values
            Xt = np.ascontiguousarray(X.T).T
            assert (M @ X).tobytes() == b.times(Xt).tobytes()
