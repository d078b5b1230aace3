"""auto on a disk whose conformal start flips: the searched map's mean distortion lowered within
its max (``strategies._mean_lowered``, ``energy_within.lowered``). data25's cow strip (1,651
faces of tests/data/cow.off, listed in tests/data/cow-strip-faces.txt): auto certified C 9.187 with
an area-weighted mean of 3.17, where a solve at 9.187 gives 1.49; lowered, 2.09 at the same C.
Recomputed here from the UVs (numpy SVD per face)."""
import os

import numpy as np

import bd_uv
import bd_uv.unwrapping.strategies as strategies
from helpers import DATA, load_off, reference_distortion


def _strip():
    V, F = load_off("cow.off")
    ids = np.loadtxt(os.path.join(DATA, "cow-strip-faces.txt"), dtype=np.int64)
    F = F[ids]
    used, inv = np.unique(F, return_inverse=True)
    return V[used], inv.reshape(-1, 3)


def _area_mean(V, F, D):
    P = V[F]
    a = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    return float((a * D).sum() / a.sum())


def test_a_flipping_starts_searched_map_gets_its_mean_lowered_within_its_max(monkeypatch):
    V, F = _strip()
    res = bd_uv.unwrap(V, F, bound="auto")
    (isl,) = res.islands
    assert isl.status == "certified" and "mean_lowered" in isl.flags
    D, flipped = reference_distortion(V, F, res.corner_uv)
    assert not flipped.any() and D.max() <= isl.bound_certified * (1 + 1e-9)
    mean = _area_mean(V, F, D)
    monkeypatch.setattr(strategies, "_mean_lowered", lambda prob, best: None)
    before = bd_uv.unwrap(V, F, bound="auto")
    (isl0,) = before.islands
    D0, _ = reference_distortion(V, F, before.corner_uv)
    # the same certified C, the mean at most 0.7 of the searched map's (2.09 against 3.17)
    assert isl.bound_certified <= isl0.bound_certified
    assert mean <= 0.7 * _area_mean(V, F, D0)
