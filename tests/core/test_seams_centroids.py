"""``bisect.FaceCentroids``: the rows of ``V[F].mean(axis=1)`` bit for bit, whatever the
coordinates' magnitudes and whether the rows come at once or ``CHUNK`` at a time (the seam
search's splits read them; a different last bit would move a Fiedler start vector)."""
import numpy as np

from bd_uv.seams import bisect as bisect_mod
from bd_uv.seams.bisect import FaceCentroids


def _mesh(rng, n=400, m=900):
    # Coordinates of mixed magnitudes and signs: sums that round differently in another order.
    V = rng.standard_normal((n, 3)) * 10.0 ** rng.integers(-8, 9, (n, 1))
    F = rng.integers(0, n, (m, 3))
    return V, F


def test_centroids_are_the_mean_bit_for_bit():
    rng = np.random.default_rng(16)
    for _ in range(20):
        V, F = _mesh(rng)
        rows = rng.permutation(len(F))[:500]
        want = V[F[rows]].mean(axis=1)
        got = FaceCentroids(V, F)[rows]
        assert got.shape == want.shape
        assert np.array_equal(got.view(np.int64), want.view(np.int64))


def test_centroids_by_chunks_are_the_mean_bit_for_bit(monkeypatch):
    monkeypatch.setattr(bisect_mod, "CHUNK", 37)
    rng = np.random.default_rng(7)
    V, F = _mesh(rng)
    rows = rng.permutation(len(F))
    want = V[F[rows]].mean(axis=1)
    assert np.array_equal(FaceCentroids(V, F)[rows].view(np.int64), want.view(np.int64))


def test_held_centroids_are_the_mean_bit_for_bit():
    """Held (``hold=True``, the search's meshes of at most ``auto.GEOM_FACES`` faces): the rows
    read from the whole array are those formed for the faces asked for, to the bit."""
    rng = np.random.default_rng(32)
    for _ in range(10):
        V, F = _mesh(rng)
        rows = rng.permutation(len(F))[:500]
        want = V[F[rows]].mean(axis=1)
        held = FaceCentroids(V, F, hold=True)
        assert held.held is not None
        assert np.array_equal(held[rows].view(np.int64), want.view(np.int64))


def test_dual_lengths_are_the_centroid_distances():
    """``dual_lengths``: each interior edge's two faces' centroid distance, recomputed here from
    the corners by hand (to rounding) and equal to the bit to the norm the split forms for its
    pairs; 0 on the boundary; None where the centroids are not held."""
    from bd_uv.seams.edges import edge_table
    from seams_helpers import uv_sphere
    V, F, _ = uv_sphere(12, 7)
    F = F[3:]                                   # a hole: some boundary edges
    E = edge_table(V, F)
    assert FaceCentroids(V, F).dual_lengths(E) is None
    d = FaceCentroids(V, F, hold=True).dual_lengths(E)
    f0, f1 = E.faces[:, 0], E.faces[:, 1]
    inner = f1 >= 0
    assert (~inner).any() and inner.any()
    assert np.all(d[~inner] == 0.0)
    c0 = (V[F[f0[inner], 0]] + V[F[f0[inner], 1]] + V[F[f0[inner], 2]]) / 3.0
    c1 = (V[F[f1[inner], 0]] + V[F[f1[inner], 1]] + V[F[f1[inner], 2]]) / 3.0
    by_hand = np.sqrt(((c0 - c1) ** 2).sum(axis=1))
    np.testing.assert_allclose(d[inner], by_hand, rtol=1e-14)
    cen = V[F].mean(axis=1)
    pairs = np.stack([f0[inner], f1[inner]], 1)
    split_norm = np.linalg.norm(cen[pairs[:, 0]] - cen[pairs[:, 1]], axis=1)
    assert np.array_equal(d[inner].view(np.int64), split_norm.view(np.int64))


def test_bisect_with_held_centroids_cuts_alike():
    """A split with the centroids and dual lengths held cuts the same edges as with them formed
    per split (the same weights to the bit, so the same Fiedler vectors and sweep)."""
    from bd_uv.seams.bisect import bisect
    from bd_uv.seams.edges import edge_table
    from bd_uv.geometry import face_areas
    from seams_helpers import uv_sphere
    V, F, _ = uv_sphere(24, 12)
    E = edge_table(V, F)
    A = face_areas(V, F)
    faces = [np.arange(len(F))]
    got = []
    for hold in (False, True):
        cut = np.zeros(len(E.ends), dtype=bool)
        sides = bisect(faces, E, cut, A, FaceCentroids(V, F, hold=hold))
        assert sides[0] is not None
        got.append((cut.copy(), sides[0]))
    assert got[0][0].any()
    assert np.array_equal(got[0][0], got[1][0])
    assert all(np.array_equal(a, b) for a, b in zip(got[0][1], got[1][1]))
