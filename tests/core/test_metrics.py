import numpy as np
import pytest

import bd_uv
from bd_uv.geometry import local_coordinates
from helpers import grid, reference_distortion


def test_rigidly_moved_planar_mesh_has_distortion_one():
    V, F = grid()
    rng = np.random.default_rng(0)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    V3 = V @ Q.T + [3.0, -2.0, 7.0]                       # rigid motion in 3D
    th = 0.7
    R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    uv = (V[:, :2] @ R.T + [0.25, -1.5])[F]               # planar coordinates, rotated, moved
    D = bd_uv.conformal_distortion(V3, F, uv)
    np.testing.assert_allclose(D, 1.0, atol=1e-9)
    assert not bd_uv.flipped_faces(V3, F, uv).any()


def test_hand_built_triangle_alpha_beta():
    # Right triangle (0,0),(1,0),(0,1) mapped by (x, y) -> (2x + y, 3y): J = [[2, 1], [0, 3]]
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    F = np.array([[0, 1, 2]])
    uv = np.array([[[0, 0], [2, 0], [1, 3]]], float)
    alpha, beta = bd_uv.face_jacobians(V, F, uv)
    # alpha = ((a+d) + i(c-b))/2, beta = ((a-d) + i(c+b))/2 for J = [[a,b],[c,d]]
    assert alpha[0] == pytest.approx(complex(2.5, -0.5))
    assert beta[0] == pytest.approx(complex(-0.5, 0.5))
    s = np.linalg.svd(np.array([[2.0, 1.0], [0.0, 3.0]]), compute_uv=False)
    assert abs(alpha[0]) + abs(beta[0]) == pytest.approx(s[0])          # eq. 4.7
    assert abs(alpha[0]) - abs(beta[0]) == pytest.approx(s[1])          # eq. 4.8
    assert bd_uv.conformal_distortion(V, F, uv)[0] == pytest.approx(s[0] / s[1])


def test_flipped_and_collapsed_faces_are_infinite():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    F = np.array([[0, 1, 2], [0, 1, 2]])
    uv = np.array([[[0, 0], [0, 1], [1, 0]], [[0, 0], [1, 0], [2, 0]]], float)
    D = bd_uv.conformal_distortion(V, F, uv)
    assert np.all(np.isinf(D))
    assert bd_uv.flipped_faces(V, F, uv).all()


def test_distortion_matches_reference_on_random_maps():
    rng = np.random.default_rng(1)
    V = rng.normal(size=(30, 3))
    F = rng.integers(0, 30, size=(50, 3))
    F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])]
    uv = rng.normal(size=(len(F), 3, 2))
    D = bd_uv.conformal_distortion(V, F, uv)
    Dref, flip = reference_distortion(V, F, uv)
    ok = ~flip
    np.testing.assert_allclose(D[ok], Dref[ok], rtol=1e-8)
    assert np.all(np.isinf(D[flip]))


def test_local_coordinates_are_isometric():
    rng = np.random.default_rng(2)
    V = rng.normal(size=(3, 3))
    Z = local_coordinates(V, np.array([[0, 1, 2]]))[0]
    for i, j in [(0, 1), (1, 2), (0, 2)]:
        assert abs(Z[i] - Z[j]) == pytest.approx(np.linalg.norm(V[i] - V[j]))
    assert Z[2].imag > 0


def test_distortion_of_a_tiny_face_far_from_the_origin():
    """Issue 22 (mesh contract, seed 8): a one-face piece 5e-14 across at u = 0.98 measured
    D = 1.03456 where its UVs give 1.03407: the Jacobian summed absolute coordinates, whose
    rounding at 0.98 is 2e-3 of the face's size. Measured from the face's own corner, where it
    lies does not change D."""
    V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.3, 0.8, 0.0]])
    F = np.array([[0, 1, 2]])
    uv = np.array([[[0.0, 0.0], [1.0, 0.1], [0.2, 0.9]]]) * 5e-14
    at_origin = bd_uv.conformal_distortion(V, F, uv)
    far = uv + [0.985407614873111, 0.5037187684895323]
    ref, _ = reference_distortion(V, F, far)      # numpy SVD of the stored corners' differences
    assert at_origin[0] == pytest.approx(ref[0], rel=1e-9)
    assert bd_uv.conformal_distortion(V, F, far)[0] == pytest.approx(ref[0], rel=1e-9)
