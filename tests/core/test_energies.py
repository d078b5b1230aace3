"""BD-Biharmonic (eq. 6.1) and L1 stretch energies, against independent formulas."""
import numpy as np

from bd_uv.deform import solve_with_handles
from bd_uv.energies import (biharmonic_matrix, cotangent_laplacian, energy, jacobian_operators,
                            lumped_mass)
from bd_uv.frames import frames_from_map
from bd_uv.geometry import local_coordinates
from planar import boundary_edges, circle, mesh_polygon, square, svd_of_maps


def cot_laplacian_reference(V2, F):
    """L_ij = -(cot of the angles opposite edge ij)/2, rows summing to 0 (dense)."""
    n = len(V2)
    L = np.zeros((n, n))
    for k in range(3):
        i, j, o = F[:, (k + 1) % 3], F[:, (k + 2) % 3], F[:, k]
        a, b = V2[i] - V2[o], V2[j] - V2[o]
        cot = np.einsum("ij,ij->i", a, b) / np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
        np.add.at(L, (i, j), -0.5 * cot)
        np.add.at(L, (j, i), -0.5 * cot)
    L -= np.diag(L.sum(1))
    return L


def ops_of(V2, F):
    return jacobian_operators(local_coordinates(np.column_stack([V2, 0 * V2[:, 0]]), F), F,
                              len(V2))


def test_cotangent_laplacian_and_biharmonic_energy():
    V2, F = mesh_polygon(square(5), [circle(8, 0.3)[::-1]], [[0, 0]], area=0.05)
    ops = ops_of(V2, F)
    L = cot_laplacian_reference(V2, F)
    assert np.allclose(cotangent_laplacian(ops).toarray(), L)
    A = 0.5 * np.abs(np.cross(V2[F[:, 1]] - V2[F[:, 0]], V2[F[:, 2]] - V2[F[:, 0]]))
    M = np.zeros(len(V2))
    np.add.at(M, F.ravel(), np.repeat(A / 3, 3))
    assert np.allclose(lumped_mass(ops), M)
    K = L @ np.diag(1 / M) @ L
    assert np.allclose(biharmonic_matrix(ops).toarray(), K)
    rng = np.random.default_rng(0)
    u = rng.standard_normal(len(V2)) + 1j * rng.standard_normal(len(V2))
    P, q, const = energy("biharmonic", ops, np.ones(len(F)))
    x = np.concatenate([u.real, u.imag])
    assert np.isclose(0.5 * x @ (P @ x) + q @ x + const, np.real(np.conj(u) @ K @ u))


def l1_stretch(V2, uv, F):
    s, _ = svd_of_maps(V2, uv, F)
    A = 0.5 * np.abs(np.cross(V2[F[:, 1]] - V2[F[:, 0]], V2[F[:, 2]] - V2[F[:, 0]]))
    return float(np.sum(s.sum(1) * A))


def test_l1_stretch_optimum_is_no_higher_than_bd_dirichlet_on_the_same_space():
    V2, F = mesh_polygon(square(6), area=0.02)
    ops = ops_of(V2, F)
    b = np.unique(boundary_edges(F))
    # boundary: the square squeezed into a trapezoid; one interior vertex pulled sideways
    tgt = V2[b] * [1.0, 1.0] + np.column_stack([0.4 * V2[b, 1] * (V2[b, 0] + 1), 0 * b])
    c = int(np.argmin(np.linalg.norm(V2 - [0.0, 0.0], axis=1)))
    idx = np.concatenate([b, [c]])
    val = np.concatenate([tgt[:, 0] + 1j * tgt[:, 1], [0.5 + 0.1j]])
    x0 = np.concatenate([V2[:, 0], V2[:, 1]])
    w = frames_from_map(ops.Are @ x0 + 1j * (ops.Aim @ x0))
    C = 4.0
    results = {}
    for method in ("dirichlet", "stretch-l1"):
        u, sol = solve_with_handles(ops, idx, val, w, C, method, 1e-3)
        assert sol.outcome == "solved"
        uv = np.column_stack([u.real, u.imag])
        s, det = svd_of_maps(V2, uv, F)
        assert np.all(det > 0) and np.max(s[:, 0] / s[:, 1]) <= C * (1 + 1e-5)
        results[method] = l1_stretch(V2, uv, F)
    assert results["stretch-l1"] <= results["dirichlet"] * (1 + 1e-6)
