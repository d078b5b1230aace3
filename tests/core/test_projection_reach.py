"""Projection iterations give up on an island that is clearly out of reach (``solvers.reach``), and
nothing else changes: runs that certify take the same iterations to the same map.

The out-of-reach island is a cone cap whose apex is off-centre. Any flip-free flattening opens the
apex's angles to 2 pi, and a linear map of conformal distortion K turns an angle a into at most
2 atan(K tan(a / 2)), so no map of the island is within K* (``apex_bound``, recomputed here from
the 3D angles alone) of the bisection on sum 2 atan(K tan(a_i / 2)) = 2 pi. At C = 0.7 K* the
island cannot certify, whatever the solver does."""
import numpy as np
import pytest

from bd_uv.energies import jacobian_operators
from bd_uv.frames import lscm_map
from bd_uv.geometry import local_coordinates
from bd_uv.mesh import islands
from bd_uv.options import unwrap_options
from bd_uv.seams.needed import unwrap_needed
from bd_uv.solvers.projection import ProjectionSolver
from bd_uv.solvers.reach import REACH_WINDOW, Progress

from helpers import grid, load_off, reference_distortion


def cone(n=12, h=1.2, rings=5, apex=(0.5, 0.1)):
    """A cone cap over the unit circle, apex at ``apex`` (x, y) and height h, ``rings`` rings of
    n vertices: (V, F), the apex is vertex 0."""
    V = [[apex[0], apex[1], h]]
    for r in range(1, rings + 1):
        t = r / rings
        for j in range(n):
            p = (1 - t) * np.asarray(apex) + t * np.array([np.cos(2 * np.pi * j / n),
                                                            np.sin(2 * np.pi * j / n)])
            V.append([p[0], p[1], h * (1 - t)])
    F = [[0, 1 + j, 1 + (j + 1) % n] for j in range(n)]
    for r in range(1, rings):
        o, p = 1 + (r - 1) * n, 1 + r * n
        for j in range(n):
            a, b, c, d = o + j, o + (j + 1) % n, p + j, p + (j + 1) % n
            F += [[a, c, d], [a, d, b]]
    return np.array(V, dtype=float), np.array(F)


def apex_bound(V, F):
    """The least max conformal distortion any flip-free flattening can have, from vertex 0's
    angles (see the module docstring)."""
    a = []
    for f in F[(F == 0).any(axis=1)]:
        i = list(f).index(0)
        u, v = V[f[(i + 1) % 3]] - V[0], V[f[(i + 2) % 3]] - V[0]
        a.append(np.arccos(u @ v / np.linalg.norm(u) / np.linalg.norm(v)))
    a = np.array(a)
    assert a.sum() < 2 * np.pi     # a cone: the angles must open
    lo, hi = 1.0, 1e6
    for _ in range(200):
        K = np.sqrt(lo * hi)
        lo, hi = (lo, K) if np.sum(2 * np.arctan(K * np.tan(a / 2))) >= 2 * np.pi else (K, hi)
    return hi


def _island(V, F):
    isl = islands(V, F)[0]
    Vi = V[isl.vertices]
    Z = local_coordinates(Vi, isl.tris)
    ops = jacobian_operators(Z, isl.tris, len(Vi))
    return Vi, isl, ops, lscm_map(Z, isl.tris, len(Vi), isl.loops)


def test_cone_beyond_its_bound_is_given_up_in_a_window_not_the_budget():
    V, F = cone()
    K = apex_bound(V, F)
    Vi, isl, ops, u0 = _island(V, F)
    C = 0.7 * K
    runs = {}
    for reach in (REACH_WINDOW, None):
        S = ProjectionSolver(ops, len(Vi), isl.loops[0][:1], tris=isl.tris)
        runs[reach] = S.project(u0, C, max_iter=300, reach=reach)
    early, full = runs[REACH_WINDOW], runs[None]
    assert not early.all_converged and not full.all_converged      # the same fallback
    assert early.out_of_reach.tolist() == [True] and full.out_of_reach.tolist() == [False]
    assert full.iterations == 300                  # the absolute distance kept dropping: budget
    assert early.iterations <= 2 * REACH_WINDOW    # given up after one window without progress
    # what it returns is no better than the bound any flattening has, recomputed from its UVs
    for r in runs.values():
        D, flipped = reference_distortion(Vi, isl.tris, np.stack([r.u.real, r.u.imag], -1)[
            isl.tris])
        assert flipped.any() or D.max() >= K * (1 - 1e-9)


def _same_runs(ops, nv, fixed, tris, u0, C):
    out = []
    for reach in (REACH_WINDOW, None):
        S = ProjectionSolver(ops, nv, fixed, tris=tris)
        out.append(S.project(u0, C, reach=reach))
    a, b = out
    assert a.iterations == b.iterations and np.array_equal(a.u, b.u)
    assert a.converged.tolist() == b.converged.tolist() and not a.out_of_reach.any()
    return a


