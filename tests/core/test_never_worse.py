"""The result is never worse than its start (issue 9): a start within C comes back as it is; a
start outside C is bent only as far as the bound demands; many islands solve as one alone would.
Distortion is recomputed here with an SVD of each face's map, independently of bd_uv.metrics."""
import numpy as np
import pytest

import bd_uv
from bd_uv.frames import lscm_map
from bd_uv.geometry import face_areas, local_coordinates
from bd_uv.mesh import islands
from helpers import load_off, reference_distortion


def svd_distortion(V, F, corner_uv):
    """(D per face, True where the face keeps its orientation), from helpers' SVD."""
    D, flipped = reference_distortion(V, F, corner_uv)
    return D, ~flipped


def area_mean(V, F, D):
    A = face_areas(V, F)
    return float(np.sum(A * D) / np.sum(A))


def same_up_to_similarity(uv_a, uv_b, rtol=1e-9):
    """uv_b = s * uv_a + t for some s > 0 and t (no rotation: both are axis-placed)."""
    a = uv_a - uv_a.mean(axis=0)
    b = uv_b - uv_b.mean(axis=0)
    s = np.linalg.norm(b) / np.linalg.norm(a)
    return np.allclose(s * a, b, rtol=0, atol=rtol * np.abs(b).max())


def conformal_start(V, F):
    """The free-boundary conformal map of a one-island mesh, as the unwrap starts from it."""
    (isl,) = islands(V, F)
    Vi = V[isl.vertices]
    Vn = (Vi - Vi.mean(axis=0)) / np.sqrt(face_areas(Vi, isl.tris).sum())
    u = lscm_map(local_coordinates(Vn, isl.tris), isl.tris, len(Vi), isl.loops)
    return isl, np.stack([u.real, u.imag], axis=1)


def test_a_conformal_map_within_the_bound_comes_back_as_it_is():
    V, F = load_off("nefertiti.off")
    isl, uv0 = conformal_start(V, F)
    D0, _ = svd_distortion(V, F, uv0[isl.tris])
    res = bd_uv.unwrap(V, F, bound=5.0)
    (r,) = res.islands
    assert r.status == "certified" and r.solves == 0 and "initial_map" in r.flags
    assert same_up_to_similarity(uv0, r.uv)
    D, kept = svd_distortion(V, F, res.corner_uv)
    assert np.all(kept)
    assert np.max(D) == pytest.approx(np.max(D0), rel=1e-9)
    assert area_mean(V, F, D) == pytest.approx(area_mean(V, F, D0), rel=1e-9)


def test_current_uvs_within_the_bound_come_back_as_they_are():
    """frames="input-uv" starts from the current UVs: within C, nothing is solved or changed."""
    V, F = load_off("nefertiti.off")
    first = bd_uv.unwrap(V, F, bound=5.0, method="arap")     # some flip-free map, not LSCM's
    res = bd_uv.unwrap(V, F, bound=5.0, frames="input-uv", initial_uv=first.corner_uv)
    (r,) = res.islands
    assert r.status == "certified" and r.solves == 0 and r.frames == "input-uv"
    assert same_up_to_similarity(first.islands[0].uv, r.uv)


def test_a_start_outside_the_bound_is_bent_below_it_and_never_above_its_own_max():
    V, F = load_off("nefertiti.off")
    isl, uv0 = conformal_start(V, F)
    D0, _ = svd_distortion(V, F, uv0[isl.tris])
    C = 1.3                                    # the conformal map reaches 1.443
    assert np.max(D0) > C
    res = bd_uv.unwrap(V, F, bound=C)
    D, kept = svd_distortion(V, F, res.corner_uv)
    assert res.certified and np.all(kept)
    assert np.max(D) <= C * (1 + 1e-9) < np.max(D0)
    # bending the worst faces down costs the rest little: mean within 2 % of the start's
    assert area_mean(V, F, D) <= 1.02 * area_mean(V, F, D0)


def test_a_conformal_map_that_flips_gives_a_low_mean_within_the_bound():
    """three_peaks: its conformal map flips 30 faces; the result stays within C = 5 with a mean
    distortion below Blender ABF's 1.353 on this mesh (measured 1.346 at the time of writing)."""
    V, F = load_off("three_peaks.off")
    res = bd_uv.unwrap(V, F, bound=5.0)
    D, kept = svd_distortion(V, F, res.corner_uv)
    assert res.certified and np.all(kept) and np.max(D) <= 5.0 * (1 + 1e-9)
    assert area_mean(V, F, D) < 1.36


def test_three_peaks_at_c5_is_bent_and_searched_without_a_conic_solve():
    """three_peaks at C = 5: the projection moves 10 % of its area, the bound search from the
    projected map and the least mean between them replace the conic polish (issue 21: half its
    time). Within C, mean (recomputed) 1.3032 where the polish gave 1.2973 and ABF 1.353."""
    V, F = load_off("three_peaks.off")
    res = bd_uv.unwrap(V, F, bound=5.0)
    (isl,) = res.islands
    assert isl.solves == 0 and "projected" in isl.flags
    D, kept = svd_distortion(V, F, res.corner_uv)
    assert res.certified and np.all(kept) and np.max(D) <= 5.0 * (1 + 1e-9)
    assert area_mean(V, F, D) < 1.305


def test_many_islands_solved_together_match_each_solved_alone():
    """Copies of one patch, moved and scaled: the batched conformal path gives every copy the
    map the patch gets alone (distortion per face to 1e-9), and one pinned copy (solved on its
    own) keeps its pins."""
    V0, F0 = load_off("nefertiti.off")
    n, copies = len(V0), 4
    V = np.concatenate([V0 * (1 + i) + 10.0 * i for i in range(copies)])
    F = np.concatenate([F0 + i * n for i in range(copies)])
    alone = bd_uv.unwrap(V0, F0, bound=5.0)
    Da, _ = svd_distortion(V0, F0, alone.corner_uv)
    pin_corners = np.array([3 * len(F0) * 3, 3 * len(F0) * 3 + 1])    # face 3 |F0| (copy 3)
    pin_uv = np.array([[0.0, 0.0], [0.1, 0.0]])
    res = bd_uv.unwrap(V, F, bound=5.0, pin_corners=pin_corners, pin_uv=pin_uv)
    assert res.certified and len(res.islands) == copies
    D, kept = svd_distortion(V, F, res.corner_uv)
    assert np.all(kept)
    for i in range(copies - 1):
        assert np.allclose(D[i * len(F0):(i + 1) * len(F0)], Da, rtol=1e-9)
    last = res.corner_uv[3 * len(F0)]
    assert np.array_equal(last[:2], pin_uv)
