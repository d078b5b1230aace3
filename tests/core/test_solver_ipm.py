"""The Schur-complement interior-point method agrees with Clarabel on real bounded-distortion
programs (optimal energy within 1e-4 relative, the same feasibility verdict), warm-starts from a
feasible map, reuses its symbolic analysis, and checks cancel once per iteration.

The programs are built here from the repo's own spaces and energies the way the pipeline builds
them (area-1 island, frames from the LSCM map, sigma = 1, objective scaled to order 1, vertex 0
pinned), independently of pipeline.py.
"""
import numpy as np
import pytest
import scipy.sparse as sp

from bd_uv.energies import energy, jacobian_operators
from bd_uv.frames import frames_from_map, lscm_map
from bd_uv.geometry import face_areas, local_coordinates
from bd_uv.mesh import islands
from bd_uv.solvers import conic, ipm
from bd_uv.spaces import bounded_distortion_space

from helpers import grid, load_off


def _program(V, F, C, cone="soc"):
    """(P, q, A, b, cones, x_lscm) of F_C with LSCM frames, vertex 0 pinned at 0."""
    isl = islands(V, F)[0]
    Vi = V[isl.vertices]
    Vn = (Vi - Vi.mean(axis=0)) / np.sqrt(face_areas(Vi, isl.tris).sum())
    nv = len(Vi)
    Z = local_coordinates(Vn, isl.tris)
    ops = jacobian_operators(Z, isl.tris, nv)
    u = lscm_map(Z, isl.tris, nv, isl.loops)
    u = u - u[0]
    x = np.concatenate([u.real, u.imag])
    alpha = ops.Are @ x + 1j * (ops.Aim @ x)
    w = frames_from_map(alpha)
    ra = np.real(w * alpha)
    xs = x / ra.min()  # the LSCM map scaled onto the floor Re(w alpha) >= 1
    P, q, _ = energy("lscm", ops, w)
    P = P / max(0.5 * xs @ (P @ xs), 1e-6)
    A, b, cones = bounded_distortion_space(ops, w, C, 1.0, cone)
    free = np.setdiff1d(np.arange(2 * nv), [0, nv])
    return sp.csc_matrix(P)[free][:, free], q[free], A[:, free], b, cones, xs[free]


def _nefertiti():
    return load_off("nefertiti.off")


def _bumpy():
    return grid(9, 8, z=lambda x, y: 0.15 * np.sin(6 * x) * np.cos(5 * y))


def _rel(a, b):
    return abs(a - b) / max(abs(b), 1e-12)


@pytest.mark.parametrize("mesh", [_nefertiti, _bumpy])
@pytest.mark.parametrize("C", [1.5, 2.0, 5.0])
def test_agrees_with_clarabel(mesh, C):
    P, q, A, b, cones, _ = _program(*mesh(), C)
    ref = conic.solve_conic(P, q, A, b, cones)
    sol = ipm.solve_conic(P, q, A, b, cones)
    assert ref.outcome == "solved"
    assert sol.outcome == "solved", sol.status
    assert _rel(sol.objective, ref.objective) <= 1e-4
    # the returned x is (nearly) feasible and its objective is the one reported
    s = b - A @ sol.x
    nl = cones[0][1]
    assert s[:nl].min() >= -1e-6
    t = s[nl:].reshape(-1, 3)
    assert np.min(t[:, 0] - np.linalg.norm(t[:, 1:], axis=1)) >= -1e-6
    assert _rel(0.5 * sol.x @ (P @ sol.x) + q @ sol.x, sol.objective) <= 1e-12


@pytest.mark.parametrize("mesh", [_nefertiti, _bumpy])
def test_infeasible_verdict_agrees(mesh):
    # C barely above 1 on a curved surface: no piecewise-linear map is that close to conformal
    P, q, A, b, cones, _ = _program(*mesh(), 1.02)
    ref = conic.solve_conic(P, q, A, b, cones)
    sol = ipm.solve_conic(P, q, A, b, cones)
    assert ref.outcome == "infeasible"
    assert sol.outcome == "infeasible", sol.status


