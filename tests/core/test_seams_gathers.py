"""Row gathers by ``take`` rather than numpy's fancy index (~4x cheaper for rows of an (n,3)
array, ~2x by int32 ids) and stable orders by radix passes: the same numbers as before, checked
against the fancy-indexed and by-hand forms."""
import numpy as np

from bd_uv.geometry import _cross_norm, face_areas, local_coordinates
from bd_uv.seams.orders import _stable_order
from bd_uv.solvers.lscm import face_geometry


def _mesh(rng, n=300, m=700):
    V = rng.standard_normal((n, 3)) * 10.0 ** rng.integers(-3, 4, (n, 1))
    F = rng.integers(0, n, (m, 3)).astype(np.int32)
    return V, F


def test_face_areas_by_hand_and_bit_for_bit():
    rng = np.random.default_rng(3)
    V, F = _mesh(rng)
    A = face_areas(V, F)
    P = V[F.astype(np.int64)]
    by_hand = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    np.testing.assert_allclose(A, by_hand, rtol=1e-12, atol=0)
    # the same bits as the corners gathered by a fancy index (int32 and int64 ids alike)
    assert np.array_equal(A, 0.5 * _cross_norm(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]))
    assert np.array_equal(A, face_areas(V, F.astype(np.int64)))


def test_local_coordinates_keep_lengths():
    """Corner 0 at 0, corner 1 on the positive real axis, side lengths as in 3D."""
    rng = np.random.default_rng(4)
    V, F = _mesh(rng)
    Z = local_coordinates(V, F)
    P = V[F.astype(np.int64)]
    for a, b in ((0, 1), (1, 2), (2, 0)):
        np.testing.assert_allclose(np.abs(Z[:, b] - Z[:, a]),
                                   np.linalg.norm(P[:, b] - P[:, a], axis=1), rtol=1e-10)
    assert np.all(Z[:, 0] == 0)
    assert np.all(Z[:, 1].imag == 0) and np.all(Z[:, 1].real >= 0)


def test_cbw_of_faces_is_the_rows_of_the_whole():
    rng = np.random.default_rng(5)
    V, F = _mesh(rng)
    F = F[face_areas(V, F) > 0]
    g = face_geometry(V, F)
    faces = rng.integers(0, len(F), 400)
    want = g.zarea[faces][:, None] * g.cb[faces].conj()
    assert np.array_equal(g.cbw(faces), want)
    assert np.array_equal(g.cbw()[faces], want)


def test_stable_order_is_numpys_stable_argsort():
    rng = np.random.default_rng(6)
    for hi in (3, 200, 70_000, 2 ** 31 - 1):
        for n in (0, 1, 17, 5000):
            keys = rng.integers(0, hi, n).astype(np.int32)   # ties where hi is small
            got = _stable_order(keys)
            assert np.array_equal(got, keys.argsort(kind="stable"))
            assert np.all(np.diff(keys[got]) >= 0)


def _disk(k=9, seed=3):
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(np.arange(k, dtype=float), np.arange(k, dtype=float), indexing="ij")
    V = np.stack([x.ravel(), y.ravel(), 0.4 * rng.standard_normal(k * k)], 1)
    i = np.arange(k - 1)
    a = (i[:, None] * k + i[None, :]).ravel()
    F = np.concatenate([np.stack([a, a + k, a + k + 1], 1), np.stack([a, a + k + 1, a + 1], 1)])
    return V, F


def test_lscm_right_hand_side_from_the_pinned_faces_alone():
    """``_lscm_system``'s right-hand side formed from the faces at a pinned vertex only: the
    same bits as every face's terms summed (the others add zeros), and equal to minus the
    matrix applied to the pinned values, recomputed here from the full system; with a
    non-finite term (a zero-area face's gradients) every face is summed, as before."""
    from bd_uv.array_calls import einsum
    from bd_uv.solvers.lscm import _lscm_system
    V, F = _disk()
    g = face_geometry(V, F)
    n = len(V)
    for idx in (np.array([0, n - 1]), np.array([5, 40]), np.array([3, 4])):
        val = np.array([0.0, 1.0], np.complex128)
        A, rhs, u0, free = _lscm_system(g.cbw(), g.cb, F, n, idx, val)
        cbw, cb = g.cbw(), g.cb
        hu = (cbw * einsum("fb,fb->f", cb, u0[F])[:, None]).ravel()
        want = -(np.bincount(F.ravel(), hu.real, n) + 1j * np.bincount(F.ravel(), hu.imag, n))
        assert np.array_equal(rhs, np.concatenate([want.real[free], want.imag[free]]))
        # By hand: the LSCM energy's Hermitian matrix H = sum_f cbw_f^T cb_f; rhs = -(H u0)
        H = np.zeros((n, n), np.complex128)
        for f in range(len(F)):
            H[np.ix_(F[f], F[f])] += np.outer(cbw[f], cb[f])
        by_hand = -(H @ u0)
        np.testing.assert_allclose(rhs, np.concatenate([by_hand.real[free], by_hand.imag[free]]),
                                   atol=1e-12)
    # A non-finite coefficient away from the pins: every face summed, as before (NaN reaches
    # the right-hand side at that face's vertices).
    cb = g.cb.copy()
    cb[len(F) // 2] = np.nan
    cbw = g.zarea[:, None] * cb.conj()
    idx = np.array([0, n - 1])
    _, rhs, u0, free = _lscm_system(cbw, cb, F, n, idx, np.array([0.0, 1.0], np.complex128))
    assert np.isnan(rhs).any()


def test_edges_of_is_numpys_unique():
    """``bisect._edges_of``: the sorted distinct edge ids, by marks (many ids) or by a sort (few),
    in the ids' own dtype, as ``np.unique`` gives them."""
    from bd_uv.seams.bisect import _edges_of
    rng = np.random.default_rng(7)
    for e in (1, 50, 4000):
        for n in (0, 1, 3, 40, 900):
            for dt in (np.int32, np.int64):
                fe = rng.integers(0, e, n).astype(dt)
                got = _edges_of(fe, e)
                want = np.unique(fe)
                assert got.dtype == want.dtype and np.array_equal(got, want)


def test_face_geometry_by_any_integer_ids_and_out_of_range():
    """Signed ids go through ``take``, unsigned ones (which it would refuse) through the fancy
    index: the same areas and frames for every integer type; an id out of range is an
    IndexError either way."""
    import pytest
    rng = np.random.default_rng(8)
    V, F = _mesh(rng, n=50, m=80)
    want_a, want_z = face_areas(V, F.astype(np.int64)), local_coordinates(V, F.astype(np.int64))
    for dt in (np.int16, np.int32, np.uint32, np.uint64):
        assert np.array_equal(face_areas(V, F.astype(dt)), want_a)
        np.testing.assert_array_equal(local_coordinates(V, F.astype(dt)), want_z)  # NaN alike
    for dt in (np.int64, np.uint64):
        with pytest.raises(IndexError):
            face_areas(V, np.array([[0, 1, 50]], dtype=dt))
