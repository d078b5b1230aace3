"""Singular-value (stretch) bounds, Lipman 2012 section 6.3, checked by SVD of each face's map."""
import numpy as np
import pytest

import bd_uv
from bd_uv.deform import alpha_of, bounded_with_resets, deform
from bd_uv.energies import jacobian_operators
from bd_uv.frames import frames_from_map, lscm_map
from bd_uv.geometry import face_areas, local_coordinates
from bd_uv.metrics import singular_values
from bd_uv.spaces import check_stretch
from helpers import load_off
from planar import mesh_polygon, square, svd_of_maps


def test_singular_values_match_svd():
    V2, F = mesh_polygon(square(4), area=0.05)
    rng = np.random.default_rng(1)
    uv = V2 @ np.array([[1.3, 0.4], [-0.2, 0.8]]) + 0.02 * rng.standard_normal(V2.shape)
    V = np.column_stack([V2, np.zeros(len(V2))])
    smax, smin = singular_values(V, F, uv[F], normalize=False)
    s, det = svd_of_maps(V2, uv, F)
    assert np.allclose(smax, s[:, 0]) and np.allclose(smin, s[:, 1])
    # relative to the island's scale: the same map scaled to UV area = 3D area
    k = np.sqrt(face_areas(V, F).sum() / (0.5 * np.abs(np.sum(np.cross(uv[F[:, 1]] - uv[F[:, 0]],
                                                                       uv[F[:, 2]] - uv[F[:, 0]])))))
    nmax, nmin = singular_values(V, F, uv[F])
    assert np.allclose(nmax, k * s[:, 0]) and np.allclose(nmin, k * s[:, 1])


def test_stretch_must_allow_the_conformal_bound():
    check_stretch(4.0, 2.0)
    with pytest.raises(ValueError, match=r"S >= sqrt\(C\) = 2\.236"):
        check_stretch(5.0, 2.0)


def test_deformation_within_stretch_bounds():
    """A corner pulled inwards collapses faces (smallest singular value near 0) unless bounded."""
    V, F = mesh_polygon(square(8), area=0.01)
    H = [int(np.argmin(np.linalg.norm(V - p, axis=1))) for p in [[-1, -1], [1, -1], [1, 1], [-1, 1]]]
    P = np.array([[-1, -1], [1, -1], [0.2, 0.2], [-1, 1]], float)
    S = 2.0
    free = deform(V, F, H, P, method="arap", bound=4.0)
    assert svd_of_maps(V, free.uv, F)[0][:, 1].min() < 1 / S
    res = deform(V, F, H, P, method="arap", bound=4.0, stretch=S)
    s, det = svd_of_maps(V, res.uv, F)
    assert np.all(det > 0)
    assert s[:, 1].min() >= (1 / S) * (1 - 1e-6) and s[:, 0].max() <= S * (1 + 1e-6)
    assert np.max(s[:, 0] / s[:, 1]) <= 4.0 * (1 + 1e-6)
    assert np.array_equal(res.uv[H], P)


def test_free_boundary_surface_map_within_stretch_bounds():
    """The rows as unwrap would use them: unit-area island, one vertex anchored, BD-ARAP."""
    V, F = load_off("nefertiti.off")
    isl = bd_uv.islands(V, F)[0]
    Vi = V[isl.vertices]
    Vn = (Vi - Vi.mean(0)) / np.sqrt(face_areas(Vi, isl.tris).sum())
    Z = local_coordinates(Vn, isl.tris)
    ops = jacobian_operators(Z, isl.tris, len(Vn))
    u0 = lscm_map(Z, isl.tris, len(Vn), isl.loops)
    S = 1.5
    u, _, _ = bounded_with_resets(ops, [0], [0j], frames_from_map(alpha_of(ops, u0)), 2.0,
                                  "arap", 1 / S, (1 / S, S))
    uv = np.column_stack([u.real, u.imag])
    # independent: SVD of each face's map from its own 2D shape
    P = Vn[isl.tris]
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    x = e1 / np.linalg.norm(e1, axis=1)[:, None]
    y = np.cross(np.cross(e1, e2), e1)
    y /= np.linalg.norm(y, axis=1)[:, None]
    X0 = np.stack([np.einsum("ij,ij->i", e1, x), np.einsum("ij,ij->i", e1, y)], 1)
    Y0 = np.stack([np.einsum("ij,ij->i", e2, x), np.einsum("ij,ij->i", e2, y)], 1)
    E0 = np.stack([X0, Y0], 2)
    T = uv[isl.tris]
    E1 = np.stack([T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]], 2)
    s = np.linalg.svd(E1 @ np.linalg.inv(E0), compute_uv=False)
    assert np.all(np.linalg.det(E1 @ np.linalg.inv(E0)) > 0)
    assert s[:, 1].min() >= (1 / S) * (1 - 1e-6) and s[:, 0].max() <= S * (1 + 1e-6)
    assert np.max(s[:, 0] / s[:, 1]) <= 2.0 * (1 + 1e-6)


def test_fixed_mean_scale_keeps_bounds_after_area_normalisation():
    """BD-Dirichlet rewards shrinking: without the mean-scale row it sits at 1/S and scaling the
    map to UV area = 3D area pushes its largest singular value past S."""
    V, F = load_off("nefertiti.off")
    isl = bd_uv.islands(V, F)[0]
    Vi = V[isl.vertices]
    Vn = (Vi - Vi.mean(0)) / np.sqrt(face_areas(Vi, isl.tris).sum())
    Z = local_coordinates(Vn, isl.tris)
    ops = jacobian_operators(Z, isl.tris, len(Vn))
    w = frames_from_map(alpha_of(ops, lscm_map(Z, isl.tris, len(Vn), isl.loops)))
    S, margin = 1.5, 0.01
    bounds = ((1 + margin) / S, (1 - margin) * S)
    spread = {}
    for fix in (False, True):
        u, _, _ = bounded_with_resets(ops, [0], [0j], w, 2.0, "dirichlet", bounds[0], bounds,
                                      fix_scale=fix)
        uv = np.column_stack([u.real, u.imag])
        T = uv[isl.tris]
        uv_area = 0.5 * np.sum(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]))
        uv = uv * np.sqrt(1.0 / uv_area)  # the island's scale: UV area = 3D area (= 1 here)
        smax, smin = singular_values(Vn, isl.tris, uv[isl.tris], normalize=False)
        spread[fix] = (smin.min(), smax.max())
    assert spread[False][1] > S
    assert spread[True][0] >= 1 / S and spread[True][1] <= S
