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
