"""The compaction's linear programs through scipy's HiGHS binding (packing/highs_lp.py): the
same answers as linprog's highs-ds, checked against the constraints and the optimum; solved as
their dual, the same optimum (and the same x where only one is optimal)."""
import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.sparse import random as sparse_random

from bd_uv.packing import PackOptions, highs_lp
from bd_uv.packing.compact import compact_square
from bd_uv.packing.outlines import chart_outlines
from bd_uv.packing.square import square_layout
from packing_sets import chart_set
from test_pack_compaction import _inside_and_apart


def _program(seed, m=300, n=31, generic=False):
    """A tall program like a compaction step's: min x_n over A x <= b, box bounds, feasible at
    0 (b > 0), bounded by the boxes. ``generic``: a cost on every column too, so that one x is
    optimal (with x_n's alone many are)."""
    rng = np.random.default_rng(seed)
    A = sparse_random(m, n, density=0.1, random_state=seed, format="csr")
    A.data = rng.normal(size=A.nnz)
    A = A.tolil()
    A[:, n - 1] = rng.uniform(0.1, 1.0, size=(m, 1))   # the side: every row holds it
    A = A.tocsr()
    b = rng.uniform(0.5, 2.0, m)
    lb, ub = -rng.uniform(0.5, 1.5, n), rng.uniform(0.5, 1.5, n)
    cost = rng.normal(size=n) if generic else np.zeros(n)
    cost[-1] = -1.0     # the side as large as the rows allow
    return cost, A, b, lb, ub


@pytest.mark.parametrize("seed", range(6))
def test_the_binding_solves_as_linprog_does(seed):
    cost, A, b, lb, ub = _program(seed)
    x, status = highs_lp.solve_lp(cost, A, b, lb, ub, 10.0)
    ref = linprog(cost, A_ub=A, b_ub=b, bounds=np.stack([lb, ub], 1), method="highs-ds",
                  options={"presolve": False})
    assert status == 0 and ref.status == 0
    # feasible, recomputed here
    assert np.all(A @ x <= b + 1e-9) and np.all(x >= lb - 1e-12) and np.all(x <= ub + 1e-12)
    # optimal: the same objective as linprog's (the same dual simplex, the same program)
    assert cost @ x == pytest.approx(ref.fun, abs=1e-9)
    assert np.allclose(x, ref.x, atol=1e-9)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("generic", [False, True])
def test_the_dual_gives_the_same_optimum(seed, generic):
    """The program solved as its dual (x its row duals): feasible, linprog's optimum, and
    linprog's x where only one x is optimal."""
    cost, A, b, lb, ub = _program(seed, generic=generic)
    ref = linprog(cost, A_ub=A, b_ub=b, bounds=np.stack([lb, ub], 1), method="highs-ds",
                  options={"presolve": False})
    for core in (highs_lp._core, lambda: None):   # the binding, then linprog on the dual
        highs_lp._core, saved = core, highs_lp._core
        try:
            x, status = highs_lp.solve_lp(cost, A, b, lb, ub, 10.0, dual=True)
        finally:
            highs_lp._core = saved
        assert status == 0 and ref.status == 0
        assert np.all(A @ x <= b + 1e-9) and np.all(x >= lb - 1e-9) and np.all(x <= ub + 1e-9)
        assert cost @ x == pytest.approx(ref.fun, abs=1e-9)
        if generic:
            assert np.allclose(x, ref.x, atol=1e-7)


def test_an_infeasible_program_is_reported_infeasible():
    cost, A, b, lb, ub = _program(7, m=50, n=5)
    A = A.tolil()
    A[0, :] = 0.0
    A[0, 0] = 1.0
    b[0] = lb[0] - 1.0       # x_0 <= lb_0 - 1: no x
    x, status = highs_lp.solve_lp(cost, A.tocsr(), b, lb, ub, 10.0)
    assert x is None and status == 2
    x, status = highs_lp.solve_lp(cost, A.tocsr(), b, lb, ub, 10.0, dual=True)
    assert x is None and status == 2     # (its dual unbounded)
    assert linprog(cost, A_ub=A.tocsr(), b_ub=b, bounds=np.stack([lb, ub], 1),
                   method="highs-ds", options={"presolve": False}).status == 2


def test_without_the_binding_linprog_gives_the_same_compaction(monkeypatch):
    """The compaction of spyrrow's first placement (no search: the same every run), 25 programs:
    the same steps and side through the binding and through linprog (both solve each program's
    dual first: a chart that does not hold the side may turn otherwise, the optimum holding
    many turns), the square smaller, and the outlines inside it and the padding apart (brute
    force) both ways."""
    V, F, uv, lab = chart_set("holes", 12, seed=11)
    options = PackOptions(resolution=1024, padding_px=4, rotate="any", solves=1)
    charts, tol = chart_outlines(V, F, uv, lab, 12, options)
    pl0, side0, _ = square_layout(charts.outlines, options, tol, 0.0)
    runs = []
    for core in (highs_lp._core, lambda: None):   # the binding, then linprog
        monkeypatch.setattr(highs_lp, "_core", core)
        runs.append(compact_square(charts.outlines, pl0, side0, options, tol, 1e9,
                                   max_programs=25))
    (pa, sa, na), (pb, sb, nb) = runs
    assert na == nb and na >= 1 and sa < side0 * (1 - 1e-3)
    assert sa == pytest.approx(sb, rel=1e-9)
    _inside_and_apart(charts, pa, sa, options, tol)
    _inside_and_apart(charts, pb, sb, options, tol)
