"""A number C out of reach of a disk whose conformal start flips (``bounded``'s quick path): the
bound search from its harmonic map ends far above C (``searched.FAR``), and the bound is raised
to that search's map at once, its energy lowered within the first of C x 1.5^k at or above its max
(``energy_within.from_harmonic``), as ``searched.over_bound`` raises a flip-free start's; before,
conic solves raised C by 1.5x steps from C (cow.off's 2338/400 disk at C = 3: 12 pieces at 16.5).

Checked from the stored UVs alone: each face's distortion and orientation by numpy's SVD in its
own 3D frame (``unwrap_contract.distortion_and_flips``), the boundary one simple polygon whose
inside is the triangles' union (shapely), the area-weighted mean from those distortions.
"""
import numpy as np

import bd_uv
from bd_uv.unwrapping import energy_within, one_disk, searched
from helpers import load_off, rings
from unwrap_contract import assert_one_simple_disk, distortion_and_flips


def _mean(V, F, D):
    P = V[F]
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    return float((area * D).sum() / area.sum())


def test_a_number_c_out_of_reach_is_raised_to_the_searched_map(monkeypatch):
    V, F = rings(*load_off("cow.off"), 2338, 400)
    disk = one_disk.find(V, F)
    res = bd_uv.unwrap(V, F, bound=3.0)
    (r,) = res.islands                                  # one island
    assert r.status == "certified" and {"bound_raised", "projected"} <= set(r.flags)
    D, flipped = distortion_and_flips(V, F, res.corner_uv)
    assert not flipped.any() and 3.0 < D.max() <= r.bound_certified <= 1.01 * D.max()
    assert r.bound_certified < 3.0 * 1.5 ** 2             # within the raise's second step
    assert_one_simple_disk(V, F, res.corner_uv, r, disk.island)
    # before (the search's far end not used): conic solves raised C further and the overlap
    # repair cut the disk
    monkeypatch.setattr(searched, "FAR", 1e9)
    monkeypatch.setattr(energy_within, "FAR", 1e9)
    before = bd_uv.unwrap(V, F, bound=3.0)
    assert len(before.islands) > 1
    assert max(i.bound_certified for i in before.islands) > r.bound_certified
    Db, _ = distortion_and_flips(V, F, before.corner_uv)
    assert _mean(V, F, D) < _mean(V, F, Db)
