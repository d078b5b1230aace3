"""A disk's conformal system in qdldl's own order (over ``ordered_ldl.RANKED_VERTICES``) is
factorised once and refilled for its later solves with other shapes (``Disk.factors``: the capped
angles of ``capped.unfold``, the angle start's solves): the same map, bit for bit, as a new
factorisation, and the map solves its own system (checked against scipy's SuperLU).
"""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from bd_uv.geometry import corner_angles, gradient_operators
from bd_uv.mesh import check_arrays
from bd_uv.solvers.lscm import _lscm_system, face_geometry_of
from bd_uv.solvers.ordered_ldl import RANKED_VERTICES
from bd_uv.unwrapping import disk_conformal, one_disk
from bd_uv.unwrapping.capped import from_angles
from helpers import grid


def _disk(nx=41, ny=40):
    V, F = grid(nx, ny, lambda x, y: 0.3 * np.sin(5 * x) * np.cos(4 * y))
    V, F = check_arrays(V, F)
    disk = one_disk.find(V, F)
    assert disk is not None and len(disk.island.vertices) > RANKED_VERTICES
    assert disk.ranks is None          # qdldl orders the system itself
    return V, disk


def _other_shapes(disk, k):
    """The disk's faces with the corner angles of every k-th face moved (as ``capped`` rebuilds
    faces from angles at their own areas): (Z, G)."""
    A = np.abs(corner_angles(disk.Z))
    faces = np.arange(0, len(A), k)
    A2 = A[faces] * np.array([0.9, 1.0, 1.0])
    A2 *= np.pi / A2.sum(axis=1)[:, None]
    Z = disk.Z.copy()
    Z[faces] = from_angles(A2, disk.area[faces])
    return Z, gradient_operators(Z)


def _system_solution(V, disk, Z, G):
    """The conformal map of shapes Z, G solved by scipy's SuperLU from the full symmetric
    matrix (the pins as ``disk_conformal`` chooses them)."""
    isl = disk.island
    geom = face_geometry_of(Z, G, disk.area)
    idx = disk_conformal._far_pair(V.take(isl.vertices, axis=0), isl.loops[0])
    A, rhs, u, free = _lscm_system(geom.cbw(), geom.cb, isl.tris, len(isl.vertices), idx,
                                   np.array([0.0, 1.0], complex))
    full = A + sp.triu(A, k=1).T
    x = spla.spsolve(sp.csc_matrix(full), rhs)
    u[free] = x[:len(free)] + 1j * x[len(free):]
    return u


def test_refilled_solves_are_a_new_factorisations_bits():
    V, disk = _disk()
    u0 = disk_conformal.conformal(V, disk, disk.Z, disk.G, None)
    kept = disk.factors["qdldl"][0]
    for k in (7, 3):
        Z, G = _other_shapes(disk, k)
        u = disk_conformal.conformal(V, disk, Z, G, None)
        assert disk.factors["qdldl"][0] is kept          # refilled, not made anew
        _, fresh = _disk()                              # a disk with no factorisation kept
        assert np.array_equal(u, disk_conformal.conformal(V, fresh, Z, G, None))
        ref = _system_solution(V, disk, Z, G)
        assert np.abs(u - ref).max() <= 1e-9 * np.abs(ref).max()
        assert np.abs(u - u0).max() > 1e-6 * np.abs(u0).max()   # other shapes, another map
    # the disk's own shapes again: its first map, bit for bit
    assert np.array_equal(disk_conformal.conformal(V, disk, disk.Z, disk.G, None), u0)
    disk.forget_factors()
    assert "factors" not in disk.__dict__


def test_another_pattern_is_factorised_anew():
    V, disk = _disk()
    disk_conformal.conformal(V, disk, disk.Z, disk.G, None)
    kept = disk.factors
    V2, other = _disk(43, 40)          # more vertices: another pattern
    other.__dict__["factors"] = kept   # handed the first disk's factorisation
    u = disk_conformal.conformal(V2, other, other.Z, other.G, None)
    ref = _system_solution(V2, other, other.Z, other.G)
    assert np.abs(u - ref).max() <= 1e-9 * np.abs(ref).max()
    assert len(kept["qdldl"][1][0]) == 2 * (len(other.island.vertices) - 2) + 1
