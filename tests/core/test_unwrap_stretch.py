"""Stretch bounds inside an unwrap (Lipman 2012, section 6.3): every face's singular values within
[1/S, S] at the island's own scale (UV area = 3D area), certified from the final UVs, recomputed
here with numpy's SVD of each face's map."""
import numpy as np
import pytest

import bd_uv
from helpers import load_off, reference_jacobians


def singular_values_at_own_scale(V, F, corner_uv):
    J = reference_jacobians(V, F, corner_uv)
    s = np.linalg.svd(J, compute_uv=False)
    P = V[F]
    A3 = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    scale = np.sqrt(A3.sum() / np.sum(np.abs(np.linalg.det(J)) * A3))
    return s[:, 0] * scale, s[:, 1] * scale, np.linalg.det(J)


def test_a_stretch_bound_is_met_and_reported():
    V, F = load_off("nefertiti.off")
    free = bd_uv.unwrap(V, F, bound=2.0)
    s1, s2, _ = singular_values_at_own_scale(V, F, free.corner_uv)
    S = 1.42                                   # the free map's smallest singular value is lower
    assert s2.min() < 1.0 / S
    res = bd_uv.unwrap(V, F, bound=2.0, stretch=S)
    (isl,) = res.islands
    assert isl.status == "certified"
    s1, s2, det = singular_values_at_own_scale(V, F, res.corner_uv)
    assert (det > 0).all() and (s1 / s2).max() <= 2.0 * (1 + 1e-9)
    assert s2.min() >= 1.0 / S * (1 - 1e-6) and s1.max() <= S * (1 + 1e-6)
    assert isl.min_singular == pytest.approx(s2.min(), rel=1e-6)
    assert isl.max_singular == pytest.approx(s1.max(), rel=1e-6)


def test_a_stretch_bound_that_cannot_hold_with_c_is_refused():
    V, F = load_off("nefertiti.off")
    with pytest.raises(ValueError, match="sqrt"):
        bd_uv.unwrap(V, F, bound=3.0, stretch=1.2)     # S^2 = 1.44 < C
    with pytest.raises(ValueError, match="numeric bound"):   # minimising C: free boundary only
        bd_uv.unwrap(V, F, bound="auto", stretch=2.0, boundary="circle")


def test_an_island_that_cannot_meet_the_bounds_fails_and_says_so():
    V, F = load_off("nefertiti.off")
    res = bd_uv.unwrap(V, F, bound=1.3, stretch=1.15)
    (isl,) = res.islands
    assert isl.status == "failed" and type(isl.error) is bd_uv.InfeasibleError
    assert "stretch" in isl.message and np.isnan(res.corner_uv).all()


def test_bound_one_with_a_stretch_bound_is_no_crash():
    """Found by the CLI fuzz contract (issue 22): C = 1 is a valid bound, but with a stretch bound
    the search handed it to the projection iterations, which need C > 1 (ValueError). Now the
    conic solve alone: every island certified within C = 1 (up to rounding) and S, or failed
    with a typed error."""
    V, F = load_off("three_peaks.off")
    V, F = V[np.unique(F[:60])], np.unique(F[:60], return_inverse=True)[1].reshape(-1, 3)
    for method in ("lscm", "arap"):
        res = bd_uv.unwrap(V, F, bound=1.0, stretch=1.5, method=method)
        for isl in res.islands:
            if isl.status == "failed":
                assert isinstance(isl.error, bd_uv.IslandError)
                continue
            f = isl.faces
            s1, s2, det = singular_values_at_own_scale(V, F[f], res.corner_uv[f])
            assert (det > 0).all() and (s1 / s2).max() <= 1.0 + 2e-6
        assert any(isl.status == "certified" for isl in res.islands)
