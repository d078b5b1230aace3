"""Projection iterations (Kovalsky et al. 2015) onto the bounded-distortion set: every result is
re-checked here from its UVs with an SVD of each face's 2x2 map (tests/core/helpers.py)."""
import numpy as np
import pytest

from bd_uv.energies import jacobian_operators
from bd_uv.errors import CancelledError
from bd_uv.frames import harmonic_map, lscm_map
from bd_uv.geometry import local_coordinates
from bd_uv.mesh import islands
from bd_uv.solvers.flip_free import flip_free_map
from bd_uv.solvers.local_projection import project_singular_values
from bd_uv.solvers.projection import ProjectionSolver

from helpers import grid, load_off, reference_distortion


def _setup(V, F):
    isl = islands(V, F)[0]
    Vi = V[isl.vertices]
    Z = local_coordinates(Vi, isl.tris)
    return Vi, isl, Z, jacobian_operators(Z, isl.tris, len(Vi))


def _check(Vi, tris, u, C, rtol=1e-9):
    D, flipped = reference_distortion(Vi, tris, np.stack([u.real, u.imag], -1)[tris])
    assert not flipped.any()
    assert np.all(D <= C * (1 + rtol))
    return D


def _bumpy():
    return grid(14, 12, z=lambda x, y: 0.35 * np.sin(7 * x) * np.cos(6 * y) + 0.3 * x * y)


def test_singular_value_projection_is_the_nearest_point_of_the_polygon():
    rng = np.random.default_rng(0)
    s2 = rng.normal(scale=2.0, size=400)
    s1 = s2 + np.abs(rng.normal(scale=3.0, size=400))
    kappa, lo, hi = 2.5, np.full(400, 0.3), np.full(400, 4.0)
    t1, t2, moved = project_singular_values(s1, s2, kappa, lo, hi)
    # Brute force over a fine sampling of the polygon.
    g1, g2 = np.meshgrid(np.linspace(0.3, 4.0, 600), np.linspace(0.3, 4.0, 600))
    ok = (g2 <= g1) & (g1 <= kappa * g2)
    P = np.stack([g1[ok], g2[ok]], 1)
    d_brute = np.min((P[None, :, 0] - s1[:, None]) ** 2 + (P[None, :, 1] - s2[:, None]) ** 2, 1)
    d = (t1 - s1) ** 2 + (t2 - s2) ** 2
    assert np.all(d <= d_brute + 1e-9)
    assert np.all((t2 >= 0.3 - 1e-12) & (t1 <= kappa * t2 + 1e-12) & (t1 <= 4.0 + 1e-12))
    assert np.array_equal(moved, ~((s2 >= 0.3) & (s1 <= kappa * s2) & (s1 <= 4.0)))


@pytest.mark.parametrize("start", ["lscm", "harmonic"])
def test_bumpy_grid_certifies_from_both_starts(start):
    V, F = _bumpy()
    Vi, isl, Z, ops = _setup(V, F)
    nv = len(Vi)
    u0 = lscm_map(Z, isl.tris, nv, isl.loops) if start == "lscm" else harmonic_map(
        Z, isl.tris, nv, isl.loops)
    D0, _ = reference_distortion(Vi, isl.tris, np.stack([u0.real, u0.imag], -1)[isl.tris])
    C = 1.5
    assert D0.max() > C  # the bound is active
    S = ProjectionSolver(ops, nv, [isl.loops[0][0]], tris=isl.tris)
    r = S.project(u0, C)
    assert r.all_converged and r.iterations > 0
    D = _check(Vi, isl.tris, r.u, C)
    assert np.isclose(r.max_distortion[0], D.max())
    assert r.u[isl.loops[0][0]] == u0[isl.loops[0][0]]  # the fixed vertex stays


@pytest.mark.parametrize("start", ["lscm", "harmonic"])
def test_three_peaks_certifies_from_flipping_lscm_and_from_harmonic(start):
    V, F = load_off("three_peaks.off")
    Vi, isl, Z, ops = _setup(V, F)
    nv = len(Vi)
    u0 = lscm_map(Z, isl.tris, nv, isl.loops) if start == "lscm" else harmonic_map(
        Z, isl.tris, nv, isl.loops)
    if start == "lscm":  # this start flips faces
        uv = np.stack([u0.real, u0.imag], -1)[isl.tris]
        assert reference_distortion(Vi, isl.tris, uv)[1].any()
    S = ProjectionSolver(ops, nv, [isl.loops[0][0]], tris=isl.tris)
    r = S.project(u0, 5.0)
    assert r.all_converged
    _check(Vi, isl.tris, r.u, 5.0)


