"""The compaction's linear programs handed to HiGHS without ``scipy.optimize.linprog``'s wrapper.

A compaction step (:mod:`.compact_step`) solves a small, tall program (3 k + 1 columns, a few
hundred to a few thousand rows) with HiGHS' dual simplex and no presolve. Through ``linprog``
about as much CPU went into scipy's checks, its sparse stacking and conversions and its option
handling (each option checked against HiGHS' tables on every call) as into HiGHS itself:
measured on the compaction of igl-elephant, dino and igl-arm from their nested layouts (232
programs), HiGHS 1.07 s, ``linprog`` around it 1.00 s more. Here the same program (the same
matrix in columns, the same options: dual simplex, presolve off, the time limit, no output) is
passed as arrays to the HiGHS that scipy ships (``scipy.optimize._highspy._core``, private:
scipy 1.15 and later) and its answer read back as ``linprog`` reads it, with the same
feasibility check of the solution (``scipy.optimize._linprog_util._check_result``: bounds and
rows within 10 sqrt(1e-9)). Where that module is missing or differs, ``linprog`` is called as
before.

Or its dual (``dual``: :func:`_dual`, 3 k + 1 rows, its basis that small), by dual simplex with
no presolve and no scaling, x read from its row duals and checked the same way. Measured on
the programs of dino's and igl-arm's compactions (58; issue18-pack27-2026-11-29.md): HiGHS
0.37 -> 0.17 s and 0.22 -> 0.09 s, the same optima within 1e-13. HiGHS' own dualisation
(``simplex_dualize_strategy``) gave a wrong optimum on one of dino's and crashed the process on
igl-arm's, hence the dual built here. Where many x are optimal the dual's is another one.
"""
import numpy as np

__all__ = ["solve_lp"]

_TOL = 10 * np.sqrt(1e-9)   # linprog's check of a solution (its tol 1e-9, _check_result)


def _core():
    """scipy's HiGHS binding, or None where this scipy has none (or another one)."""
    try:
        from scipy.optimize._highspy import _core as h
        h._Highs, h.HighsOptions, h.MatrixFormat.kColwise, h.ObjSense.kMinimize  # noqa: B018
        h.HighsModelStatus.kOptimal, h.HighsModelStatus.kInfeasible   # noqa: B018
        h.simplex_constants.SimplexStrategy.kSimplexStrategyDual   # noqa: B018
    except (ImportError, AttributeError):
        return None
    return h


def solve_lp(cost, A, rhs, lb, ub, seconds, dual=False):
    """min cost . x subject to A x <= rhs and lb <= x <= ub, by HiGHS' dual simplex with no
    presolve, for at most ``seconds``; ``dual``: its dual instead (:func:`_solve_dual`).

    Parameters
    ----------
    cost : (n,) float64
    A : scipy sparse (m, n)
    rhs, lb, ub : (m,), (n,), (n,) float64, finite

    Returns
    -------
    x (n,) float64 or None, status as ``linprog``'s (0 solved, 2 infeasible, others failed)
    """
    h = _core()
    if h is None:
        return _linprog(cost, A, rhs, lb, ub, seconds, dual)
    if dual:
        return _solve_dual(h, cost, A, rhs, lb, ub, seconds)
    A = A.tocsc()
    A.sort_indices()
    n, m = len(cost), len(rhs)
    highs, opt = h._Highs(), _options(h, seconds)
    # the model as arrays: a HighsLp's attributes take lists, converted element by element
    # (3-4 ms a program of a few thousand rows, measured on dino's: half of HiGHS' own time);
    # every column continuous
    if (highs.passOptions(opt) == h.HighsStatus.kError
            or highs.passModel(n, m, A.nnz, int(h.MatrixFormat.kColwise),
                               int(h.ObjSense.kMinimize), 0.0,
                               *(np.ascontiguousarray(v, dtype=np.float64)
                                 for v in (cost, lb, ub)),
                               np.full(m, -h.kHighsInf),
                               np.ascontiguousarray(rhs, dtype=np.float64),
                               A.indptr.astype(np.int32), A.indices.astype(np.int32),
                               A.data.astype(np.float64), np.zeros(n, dtype=np.int32))
            == h.HighsStatus.kError
            or highs.run() == h.HighsStatus.kError):
        return None, 4
    status = highs.getModelStatus()
    if status == h.HighsModelStatus.kInfeasible:
        return None, 2
    if status != h.HighsModelStatus.kOptimal:
        return None, 4
    sol = highs.getSolution()
    x = np.array(sol.col_value)
    slack = rhs - np.asarray(sol.row_value)
    if (np.isnan(x).any() or np.isnan(slack).any() or (x < lb - _TOL).any()
            or (x > ub + _TOL).any() or (slack < -_TOL).any()):
        return None, 4
    return x, 0


