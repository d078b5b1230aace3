"""Stretch bounds in the conic solve (Lipman 2012, section 6.3, eqs. 6.3-6.4): islands whose start
breaks both C and S, every method, fixed boundaries and bound="auto". Checked independently of
bd_uv's metrics: numpy's SVD of each face's map from its own 3D triangle, at the island's own scale
(UV area = 3D area) or, with a fixed boundary, relative to the 3D geometry."""
import numpy as np
import pytest

import bd_uv
from bd_uv.frames import lscm_map
from bd_uv.geometry import local_coordinates
from helpers import grid, load_off, reference_jacobians
from overlap_shapes import overlapping_triangle_pairs


def three_peaks(n=25, h=0.8, s=0.12):
    """A height field with three narrow peaks (like /work/shared/meshes/three_peaks.off, made
    here): its conformal map squeezes the peaks (distortion and stretch far above 5 and 3)."""
    def z(x, y):
        return h * sum(np.exp(-((x - a) ** 2 + (y - b) ** 2) / s ** 2)
                       for a, b in ((0.3, 0.25), (0.7, 0.3), (0.5, 0.6)))
    return grid(n, int(0.8 * n), z)


def svd_check(V, F, corner_uv, C, S, own_scale=True):
    """(smallest, largest singular value, max distortion), asserting 0 flips, D <= C and the
    singular values within [1/S, S] (at the island's own scale, or absolute)."""
    J = reference_jacobians(V, F, corner_uv)
    s = np.linalg.svd(J, compute_uv=False)
    det = np.linalg.det(J)
    assert (det > 0).all()
    if own_scale:
        P = V[F]
        A3 = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
        s = s * np.sqrt(A3.sum() / np.sum(det * A3))
    D = s[:, 0] / s[:, 1]
    assert D.max() <= C * (1 + 1e-6)
    assert s[:, 1].min() >= (1 - 1e-6) / S and s[:, 0].max() <= S * (1 + 1e-6)
    return s[:, 1].min(), s[:, 0].max(), D.max()


@pytest.fixture(scope="module")
def peaks():
    return three_peaks()


@pytest.fixture(scope="module")
def nefertiti():
    return load_off("nefertiti.off")


def test_a_start_breaking_both_bounds_certifies(peaks):
    V, F = peaks
    # the start: the free conformal map (LSCM; bound=1000 stood for it until C-bounded unwraps
    # of a flipping conformal map began searching lower bounds, c8dd3e0: max 3.1 there)
    (isl,) = bd_uv.islands(V, F)
    Z = local_coordinates(V[isl.vertices], isl.tris)
    u = lscm_map(Z, isl.tris, len(isl.vertices), isl.loops)
    corner_uv = np.empty((len(F), 3, 2))
    corner_uv[isl.faces] = np.stack([u.real, u.imag], -1)[isl.tris]
    J = reference_jacobians(V, F, corner_uv)
    s = np.linalg.svd(J, compute_uv=False)
    assert (s[:, 0] / s[:, 1]).max() > 5.0 and (s[:, 0] / s[:, 1]).max() < 1000.0
    own = np.sqrt(np.sum(np.linalg.det(J)) / len(J))  # uniform grid: equal areas up to the bumps
    assert (s[:, 1] / own).min() < 1.0 / 3.0
    res = bd_uv.unwrap(V, F, bound=5.0, stretch=3.0)
    (isl,) = res.islands
    assert isl.status == "certified" and isl.overlap_free and "cut" not in isl.flags
    lo, hi, _ = svd_check(V, F, res.corner_uv, 5.0, 3.0)
    assert isl.min_singular == pytest.approx(lo, rel=1e-6)
    assert isl.max_singular == pytest.approx(hi, rel=1e-6)
    assert len(overlapping_triangle_pairs(res.corner_uv)) == 0


@pytest.mark.parametrize("method", ["arap", "dirichlet", "biharmonic", "stretch-l1"])
def test_every_method_takes_a_stretch_bound(nefertiti, method):
    V, F = nefertiti
    res = bd_uv.unwrap(V, F, method=method, bound=2.5, stretch=1.6)
    (isl,) = res.islands
    assert isl.status == "certified", isl.message
    svd_check(V, F, res.corner_uv, 2.5, 1.6)


@pytest.mark.parametrize("shape", ["circle", "rectangle"])
def test_fixed_boundary_with_stretch_is_bijective_and_within_s(nefertiti, shape):
    V, F = nefertiti
    C, S = (4.0, 2.5) if shape == "circle" else (10.0, 4.0)
    res = bd_uv.unwrap(V, F, boundary=shape, bound=C, stretch=S)
    (isl,) = res.islands
    assert isl.status == "certified" and isl.bijective is True, isl.message
    svd_check(V, F, res.corner_uv, isl.bound_certified, S, own_scale=False)
    assert len(overlapping_triangle_pairs(res.corner_uv)) == 0


def test_fixed_boundary_stretch_that_cannot_hold_fails_and_says_so(nefertiti):
    V, F = nefertiti
    (isl,) = bd_uv.unwrap(V, F, boundary="rectangle", bound=4.0, stretch=2.0).islands
    assert isl.status == "failed" and "stretch" in isl.message


def test_auto_bound_with_stretch_minimises_c_within_s(nefertiti):
    V, F = nefertiti
    S = 1.6
    fixed = bd_uv.unwrap(V, F, bound=S * S, stretch=S).islands[0]
    res = bd_uv.unwrap(V, F, bound="auto", stretch=S)
    (isl,) = res.islands
    assert isl.status == "certified"
    _, _, D = svd_check(V, F, res.corner_uv, isl.bound_certified, S)
    assert D <= fixed.max_distortion * (1 + 1e-6)
    assert D < 1.4   # the conformal bound alone is 1.27 here; S = 1.6 allows C = 2.56


def test_refused_combinations_say_why(nefertiti):
    V, F = nefertiti
    with pytest.raises(ValueError, match="numeric bound"):
        bd_uv.unwrap(V, F, bound="auto", stretch=2.0, boundary="circle")
    with pytest.raises(ValueError, match=">= 1"):
        bd_uv.unwrap(V, F, bound="auto", stretch=0.5)


def test_s_close_to_one_leaves_the_scale_room():
    """S = 1.015 with C = 1.03 (S^2 = 1.030): eq. 6.3 charges the largest |beta| that C allows,
    so at C itself a bent grid has no map; the solve lowers its conformal bound
    (``spaces.stretch_conformal_bound``) and the result is certified at C and S."""
    V, F = grid(7, 6)
    V[:, 0], V[:, 1] = 2 * V[:, 0] - 1, 2.5 * V[:, 1] - 1       # [-1, 1]^2, like Blender's grid
    V[:, 2] = 0.3 * np.sin(1.7 * V[:, 0]) * np.cos(1.3 * V[:, 1])
    free = bd_uv.unwrap(V, F, bound=1.03)
    s = np.linalg.svd(reference_jacobians(V, F, free.corner_uv), compute_uv=False)
    assert s.max() / s.min() > 1.015 ** 2 * 0.99   # the conformal map's scale varies
    for method in ("lscm", "stretch-l1"):
        res = bd_uv.unwrap(V, F, bound=1.03, stretch=1.015, method=method)
        assert res.islands[0].status == "certified", res.islands[0].message
        svd_check(V, F, res.corner_uv, 1.03, 1.015)
