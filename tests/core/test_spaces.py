"""The second-order-cone space of one face contains exactly the maps with D <= C and
Re(w alpha) >= sigma in that face's frame (Lipman 2012, eqs. 4.15-4.17, Proposition 4.1)."""
import numpy as np

from bd_uv.energies import jacobian_operators
from bd_uv.geometry import local_coordinates
from bd_uv.spaces import bounded_distortion_space


def _member(A, b, cones, x):
    s = b - A @ x
    k = cones[0][1]
    lin = s[:k]
    soc = s[k:].reshape(-1, 3)
    return bool(np.all(lin >= -1e-12) and np.all(np.linalg.norm(soc[:, 1:], axis=1) <= soc[:, 0] + 1e-12))


def test_soc_space_is_exactly_bounded_distortion_with_positive_real_alpha():
    V = np.array([[0, 0, 0], [1.3, 0.1, 0], [0.4, 0.9, 0]], float)
    tris = np.array([[0, 1, 2]])
    Z = local_coordinates(V, tris)
    ops = jacobian_operators(Z, tris, 3)
    rng = np.random.default_rng(3)
    C, sigma = 3.0, 0.5
    w = np.exp(1j * 0.4)
    A, b, cones = bounded_distortion_space(ops, np.array([w]), C, sigma, "soc")
    z = Z[0]
    inside = outside = 0
    for _ in range(3000):
        alpha = complex(*rng.normal(scale=2, size=2))
        beta = complex(*rng.normal(scale=1.5, size=2))
        u = alpha * z + beta * np.conj(z) + complex(*rng.normal(size=2))
        x = np.concatenate([u.real, u.imag])
        ra = (w * alpha).real
        D = (abs(alpha) + abs(beta)) / (abs(alpha) - abs(beta)) if abs(alpha) > abs(beta) else np.inf
        # Independent characterisation: D <= C and Re(w alpha) >= sigma and |beta| <= k Re(w alpha)
        k = (C - 1) / (C + 1)
        expected = ra >= sigma and abs(beta) <= k * ra
        if ra >= sigma and abs(beta) <= k * ra:
            assert D <= C + 1e-9  # members are bounded-distortion, orientation-preserving maps
        got = _member(A, b, cones, x)
        assert got == expected
        inside += got
        outside += not got
    assert inside > 100 and outside > 100


def test_linf_space_is_inside_soc_space():
    V = np.array([[0, 0, 0], [1.0, 0, 0], [0.3, 0.8, 0]], float)
    tris = np.array([[0, 1, 2]])
    Z = local_coordinates(V, tris)
    ops = jacobian_operators(Z, tris, 3)
    A1, b1, c1 = bounded_distortion_space(ops, np.array([1 + 0j]), 4.0, 0.1, "soc")
    A2, b2, c2 = bounded_distortion_space(ops, np.array([1 + 0j]), 4.0, 0.1, "linf")
    rng = np.random.default_rng(4)
    n_in = 0
    for _ in range(2000):
        x = rng.normal(size=6)
        if np.all(b2 - A2 @ x >= 0):
            n_in += 1
            assert _member(A1, b1, c1, x)  # eq. 4.22 space is a subset (Proposition 4.2)
    assert n_in > 20
