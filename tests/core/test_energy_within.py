"""A map within a numeric C from the harmonic map, without a conic solve
(``unwrapping.energy_within``): the bound search into C, then the conformal energy lowered over F_C
by ADMM and the best map between the two. Checked by distortion, energy and boundary recomputed
from the UVs (``helpers.reference_jacobians``, shapely for the boundary)."""
import time

import numpy as np
import pytest
import shapely.geometry

from bd_uv.mesh import checked_islands
from bd_uv.unwrapping.energy_within import from_harmonic, lowest_energy
from bd_uv.unwrapping.initial import start_map
from bd_uv.unwrapping.problem import IslandProblem
from bd_uv.unwrapping.searched import search
from helpers import reference_distortion, reference_jacobians
from test_over_bound import _sphere_with_a_hole


def _quiet(*_):
    pass


def _problem(sub=2):
    V, F = _sphere_with_a_hole(sub)
    (isl,) = checked_islands(V, F)
    return V[isl.vertices], isl, IslandProblem(isl, V, (np.zeros(0, np.int64), np.zeros((0, 2))),
                                               "lscm", "soc", None)


def _corners(u, tris):
    return np.stack([u.real, u.imag], axis=1)[tris]


def _area(Vi, tris):
    P = Vi[tris]
    return 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)


def _mean(Vi, tris, u):
    D, flipped = reference_distortion(Vi, tris, _corners(u, tris))
    a = _area(Vi, tris)
    return float(a @ D / a.sum()), D, flipped


def _energy(Vi, tris, u):
    """sum of area |beta|^2, beta the anti-conformal part of each face's Jacobian"""
    J = reference_jacobians(Vi, tris, _corners(u, tris))
    beta = 0.5 * ((J[:, 0, 0] - J[:, 1, 1]) + 1j * (J[:, 1, 0] + J[:, 0, 1]))
    return float(_area(Vi, tris) @ np.abs(beta) ** 2)


def _searched(prob, C):
    """The bound search from the harmonic map to its first map within C, as ``from_harmonic``
    runs it (the same call, deterministic)."""
    from bd_uv.unwrapping.margins import solve_bound
    target = solve_bound(C)
    h = start_map(prob, "harmonic", None, _quiet)
    return search(prob, h.u, _quiet, None, [], time.perf_counter(),
                  enough=lambda x: prob.distortion(x) <= target)[0]


@pytest.mark.parametrize("C", [3.0, 5.0])
def test_from_harmonic_is_within_c_one_to_one_and_no_worse_than_the_search(C):
    Vi, isl, prob = _problem()
    (u, start), far = from_harmonic(prob, C, _quiet)
    assert start.name == "harmonic" and not far
    mean, D, flipped = _mean(Vi, isl.tris, u)
    assert not flipped.any() and D.max() <= C
    # the boundary a simple polygon wound counter-clockwise: the disk laid out one to one
    ring = shapely.geometry.Polygon(np.stack([u.real, u.imag], axis=1)[isl.loops[0]])
    assert ring.is_valid and ring.exterior.is_ccw
    # the energy step and the segment keep the mean at or below the searched map's
    assert mean <= _mean(Vi, isl.tris, _searched(prob, C))[0] * (1 + 1e-12)


def test_from_harmonic_gives_none_below_the_least_bound():
    # the least certified C of this disk is about 2.52 (``test_over_bound``): far above 2, not
    # far above 2.4
    Vi, isl, prob = _problem()
    assert from_harmonic(prob, 2.0, _quiet)[0] is None
    assert from_harmonic(prob, 2.4, _quiet) == (None, False)


def test_far_below_the_least_bound_from_harmonic_hands_back_a_map_for_the_raised_bound():
    """C = 2, out of reach (far: D - 1 > FAR (C - 1)): the searched map, its energy lowered
    within the first of C x 1.5^k at or above its max (3), flip-free, its max recomputed by SVD
    the one handed back, for ``bounded`` to raise the bound to."""
    Vi, isl, prob = _problem()
    found, far = from_harmonic(prob, 2.0, _quiet)
    (u, D), start = far
    assert found is None and start.name == "harmonic"
    Dr, flipped = reference_distortion(Vi, isl.tris, _corners(u, isl.tris))
    assert not flipped.any() and abs(Dr.max() - D) <= 1e-9 * D
    assert 1.0 + 1.25 * (2.0 - 1.0) < D < 3.0


def test_lowest_energy_holds_the_two_anchors_and_lowers_the_conformal_energy():
    Vi, isl, prob = _problem()
    us = _searched(prob, 3.0)
    ul = lowest_energy(prob, us, 3.0)
    held = np.flatnonzero(ul == us)                     # the two anchors, exactly
    assert len(held) == 2 and set(held.tolist()) <= set(isl.loops[0].tolist())
    assert _energy(Vi, isl.tris, ul) < _energy(Vi, isl.tris, us)
    D, flipped = reference_distortion(Vi, isl.tris, _corners(ul, isl.tris))
    assert not flipped.any() and D.max() <= 3.0 * 1.05   # near F_C, not certainly in it
