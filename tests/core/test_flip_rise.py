"""The LSCM start's projection (``flip_free.flip_free_map``) is given up after its first iterate
where that flips more than FLIP_RISE times as many faces as the start does (``ProjectionSolver.
project``'s ``flip_rise``), not after its WINDOW of iterations; nothing else changes.

A ring patch of cow.off whose LSCM map flips 3 faces: its projection's first iterate flips 10,
and none of its 20 iterations is flip-free. The flip counts are recomputed from the UVs by an SVD
of each face's Jacobian in its own 3D frame (``helpers.reference_distortion``); the unwrap's maps
with the rule and without it are compared bit for bit, and certified from the stored UVs
(``unwrap_contract.distortion_and_flips``)."""
import numpy as np
import pytest

import bd_uv
from bd_uv.energies import jacobian_operators
from bd_uv.frames import lscm_map
from bd_uv.geometry import local_coordinates
from bd_uv.mesh import islands
from bd_uv.solvers import flip_free
from bd_uv.solvers.projection import ProjectionSolver

from helpers import load_off, reference_distortion, rings
from unwrap_contract import distortion_and_flips

# (seed face, faces at least) of cow.off: 318 faces, its LSCM map flips 3 faces
BLOWS_UP = (4648, 300)


def _island(V, F):
    isl = islands(V, F)[0]
    Vi = V[isl.vertices]
    Z = local_coordinates(Vi, isl.tris)
    ops = jacobian_operators(Z, isl.tris, len(Vi))
    return Vi, isl, ops, Z, lscm_map(Z, isl.tris, len(Vi), isl.loops)


def _flips(Vi, tris, u):
    return int(reference_distortion(Vi, tris, np.stack([u.real, u.imag], -1)[tris])[1].sum())


def test_a_start_whose_first_iterate_flips_more_is_given_up_after_it():
    Vi, isl, ops, Z, u0 = _island(*rings(*load_off("cow.off"), *BLOWS_UP))
    rule = (flip_free.FLIP_RISE, flip_free.FLIP_LEAST)
    start = _flips(Vi, isl.tris, u0)
    assert start >= flip_free.FLIP_LEAST
    S = ProjectionSolver(ops, len(Vi), isl.loops[0][:1], tris=isl.tris)
    # the first iterate (the least-distorted iterate kept while every one flips), recomputed
    first = S.project(u0, 5.0, max_iter=2).u
    assert _flips(Vi, isl.tris, first) > flip_free.FLIP_RISE * start
    S = ProjectionSolver(ops, len(Vi), isl.loops[0][:1], tris=isl.tris)
    r = S.project(u0, 5.0, max_iter=flip_free.WINDOW, flip_rise=rule)
    assert r.iterations == 1 and not r.all_converged and r.out_of_reach.tolist() == [True]
    # without the rule: the window, no iterate flip-free, given up all the same
    u, info = flip_free.flip_free_map(Z, isl.tris, len(Vi), isl.loops, u0, 5.0, harmonic=False)
    assert u is None and info["iterations"] == 1
    flip_free.FLIP_LEAST, least = 10 ** 9, flip_free.FLIP_LEAST
    try:
        u, info = flip_free.flip_free_map(Z, isl.tris, len(Vi), isl.loops, u0, 5.0,
                                          harmonic=False)
    finally:
        flip_free.FLIP_LEAST = least
    assert u is None and info["iterations"] == flip_free.WINDOW


def test_starts_that_bend_are_unchanged():
    # three_peaks' LSCM map flips 30 faces, its first iterate 13: the same iterations to the
    # same bits with the rule as without, within C by an SVD
    Vi, isl, ops, _, u0 = _island(*load_off("three_peaks.off"))
    assert _flips(Vi, isl.tris, u0) >= flip_free.FLIP_LEAST
    runs = []
    for rule in (None, (flip_free.FLIP_RISE, flip_free.FLIP_LEAST)):
        S = ProjectionSolver(ops, len(Vi), isl.loops[0][:1], tris=isl.tris)
        runs.append(S.project(u0, 5.0, flip_rise=rule))
    a, b = runs
    assert a.all_converged and a.iterations == b.iterations and np.array_equal(a.u, b.u)
    D, flipped = reference_distortion(Vi, isl.tris, np.stack([b.u.real, b.u.imag], -1)[isl.tris])
    assert not flipped.any() and D.max() <= 5.0 * (1 + 1e-9)


@pytest.mark.parametrize("bound", ["auto", 5.0])
def test_the_unwrap_gives_the_same_map_with_fewer_iterations(monkeypatch, bound):
    V, F = rings(*load_off("cow.off"), *BLOWS_UP)
    res = bd_uv.unwrap(V, F, bound=bound)
    monkeypatch.setattr(flip_free, "FLIP_LEAST", 10 ** 9)
    ref = bd_uv.unwrap(V, F, bound=bound)
    assert np.array_equal(res.corner_uv, ref.corner_uv)
    assert [r.bound_certified for r in res.islands] == [r.bound_certified for r in ref.islands]
    # the LSCM start's window: 20 projection iterations, now 1 (at C = 5 on each of the pieces
    # the disk is cut into, 7, and on the disk before: 133 fewer)
    fewer = sum(r.iterations for r in ref.islands) - sum(r.iterations for r in res.islands)
    assert fewer > 0 and fewer % (flip_free.WINDOW - 1) == 0
    if bound == "auto":
        assert fewer == flip_free.WINDOW - 1
    D, flipped = distortion_and_flips(V, F, res.corner_uv)
    assert all(r.status == "certified" for r in res.islands) and not flipped.any()
    for r in res.islands:
        assert D[r.faces].max() <= r.bound_certified