def test_map_within_bound_comes_back_unchanged_after_zero_iterations():
    V, F = _bumpy()
    Vi, isl, Z, ops = _setup(V, F)
    u0 = lscm_map(Z, isl.tris, len(Vi), isl.loops)
    S = ProjectionSolver(ops, len(Vi), [isl.loops[0][0]], tris=isl.tris)
    r = S.project(u0, 50.0)
    assert r.iterations == 0 and r.all_converged
    assert np.array_equal(r.u, u0)


def test_union_of_two_islands_each_certified_the_easy_one_untouched():
    V1, F1 = _bumpy()
    V2, F2 = grid(5, 4)  # flat: its LSCM map is an isometry
    Va, isla, Za, _ = _setup(V1, F1)
    Vb, islb, Zb, _ = _setup(V2, F2)
    ua = lscm_map(Za, isla.tris, len(Va), isla.loops)
    ub = lscm_map(Zb, islb.tris, len(Vb), islb.loops) + 5.0
    tris = np.concatenate([isla.tris, islb.tris + len(Va)])
    Z = np.concatenate([Za, Zb])
    nv = len(Va) + len(Vb)
    ops = jacobian_operators(Z, tris, nv)
    S = ProjectionSolver(ops, nv, [isla.loops[0][0], len(Va) + islb.loops[0][0]], tris=tris)
    assert S.n_components == 2
    u0 = np.concatenate([ua, ub])
    r = S.project(u0, 1.5)
    assert r.all_converged and r.converged.shape == (2,)
    _check(np.concatenate([Va, Vb]), tris, r.u, 1.5)
    ca = r.component[0]
    assert r.iterations_per_component[1 - ca] == 0
    assert np.array_equal(r.u[len(Va):], ub)  # certified at the start: frozen there


def test_stretch_bounds_are_respected():
    V, F = _bumpy()
    Vi, isl, Z, ops = _setup(V, F)
    u0 = lscm_map(Z, isl.tris, len(Vi), isl.loops)
    S = ProjectionSolver(ops, len(Vi), [isl.loops[0][0]], tris=isl.tris)
    scale = S.component_scale(u0)
    smin, smax = 0.7, 1.5  # the LSCM map spans 0.30-2.12 times the scale: both bounds active
    r = S.project(u0, 1.6, smin=smin, smax=smax, scale=scale)
    assert r.all_converged
    _check(Vi, isl.tris, r.u, 1.6)
    # Independent singular values of each face's map.
    P = Vi[isl.tris]
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    x = e1 / np.linalg.norm(e1, axis=1)[:, None]
    n = np.cross(e1, e2)
    y = np.cross(n / np.linalg.norm(n, axis=1)[:, None], x)
    Sm = np.stack([np.stack([np.einsum("ij,ij->i", e, x), np.einsum("ij,ij->i", e, y)], 1)
                   for e in (e1, e2)], 2)
    uv = np.stack([r.u.real, r.u.imag], -1)[isl.tris]
    T = np.stack([uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]], 2)
    s = np.linalg.svd(T @ np.linalg.inv(Sm), compute_uv=False)
    assert s[:, 1].min() >= smin * scale[0] * (1 - 1e-9)
    assert s[:, 0].max() <= smax * scale[0] * (1 + 1e-9)


class _CountingCancel:
    def __init__(self, fire_at=None):
        self.calls, self.fire_at = 0, fire_at

    def is_set(self):
        self.calls += 1
        return self.fire_at is not None and self.calls >= self.fire_at


def test_cancel_is_checked_once_per_iteration():
    V, F = _bumpy()
    Vi, isl, Z, ops = _setup(V, F)
    u0 = harmonic_map(Z, isl.tris, len(Vi), isl.loops)
    S = ProjectionSolver(ops, len(Vi), [isl.loops[0][0]], tris=isl.tris)
    c = _CountingCancel()
    r = S.project(u0, 1.3, cancel=c)
    assert r.iterations >= 2
    assert c.calls == r.iterations + 1  # one check per iteration, one before certifying the last
    c = _CountingCancel(fire_at=2)
    with pytest.raises(CancelledError):
        S.project(u0, 1.3, cancel=c)
    assert c.calls == 2