def test_contradictory_constraints_infeasible():
    # Re(w alpha) >= 1 and Re(w alpha) <= -1 on face 0's row: empty whatever the frames
    P, q, A, b, cones, _ = _program(*_bumpy(), 5.0)
    nl = cones[0][1]
    A2 = sp.vstack([A[:nl], -A[[0]], A[nl:]]).tocsc()
    b2 = np.concatenate([b[:nl], [-b[0] - 2.0], b[nl:]])
    cones2 = [("nonneg", nl + 1)] + cones[1:]
    assert conic.solve_conic(P, q, A2, b2, cones2).outcome == "infeasible"
    assert ipm.solve_conic(P, q, A2, b2, cones2).outcome == "infeasible"


def test_general_second_order_cones():
    # a small random program with 4- and 5-dimensional cones, against Clarabel
    rng = np.random.default_rng(3)
    n = 12
    M = rng.standard_normal((n, n))
    P = sp.csc_matrix(M @ M.T / n)
    q = rng.standard_normal(n)
    cones = [("nonneg", 6), ("soc", 4), ("soc", 5), ("soc", 4)]
    m = 6 + 4 + 5 + 4
    A = sp.csc_matrix(rng.standard_normal((m, n)) * (rng.random((m, n)) < 0.5))
    x_in = rng.standard_normal(n)
    # b so that x_in is strictly feasible: s = e-ish interior point
    s = np.zeros(m)
    s[:6] = 1.0
    s[[6, 10, 15]] = 1.0
    b = A @ x_in + s
    ref = conic.solve_conic(P, q, A, b, cones)
    sol = ipm.solve_conic(P, q, A, b, cones)
    assert ref.outcome == sol.outcome == "solved"
    assert _rel(sol.objective, ref.objective) <= 1e-5
    warm = ipm.solve_conic(P, q, A, b, cones, x0=x_in)
    assert warm.outcome == "solved" and _rel(warm.objective, ref.objective) <= 1e-5


def test_warm_start_and_reuse():
    V, F = _nefertiti()
    P, q, A, b, cones, xs = _program(V, F, 5.0)
    solver = ipm.SchurIPM(P, A, cones)
    cold = solver.solve(P, q, A, b, cones)
    # the LSCM map (flip-free, max distortion below 5) scaled onto the floor is strictly feasible
    # only with a margin; scale it up a little so that it is
    x0 = 1.01 * xs
    assert solver.cones.margin(b - A @ x0) > 0
    warm = solver.solve(P, q, A, b, cones, x0=x0)
    assert cold.outcome == warm.outcome == "solved"
    assert _rel(warm.objective, cold.objective) <= 1e-4
    # same pattern, another bound: the analysis is reused (no new factor object)
    factor = solver.factor
    P2, q2, A2, b2, cones2, _ = _program(V, F, 2.0)
    again = solver.solve(P2, q2, A2, b2, cones2, x0=cold.x)
    assert solver.factor is factor
    ref = conic.solve_conic(P2, q2, A2, b2, cones2)
    assert again.outcome == "solved" and _rel(again.objective, ref.objective) <= 1e-4


class _CountingCancel:
    def __init__(self, after=None):
        self.calls = 0
        self.after = after

    def is_set(self):
        self.calls += 1
        return self.after is not None and self.calls > self.after


def test_cancel_checked_every_iteration():
    P, q, A, b, cones, _ = _program(*_bumpy(), 2.0)
    cancel = _CountingCancel()
    sol = ipm.solve_conic(P, q, A, b, cones, cancel=cancel)
    assert sol.outcome == "solved"
    assert cancel.calls >= sol.iterations >= 1
    stop = _CountingCancel(after=3)
    sol = ipm.solve_conic(P, q, A, b, cones, cancel=stop)
    assert sol.outcome == "cancelled" and sol.status == "CallbackTerminated"
    assert stop.calls == 4 and sol.iterations == 3


def test_splu_backend_agrees():
    P, q, A, b, cones, _ = _program(*_bumpy(), 1.5)
    a = ipm.solve_conic(P, q, A, b, cones, backend="splu")
    ref = conic.solve_conic(P, q, A, b, cones)
    assert a.outcome == "solved" and _rel(a.objective, ref.objective) <= 1e-4


def test_rejects_unknown_cone():
    P, q, A, b, cones, _ = _program(*_bumpy(), 2.0)
    bad = [("zero", cones[0][1])] + cones[1:]
    assert ipm.solve_conic(P, q, A, b, bad).outcome == "error"