def _options(h, seconds):
    """HiGHS' options of every program here: dual simplex, no presolve, the time limit, quiet."""
    opt = h.HighsOptions()
    opt.presolve = "off"
    opt.solver = "simplex"
    opt.simplex_strategy = int(h.simplex_constants.SimplexStrategy.kSimplexStrategyDual)
    opt.time_limit = float(seconds)
    opt.output_flag = False
    opt.log_to_console = False
    return opt


def _solve_dual(h, cost, A, rhs, lb, ub, seconds):
    """:func:`solve_lp` of the program's dual (:func:`_dual`) by dual simplex with no presolve
    and no scaling, x read from its row duals and checked against the program."""
    dcost, start, index, value = _dual(cost, A, rhs, lb, ub)
    n, m = len(cost), len(dcost)
    row = -np.ascontiguousarray(cost, dtype=np.float64)
    highs, opt = h._Highs(), _options(h, seconds)
    opt.simplex_scale_strategy = 0
    if (highs.passOptions(opt) == h.HighsStatus.kError
            or highs.passModel(m, n, len(value), int(h.MatrixFormat.kColwise),
                               int(h.ObjSense.kMinimize), 0.0, dcost, np.zeros(m),
                               np.full(m, h.kHighsInf), row, row, start, index, value,
                               np.zeros(m, dtype=np.int32)) == h.HighsStatus.kError
            or highs.run() == h.HighsStatus.kError):
        return None, 4
    status = highs.getModelStatus()
    if status in (h.HighsModelStatus.kUnbounded, h.HighsModelStatus.kUnboundedOrInfeasible):
        return None, 2   # (the dual is feasible: unbounded, so the program has no x)
    if status != h.HighsModelStatus.kOptimal:
        return None, 4
    return _checked(np.array(highs.getSolution().row_dual), A, rhs, lb, ub)


def _dual(cost, A, rhs, lb, ub):
    """The dual of min cost . x over A x <= rhs, lb <= x <= ub: min rhs . y - lb . p + ub . q
    over A^T y - p + q = -cost, y, p, q >= 0 (always feasible: y = 0, p - q = cost; unbounded
    exactly where the program is infeasible), whose row duals are x: its cost (m + 2n,) and
    its matrix in columns (start, index, value): A's rows, then -I and I."""
    A = A.tocsr()
    A.sort_indices()
    m, n = A.shape
    dcost = np.concatenate([rhs, -np.asarray(lb, dtype=np.float64),
                            np.asarray(ub, dtype=np.float64)]).astype(np.float64)
    start = np.concatenate([A.indptr, A.indptr[-1] + 1 + np.arange(2 * n)]).astype(np.int32)
    index = np.concatenate([A.indices, np.arange(n), np.arange(n)]).astype(np.int32)
    value = np.concatenate([A.data, -np.ones(n), np.ones(n)]).astype(np.float64)
    return dcost, start, index, value


def _checked(x, A, rhs, lb, ub):
    """(x, 0) where x keeps the bounds and rows within ``linprog``'s tolerance (its
    ``_check_result``), else (None, 4)."""
    slack = rhs - A @ x
    if (np.isnan(x).any() or np.isnan(slack).any() or (x < lb - _TOL).any()
            or (x > ub + _TOL).any() or (slack < -_TOL).any()):
        return None, 4
    return x, 0


def _linprog(cost, A, rhs, lb, ub, seconds, dual=False):
    """:func:`solve_lp` through ``scipy.optimize.linprog`` (method highs-ds); ``dual``: the
    same dual, x its equality rows' marginals."""
    from scipy.optimize import linprog
    if not dual:
        res = linprog(cost, A_ub=A, b_ub=rhs, bounds=np.stack([lb, ub], 1), method="highs-ds",
                      options={"presolve": False, "time_limit": float(seconds)})
        return (res.x if res.status == 0 else None), int(res.status)
    from scipy.sparse import csc_array
    dcost, start, index, value = _dual(cost, A, rhs, lb, ub)
    D = csc_array((value, index, start), shape=(len(cost), len(dcost)))
    res = linprog(dcost, A_eq=D, b_eq=-np.asarray(cost, dtype=np.float64), bounds=(0, None),
                  method="highs-ds", options={"presolve": False, "time_limit": float(seconds)})
    if res.status == 3:
        return None, 2
    if res.status != 0:
        return None, int(res.status)
    return _checked(np.asarray(res.eqlin.marginals, dtype=np.float64), A, rhs, lb, ub)
