"""Clarabel wrapper: the one place that reads solver statuses and settings.

Settings follow ../shared/notes/solver-measurements.md: gap tolerances 1e-6 give the same
distortion as 1e-8 in a third of the iterations; iterative refinement and presolve off; qdldl; an
iteration cap, because near infeasibility Clarabel can spend hundreds of iterations without a
certificate. Any iterate is safe to use once it is certified from its own UVs.
"""
import time
from dataclasses import dataclass

import clarabel
import numpy as np
import scipy.sparse as sp

MAX_ITER = 80
TOL_GAP = 1e-6
TOL_FEAS = 1e-7


@dataclass(frozen=True)
class ConicSolution:
    """Outcome of one conic solve.

    Attributes
    ----------
    x : (n,) float64 or None, the last iterate (may be inexact or infeasible; certify it)
    outcome : "solved" | "infeasible" | "inexact" | "cancelled" | "error" (the solver raised)
    status : str, Clarabel's own status name
    iterations : int
    seconds : float
    objective : float
    """
    x: np.ndarray
    outcome: str
    status: str
    iterations: int
    seconds: float
    objective: float


_OUTCOME = {
    "Solved": "solved",
    "AlmostSolved": "solved",
    "PrimalInfeasible": "infeasible",
    "AlmostPrimalInfeasible": "infeasible",
    "CallbackTerminated": "cancelled",
}


def solve_conic(P, q, A, b, cones, cancel=None, max_iter=MAX_ITER, tol_gap=TOL_GAP,
                tol_feas=TOL_FEAS):
    """Minimise ``x^T P x / 2 + q^T x`` subject to ``A x + s = b``, ``s`` in the cones.

    Parameters
    ----------
    P : (n,n) sparse symmetric PSD; only its upper triangle is passed (Clarabel reads only that)
    q : (n,) float
    A : (rows,n) sparse
    b : (rows,) float
    cones : list of (kind, dim), kind in {"zero", "nonneg", "soc"}
    cancel : object with is_set(), optional; checked by Clarabel's termination callback
    max_iter : int
    tol_gap, tol_feas : float, Clarabel's gap (absolute and relative) and feasibility tolerances

    Returns
    -------
    ConicSolution
    """
    kinds = {"zero": clarabel.ZeroConeT, "nonneg": clarabel.NonnegativeConeT,
             "soc": clarabel.SecondOrderConeT}
    ccones = [kinds[kind](dim) for kind, dim in cones]
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.max_iter = int(max_iter)
    settings.tol_gap_abs = float(tol_gap)
    settings.tol_gap_rel = float(tol_gap)
    settings.tol_feas = float(tol_feas)
    settings.iterative_refinement_enable = False
    settings.presolve_enable = False
    settings.direct_solve_method = "qdldl"
    # Clarabel reads raw CSC arrays: anything else would be silently transposed.
    Pu = sp.csc_matrix(sp.triu(P, format="csc"))
    Ac = sp.csc_matrix(A)
    Pu.sort_indices()
    Ac.sort_indices()
    t0 = time.perf_counter()
    try:
        solver = clarabel.DefaultSolver(Pu, np.asarray(q, np.float64), Ac,
                                        np.asarray(b, np.float64), ccones, settings)
        if cancel is not None:
            solver.set_termination_callback(lambda info: bool(cancel.is_set()))
        sol = solver.solve()
    except (KeyboardInterrupt, SystemExit):
        raise
    except BaseException as exc:  # a Rust panic arrives as pyo3's PanicException (BaseException)
        return ConicSolution(None, "error", f"{type(exc).__name__}: {exc}", 0,
                             time.perf_counter() - t0, float("nan"))
    seconds = time.perf_counter() - t0
    status = str(sol.status).split(".")[-1]
    outcome = _OUTCOME.get(status, "inexact")
    x = np.asarray(sol.x, dtype=np.float64)
    if x.size != Pu.shape[0] or not np.all(np.isfinite(x)):
        x = None
    return ConicSolution(x, outcome, status, int(sol.iterations), seconds, float(sol.obj_val))