def test_runs_that_certify_are_unchanged():
    # The cone above its bound, a bumpy grid and three_peaks from their flipping LSCM maps: the
    # same iterations to the same bits as without the test, each map within C by an SVD.
    V, F = cone()
    K = apex_bound(V, F)
    cases = [(V, F, 1.1 * K), (*grid(14, 12, z=lambda x, y: 0.35 * np.sin(7 * x) * np.cos(6 * y)
                                     + 0.3 * x * y), 1.5), (*load_off("three_peaks.off"), 5.0)]
    for V, F, C in cases:
        Vi, isl, ops, u0 = _island(V, F)
        r = _same_runs(ops, len(Vi), isl.loops[0][:1], isl.tris, u0, C)
        assert r.all_converged
        D, flipped = reference_distortion(Vi, isl.tris, np.stack([r.u.real, r.u.imag], -1)[
            isl.tris])
        assert not flipped.any() and D.max() <= C * (1 + 1e-9)


def test_progress_tells_shrinking_from_progress():
    C, n = 2.0, 1
    # shrinking: the distance falls 3 % an iteration, but so does the size, and the max stays at
    # 2 C: out of reach after one window (the absolute test alone would never fire)
    p = Progress(C, n, stall=30)
    stops = [bool(p.update(it, np.array([0.97 ** it]), np.array([50 * 0.97 ** it]),
                           np.array([2 * C]))[0]) for it in range(100)]
    assert stops.index(True) == REACH_WINDOW and p.out_of_reach.tolist() == [True]
    # the max distortion falling by 2 % of its excess over C every iteration: never
    p = Progress(C, n, stall=30)
    stops = [bool(p.update(it, np.array([0.97 ** it]), np.array([50 * 0.97 ** it]),
                           np.array([C + 3 * 0.98 ** it]))[0]) for it in range(100)]
    assert not any(stops)
    # stuck, but within REACH_FAR of C (1.05 C): left to the absolute test
    p = Progress(C, n, stall=30)
    stops = [bool(p.update(it, np.array([0.97 ** it]), np.array([50 * 0.97 ** it]),
                           np.array([1.05 * C]))[0]) for it in range(100)]
    assert not any(stops)
    # the absolute distance flat: stalled after ``stall`` iterations, not out of reach
    p = Progress(C, n, stall=30, window=None)
    stops = [bool(p.update(it, np.array([1.0]), np.array([50.0]), np.array([2 * C]))[0])
             for it in range(100)]
    assert stops.index(True) == 30 and not p.out_of_reach.any()


def test_needed_mode_cuts_the_cone_after_a_window_with_the_same_charts(monkeypatch):
    V, F = cone()
    K = apex_bound(V, F)
    project = ProjectionSolver.project
    results = {}
    for reach in (REACH_WINDOW, None):
        runs = []

        def spy(self, *args, _reach=reach, _runs=runs, **kw):
            r = project(self, *args, **{"reach": _reach, **kw})
            _runs.append(r)
            return r
        monkeypatch.setattr(ProjectionSolver, "project", spy)
        results[reach] = (unwrap_needed(V, F, options=unwrap_options(bound=0.7 * K)), runs)
    monkeypatch.setattr(ProjectionSolver, "project", project)
    (a, ra), (b, rb) = results[REACH_WINDOW], results[None]
    # the same fallback: seams added, the same charts, the same UVs, every chart certified
    assert len(a.seams_added) and np.array_equal(a.seams_added, b.seams_added)
    assert np.array_equal(a.face_island, b.face_island)
    assert np.array_equal(a.corner_uv, b.corner_uv)
    assert all(i.status == "certified" for i in a.islands) and len(a.islands) >= 2
    # the island as marked went through both starts of the projection (LSCM, then harmonic)
    assert sum(r.iterations for r in rb) >= 600
    from bd_uv.solvers.flip_free import WINDOW     # (the LSCM start's first WINDOW run again)
    assert sum(r.iterations for r in ra) <= 4 * REACH_WINDOW + WINDOW
    # given up (the LSCM start's first ``flip_free.WINDOW`` iterations aside: run again in full
    # where one of them is flip-free)
    assert all(r.out_of_reach.all() for r in ra if not r.all_converged
               and r.iterations != WINDOW)


@pytest.mark.parametrize("shrink", [0.9, 0.0])
def test_union_gives_up_on_the_cone_once_the_other_island_certified(shrink):
    # The cone beside a flat grid (certified at once): the cone continues alone on a smaller
    # system (shrink 0.9) or in the union (0), and is given up; the grid is untouched.
    V, F = cone()
    K = apex_bound(V, F)
    Vc, ic, _, uc = _island(V, F)
    Vg, ig, _, ug = _island(*grid(8, 7))
    nc = len(Vc)
    tris = np.concatenate([ic.tris, ig.tris + nc])
    Z = np.concatenate([local_coordinates(Vc, ic.tris), local_coordinates(Vg, ig.tris)])
    ops = jacobian_operators(Z, tris, nc + len(Vg))
    u0 = np.concatenate([uc, ug + 5.0])
    fixed = [ic.loops[0][0], ig.loops[0][0] + nc]
    S = ProjectionSolver(ops, nc + len(Vg), fixed, tris=tris)
    r = S.project(u0, 0.7 * K, max_iter=300, shrink=shrink)
    cone_c, grid_c = r.component[0], r.component[nc]
    assert r.converged[grid_c] and not r.converged[cone_c]
    assert r.out_of_reach[cone_c] and not r.out_of_reach[grid_c]
    assert r.iterations <= 2 * REACH_WINDOW
    assert np.array_equal(r.u[nc:], u0[nc:])