def test_flip_free_map_from_flipping_lscm():
    V, F = load_off("three_peaks.off")
    Vi, isl, Z, ops = _setup(V, F)
    nv = len(Vi)
    ul = lscm_map(Z, isl.tris, nv, isl.loops)
    u, info = flip_free_map(Z, isl.tris, nv, isl.loops, ul, 5.0)
    assert u is not None and info["start"] == "lscm"
    D = _check(Vi, isl.tris, u, 5.0)
    # Closer to conformal than the harmonic start (area-weighted mean).
    uh = harmonic_map(Z, isl.tris, nv, isl.loops)
    Dh, _ = reference_distortion(Vi, isl.tris, np.stack([uh.real, uh.imag], -1)[isl.tris])
    A = ops.area
    assert np.sum(A * D) < np.sum(A * Dh)


def test_no_factorisation_when_the_start_fits():
    V, F = _bumpy()
    Vi, isl, Z, ops = _setup(V, F)
    u0 = lscm_map(Z, isl.tris, len(Vi), isl.loops)
    S = ProjectionSolver(ops, len(Vi), [isl.loops[0][0]], tris=isl.tris)
    S.project(u0, 50.0)
    assert S._solve is None and S.factor_seconds == 0.0
    S.project(u0, 1.5)
    assert S._solve is not None


def test_many_islands_continue_on_the_unconverged_ones_alone():
    # One hard island among easy ones: once the easy ones certify, the hard one continues on a
    # smaller system; every island is certified and the easy ones are untouched.
    parts = [_bumpy()] + [grid(8, 7, z=lambda x, y, s=s: 0.05 * s * x * x) for s in range(4)]
    Vs, Zs, Ts, us, fixed, off = [], [], [], [], [], 0
    for V, F in parts:
        Vi, isl, Z, _ = _setup(V, F)
        Vs.append(Vi)
        Zs.append(Z)
        Ts.append(isl.tris + off)
        us.append(lscm_map(Z, isl.tris, len(Vi), isl.loops) + 3.0 * len(us))
        fixed.append(isl.loops[0][0] + off)
        off += len(Vi)
    tris, Z = np.concatenate(Ts), np.concatenate(Zs)
    ops = jacobian_operators(Z, tris, off)
    S = ProjectionSolver(ops, off, fixed, tris=tris)
    u0 = np.concatenate(us)
    r = S.project(u0, 1.5, shrink=0.9)
    assert r.all_converged
    _check(np.concatenate(Vs), tris, r.u, 1.5)
    easy = r.component >= 0
    easy[:len(Vs[0])] = False
    assert np.array_equal(r.u[easy], u0[easy])
    r2 = S.project(u0, 1.5, shrink=0.0)  # never restricted: same certification
    assert r2.all_converged


def test_flip_free_map_gives_none_when_no_start_reaches_the_bound():
    V, F = load_off("three_peaks.off")
    Vi, isl, Z, ops = _setup(V, F)
    nv = len(Vi)
    ul = lscm_map(Z, isl.tris, nv, isl.loops)
    u, info = flip_free_map(Z, isl.tris, nv, isl.loops, ul, 5.0, max_iter=1)
    assert u is None and info["start"] is None
    assert info["iterations"] == 2  # one per start: LSCM, then harmonic


def test_pinned_vertices_are_held_exactly():
    V, F = _bumpy()
    Vi, isl, Z, ops = _setup(V, F)
    u0 = harmonic_map(Z, isl.tris, len(Vi), isl.loops)
    loop = isl.loops[0]
    pins = np.array([loop[len(loop) // 2], loop[0]])  # unsorted on purpose
    S = ProjectionSolver(ops, len(Vi), pins, tris=isl.tris)
    r = S.project(u0, 1.5, fixed_values=u0[pins])
    assert r.all_converged
    _check(Vi, isl.tris, r.u, 1.5)
    assert np.array_equal(r.u[pins], u0[pins])
