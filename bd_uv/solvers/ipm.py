"""A primal-dual interior-point method that factorises only the Schur complement onto x.

Problem (the same form and result as ``conic.solve_conic``)::

    minimise  x^T P x / 2 + q^T x   subject to   A x + s = b,   s in K,

K a product of nonnegative orthants and second-order cones (Lipman 2012, eqs. 4.15-4.17 as
``spaces.bounded_distortion_space`` builds them: one ``("nonneg", k)`` block, then one
``("soc", 3)`` per face; other dimensions work too).

Method: the infeasible-start primal-dual path-following method of CVXOPT's ``coneqp``
(Vandenberghe 2010, "The CVXOPT linear and quadratic cone program solvers", sections 3-7) with
Nesterov-Todd scaling and Mehrotra's predictor-corrector. With the NT scaling W (``W z = W^-1 s =
lambda``), the Newton system eliminates ds and dz, leaving one symmetric positive definite system

    H dx = r,   H = P + A^T W^-2 A                                                     (Schur)

in the free vertex unknowns only. Every cone block of the bounded-distortion space involves one
face's 3 vertices, so H has the LSCM/Laplacian pattern whatever W is: its symbolic analysis is done
once (``SchurIPM``) and each iteration only refactorises numerically (qdldl's ``update``, else
scipy's SuperLU), then one step of iterative refinement on the unreduced system.

Warm start (``x0``): the iterates start at x0, each cone's slack lifted to a small margin, with the
dual on the central path; from the optimum at a tighter bound this halves the iterations.

Infeasibility: when F_C is empty the dual iterates diverge along a Farkas certificate z in K*,
``A^T z = 0``, ``b^T z < 0``. The method stops with ``"infeasible"`` when the current z proves that
every feasible point would be a million times larger than the iterates, and otherwise, when the
iterates stop making progress, decides with a phase-1 problem (maximise the margin t with
``b - A x - t e`` in K, e the cone's identity): infeasible when max t < 0 by both its primal and
dual objective.
"""
import time

import numpy as np
import scipy.sparse as sp

from . import cones as cones_
from .conic import ConicSolution
from .factor import RefactorSPD

MAX_ITER = 80
TOL_GAP = 1e-6      # relative duality gap s^T z (conic.TOL_GAP is also absolute: see GAP_FLOOR)
GAP_FLOOR = 1e-3    # gap <= TOL_GAP max(GAP_FLOOR, |objective|): an absolute 1e-6 let the
                    # energy of mannequin-devil (objective 5e-4) differ from Clarabel's by 1e-3
TOL_FEAS = 1e-7     # relative primal and dual residuals (as conic.TOL_FEAS)
TOL_INFEAS = 1e-6   # |A^T z|_1 max(1, |x|_inf) <= TOL_INFEAS (-b^T z) certifies infeasibility
STEP = 0.99         # fraction of the step to the cone boundary
REFINE = 1          # iterative refinement steps per Newton solve (at most)
REFINE_TOL = 1e-8   # ... until the unreduced residual is below this, relative to the right side
WARM_DELTA = 1e-2   # warm start: each cone's slack margin at least this x median |b - A x0|
WARM_MU = 1.0       # warm start: mu = this x |objective at x0| / degree
STALL = 20          # stop (InsufficientProgress) after this many iterations without progress
STALL_INFEAS = 5    # ... or this many while b'z < 0 (a suspected infeasibility, see _phase1)
REG = 1e-11         # static regularisation of H, relative to its largest diagonal entry


def _canonical(P, A):
    """A as CSR and the upper triangle of P as CSC, duplicates summed and indices sorted: the
    form whose pattern ``SchurIPM`` compares and analyses."""
    Ar = sp.csr_matrix(A)
    Ar.sum_duplicates()
    Ar.sort_indices()
    Pu = sp.csc_matrix(sp.triu(sp.csc_matrix(P), format="csc"))
    Pu.sum_duplicates()
    Pu.sort_indices()
    return Ar, Pu


class SchurIPM:
    """Interior-point solver with the symbolic analysis of H = P + A^T W^-2 A done once.

    Build it once per sparsity pattern of (P, A, cones); call ``solve`` for each problem with that
    pattern (frame resets, bisection on C). A problem whose pattern differs is analysed anew.

    Parameters
    ----------
    P : (n,n) sparse symmetric PSD (its pattern: the values may change between solves)
    A : (m,n) sparse
    cones : list of (kind, dim)
    backend : "auto" (qdldl when installed, else scipy SuperLU), "qdldl" or "splu"
    """

    def __init__(self, P, A, cones, backend="auto"):
        self.backend = backend
        self._analyse(P, A, cones)

    def _analyse(self, P, A, cones):
        n = A.shape[1]
        self.n = n
        self.cones = cones_.Cones(cones)
        if A.shape[0] != self.cones.m:
            raise ValueError(f"A has {A.shape[0]} rows but the cones {self.cones.m}")
        Ar = sp.csr_matrix(A)
        Ar.sum_duplicates()
        Ar.sort_indices()
        self.A_indptr, self.A_indices = Ar.indptr.copy(), Ar.indices.copy()
        Pu = sp.csc_matrix(sp.triu(sp.csc_matrix(P), format="csc"))
        Pu.sum_duplicates()
        Pu.sort_indices()
        self.P_indptr, self.P_indices = Pu.indptr.copy(), Pu.indices.copy()
        # Blocks: each orthant row alone, each second-order cone its d rows. For every block the
        # union of its rows' columns (padded with -1) and, per (row, column), the position in
        # A's CSR data (-1 for a structural zero).
        groups = []
        c = self.cones
        if len(c.lp):
            groups.append(("lp", 1, c.lp[:, None]))
        for d, rows in c.soc.items():
            groups.append(("soc", d, rows))
        rows_of = np.repeat(np.arange(Ar.shape[0]), np.diff(Ar.indptr))
        self.groups = []
        keys = []
        for kind, d, rows in groups:
            nb = len(rows)
            # entries of A in these blocks: block id, row within block, column, data position
            blk_of_row = np.full(Ar.shape[0], -1)
            pos_in_blk = np.full(Ar.shape[0], -1)
            blk_of_row[rows.ravel()] = np.repeat(np.arange(nb), d)
            pos_in_blk[rows.ravel()] = np.tile(np.arange(d), nb)
            sel = blk_of_row[rows_of] >= 0
            ent = np.flatnonzero(sel)
            eb, er, ec = blk_of_row[rows_of[ent]], pos_in_blk[rows_of[ent]], Ar.indices[ent]
            # distinct columns per block
            bc = np.unique(eb.astype(np.int64) * n + ec)
            ub, uc = bc // n, bc % n
            cnt = np.bincount(ub, minlength=nb)
            mc = int(cnt.max()) if nb else 0
            first = np.concatenate([[0], np.cumsum(cnt)[:-1]])
            slot_of = np.arange(len(bc)) - first[ub]
            cols = np.full((nb, mc), -1, np.int64)
            cols[ub, slot_of] = uc
            # slot of each entry: position of (eb, ec) in bc
            slot = np.searchsorted(bc, eb.astype(np.int64) * n + ec) - first[eb]
            gidx = np.full((nb, d, mc), -1, np.int64)
            gidx[eb, er, slot] = ent
            # H entries of the block: slot pairs k <= l (the block is symmetric), each onto the
            # upper-triangle entry (min col, max col)
            kk, ll = np.triu_indices(mc)
            ci, cj = cols[:, kk], cols[:, ll]                       # (nb, npairs)
            ok = (ci >= 0) & (cj >= 0)
            flat = np.flatnonzero(ok.ravel())
            lo, hi = np.minimum(ci, cj).ravel()[flat], np.maximum(ci, cj).ravel()[flat]
            keys.append(hi * n + lo)  # column-major key: col*n+row
            self.groups.append((kind, d, rows, gidx, flat, kk, ll))
        # P's upper triangle
        pc = np.repeat(np.arange(n), np.diff(Pu.indptr))
        keys.append(pc.astype(np.int64) * n + Pu.indices)
        diag_key = np.arange(n, dtype=np.int64) * (n + 1)
        keys.append(diag_key)  # the diagonal always (regularisation)
        allk = np.concatenate(keys)
        uk = np.unique(allk)            # a sort; the inverse by bisection (cheaper than argsort)
        inv = np.searchsorted(uk, allk)
        self.nnz = len(uk)
        hc, hr = uk // n, uk % n
        self.H_indptr = np.concatenate([[0], np.cumsum(np.bincount(hc, minlength=n))])
        self.H_indices = hr.astype(np.int32)
        offs = np.cumsum([0] + [len(k) for k in keys])
        # Targets of every block entry, padded pairs included (sent to a dummy slot nnz, so the
        # per-iteration values need no gather), then P's; the diagonal's positions.
        targets = []
        for i, (kind, d, rows, gidx, flat, kk, ll) in enumerate(self.groups):
            t = np.full(len(rows) * len(kk), self.nnz, np.int64)
            t[flat] = inv[offs[i]:offs[i + 1]]
            targets.append(t)
        targets.append(inv[offs[-3]:offs[-2]])
        self.target_all = np.concatenate(targets)
        self.diag_pos = inv[offs[-2]:]
        self.factor = RefactorSPD(self.backend)

    def _same_pattern(self, P, A, cones):
        Ar, Pu = _canonical(P, A)
        same = (list(cones) == self.cones.key
                and Ar.shape == (self.cones.m, self.n)
                and np.array_equal(Ar.indptr, self.A_indptr)
                and np.array_equal(Ar.indices, self.A_indices)
                and np.array_equal(Pu.indptr, self.P_indptr)
                and np.array_equal(Pu.indices, self.P_indices))
        return same, Ar, Pu

    def _schur(self, Pdata, Gs, scaling):
        """Upper triangle of H = P + A^T W^-2 A (+ REG) as CSC on the fixed pattern.

        Per block, with G its rows of A on its columns: G^T W^-2 G = Y^T Y, Y = W^-1 G.
        """
        vals = []
        for (kind, d, rows, gidx, flat, kk, ll), G in zip(self.groups, Gs):
            if kind == "lp":
                g = G[:, 0, :] / scaling.d_lp[:, None]
                contrib = g[:, kk] * g[:, ll]
            else:
                Y = scaling.inv_blocks(d, G)                      # (d, nb, k)
                contrib = Y[0][:, kk] * Y[0][:, ll]
                for i in range(1, d):
                    contrib += Y[i][:, kk] * Y[i][:, ll]
            vals.append(contrib.ravel())
        vals.append(Pdata)
        data = np.bincount(self.target_all, weights=np.concatenate(vals),
                           minlength=self.nnz + 1)[:self.nnz]
        dmax = float(np.max(data[self.diag_pos])) if self.n else 1.0
        data[self.diag_pos] += REG * max(dmax, 1e-300)
        return sp.csc_matrix((data, self.H_indices, self.H_indptr), shape=(self.n, self.n))

    def solve(self, P, q, A, b, cones, cancel=None, max_iter=MAX_ITER, x0=None,
              tol_gap=TOL_GAP, tol_feas=TOL_FEAS, phase1=True):
        """Minimise ``x^T P x / 2 + q^T x`` subject to ``A x + s = b``, ``s`` in the cones.

        Parameters
        ----------
        P : (n,n) sparse symmetric PSD (full or upper triangle; the upper triangle is read)
        q : (n,) float
        A : (m,n) sparse
        b : (m,) float
        cones : list of (kind, dim), kind in {"nonneg", "soc"}
        cancel : object with is_set(), optional; checked once per iteration
        max_iter : int
        x0 : (n,) float, optional; a warm start (e.g. a certified map, or the solution at a
            tighter bound). The iterates start at x0 with its slack ``b - A x0`` lifted to a
            margin of WARM_DELTA x its median on each cone (a small primal residual if x0 is on
            or outside the boundary) and the dual on the central path.
        tol_gap, tol_feas : float, stopping tolerances (relative gap, see GAP_FLOOR; residuals)
        phase1 : bool, confirm infeasibility with a phase-1 problem when the run stalls

        Returns
        -------
        ConicSolution; ``status`` one of "Solved", "PrimalInfeasible", "MaxIterations",
        "InsufficientProgress", "CallbackTerminated", "NumericalError".
        """
        t0 = time.perf_counter()
        same, Ar, Pu = self._same_pattern(P, A, cones)
        if not same:
            self._analyse(P, A, cones)
            Ar, Pu = _canonical(P, A)
        try:
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                res = self._run(Pu, np.asarray(q, np.float64), Ar, np.asarray(b, np.float64),
                                cancel, int(max_iter), x0, tol_gap, tol_feas)
        except (np.linalg.LinAlgError, RuntimeError, ValueError, FloatingPointError) as exc:
            return ConicSolution(None, "error", f"NumericalError: {exc}", 0,
                                 time.perf_counter() - t0, float("nan"))
        x, status, it, obj = res
        if status in ("MaxIterations", "InsufficientProgress", "NumericalError") and phase1:
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                verdict, it1 = self._phase1(Ar, np.asarray(b, np.float64), cancel, int(max_iter))
            it += it1
            if verdict == "infeasible":
                status = "PrimalInfeasible"
            elif verdict == "cancelled":
                status = "CallbackTerminated"
        outcome = {"Solved": "solved", "PrimalInfeasible": "infeasible",
                   "CallbackTerminated": "cancelled"}.get(status, "inexact")
        if outcome == "infeasible":
            obj = float("nan")  # as Clarabel reports it: there is no optimum
        if x is not None and not np.all(np.isfinite(x)):
            x = None
        return ConicSolution(x, outcome, status, it, time.perf_counter() - t0, obj)

    # ------------------------------------------------------------------------------------------
    def _run(self, Pu, q, Ar, b, cancel, max_iter, x0, tol_gap, tol_feas):
        n, c = self.n, self.cones
        At = Ar.T.tocsr()
        Pfull = Pu + sp.triu(Pu, 1, format="csc").T
        Pfull = Pfull.tocsr()
        Adata = np.concatenate([Ar.data, [0.0]])  # index -1 reads the appended zero
        Gs = [Adata[g] if kind == "lp" else np.ascontiguousarray(Adata[g].transpose(1, 0, 2))
              for (kind, _, _, g, *_) in self.groups]   # orthant (nb, 1, k); cones (d, nb, k)
        Pdata = Pu.data
        e = c.identity()
        nq = max(1.0, float(np.max(np.abs(q)))) if n else 1.0
        nb_ = max(1.0, float(np.max(np.abs(b)))) if len(b) else 1.0

        def kkt(scaling, bx, bz, bs):
            """Solve P dx + A^T dz = bx, A dx + ds = bz, W dz + W^-1 ds = bs through H."""
            Wi2 = scaling.matrix(inverse=True, power=2)
            t = Wi2 @ (scaling.apply(bs) - bz)
            dx = self.factor.solve(bx - At @ t)
            Adx = Ar @ dx
            dz = t + Wi2 @ Adx
            ds = bz - Adx  # exactly the primal equation (W^2 W^-2 is I only to rounding)
            return dx, ds, dz

        def newton(scaling, lam, rx, rz, rc):
            """Solve P dx + A^T dz = -rx, A dx + ds = -rz, lam o (W dz + W^-1 ds) = rc.

            The Schur complement loses accuracy as W becomes ill-conditioned near the optimum;
            a few steps of iterative refinement on the unreduced system restore it (each one
            back-solve with the same factors).
            """
            bx, bz, bs = -rx, -rz, cones_.jordan_divide(c, lam, rc)  # W dz + W^-1 ds = bs
            dx, ds, dz = kkt(scaling, bx, bz, bs)
            scale = max(1.0, float(np.max(np.abs(bx))), float(np.max(np.abs(bz))),
                        float(np.max(np.abs(bs))))
            for _ in range(REFINE):
                ex = bx - Pfull @ dx - At @ dz
                ez = np.zeros_like(bz)  # kkt meets the primal equation exactly
                es = bs - scaling.apply(dz) - scaling.apply(ds, inverse=True)
                err = max(float(np.max(np.abs(ex))), float(np.max(np.abs(es))))
                self.refinements += 1
                if err <= REFINE_TOL * scale:
                    break
                cx, cs, cz = kkt(scaling, ex, ez, es)
                dx, ds, dz = dx + cx, ds + cs, dz + cz
            return dx, ds, dz

        # Starting point.
        if x0 is not None:
            # Warm start: x0 as it is; its slack b - A x0, each cone lifted to a margin of at
            # least delta (a small primal residual where x0 is on or near the boundary, as the
            # optimum at a tighter bound is); z = mu s^-1 on the central path.
            x = np.asarray(x0, np.float64).copy()
            s = b - Ar @ x
            typical = float(np.median(np.abs(s))) if len(s) else 1.0
            delta = WARM_DELTA * max(typical, 1e-12)
            s = cones_.lift(c, s, delta)
            g = Pfull @ x + q
            mu = WARM_MU * max(abs(float(0.5 * x @ g + 0.5 * q @ x)), 1e-12) / c.degree
            z = mu * cones_.jordan_inverse(c, s)
        else:
            # CVXOPT's default start: the W = I Newton system, then shift s and z into int K.
            ident = cones_.NTScaling(c, e, e)
            self.factor.factor(self._schur(Pdata, Gs, ident))
            x = self.factor.solve(-q + At @ b)
            s = b - Ar @ x
            z = Ar @ x - b
            for v in (s, z):
                t = c.margin(v)
                if t <= 0:
                    v += (1.0 - t) * e
                elif not np.isfinite(t):
                    v += e
        status = "MaxIterations"
        steps = 0  # Newton steps taken: the iteration count reported
        last = None
        best = (np.inf, x.copy())
        self.last_info = None
        self.refinements = 0
        stall = 0
        for it in range(1, max_iter + 1):
            if cancel is not None and cancel.is_set():
                status = "CallbackTerminated"
                break
            Px = Pfull @ x
            rx = Px + q + At @ z
            rz = Ar @ x + s - b
            gap = float(s @ z)
            mu = gap / c.degree
            pobj = float(0.5 * x @ Px + q @ x)
            dobj = float(-0.5 * x @ Px - b @ z)  # the dual objective (exact when rx = 0)
            pres = float(np.max(np.abs(rz))) / nb_ if len(rz) else 0.0
            dres = float(np.max(np.abs(rx))) / nq if n else 0.0
            last = pobj
            if pres <= tol_feas and dres <= tol_feas and (
                    gap <= tol_gap * max(GAP_FLOOR, min(abs(pobj), abs(dobj)))):
                status = "Solved"
                break
            bz = float(b @ z)
            if bz < 0:
                # z in K* with b'z < 0: every feasible x has |x|_inf >= -b'z / |A'z|_1 (since
                # 0 <= z's = z'b - (A'z)'x). Infeasible when that is far beyond the iterates.
                atz = float(np.sum(np.abs(At @ z))) if n else 0.0
                if atz * max(1.0, float(np.max(np.abs(x)))) <= TOL_INFEAS * (-bz):
                    status = "PrimalInfeasible"
                    break
            score = max(pres, dres, gap / max(1.0, abs(pobj)))
            if not np.isfinite(score):
                status = "NumericalError"
                break
            if score < best[0] * 0.999:
                best = (score, x.copy())
                self.last_info = dict(pres=pres, dres=dres, gap=gap, pobj=pobj, dobj=dobj)
                stall = 0
            else:
                stall += 1
                # no progress while z drifts along a Farkas direction (b'z < 0): let phase 1
                # decide soon rather than after STALL iterations
                if stall >= STALL or (stall >= STALL_INFEAS and bz < 0):
                    status = "InsufficientProgress"
                    break
            scaling = cones_.NTScaling(c, s, z)
            lam = scaling.apply(z)
            self.factor.factor(self._schur(Pdata, Gs, scaling))
            # predictor (affine scaling)
            lamsq = cones_.jordan_product(c, lam, lam)
            dxa, dsa, dza = newton(scaling, lam, rx, rz, -lamsq)
            aa = min(1.0, c.step(s, dsa), c.step(z, dza))
            sigma = (1.0 - aa) ** 3
            # corrector (Mehrotra): second-order term (W^-1 ds_a) o (W dz_a)
            corr = cones_.jordan_product(c, scaling.apply(dsa, inverse=True), scaling.apply(dza))
            rc = -lamsq - corr + sigma * mu * e
            dx, ds, dz = newton(scaling, lam, rx, rz, rc)
            a = min(1.0, STEP * min(c.step(s, ds), c.step(z, dz)))
            if not np.isfinite(a) or a <= 1e-12:
                status = "InsufficientProgress"
                break
            x = x + a * dx
            s = s + a * ds
            z = z + a * dz
            steps += 1
        if status != "Solved" and status != "PrimalInfeasible":
            x = best[1] if best[0] < np.inf else x
        obj = float(0.5 * x @ (Pfull @ x) + q @ x) if last is not None else float("nan")
        return x, status, steps, obj

    def _phase1(self, Ar, b, cancel, max_iter):
        """Is {x : b - A x in K} empty? Maximise t with b - A x - t e in K, t <= 1.

        Solved as a conic program in (x, t) by a second SchurIPM (the column of t is dense: its
        H gets one dense row, small next to the mesh pattern). A tiny x-regularisation keeps the
        x-part of H positive definite. Returns ("infeasible" | "feasible" | "unknown" |
        "cancelled", iterations).
        """
        c = self.cones
        e = c.identity()
        m, n = Ar.shape
        A1 = sp.vstack([sp.hstack([Ar, sp.csr_matrix(e[:, None])]),
                        sp.csr_matrix(([1.0], ([0], [n])), shape=(1, n + 1))]).tocsr()
        b1 = np.concatenate([b, [1.0]])
        # cones: the "t <= 1" row joins the orthant; keep the orthant first
        lp = c.lp
        order = np.concatenate([lp, [m], np.setdiff1d(np.arange(m), lp)])
        cones1 = [("nonneg", len(lp) + 1)]
        for d, rows in c.soc.items():
            cones1 += [("soc", d)] * len(rows)
        # rows of A1 must follow cones1: orthant rows, then soc rows in their original order
        soc_rows = np.concatenate([r.ravel() for r in c.soc.values()]) if c.soc else \
            np.zeros(0, np.int64)
        order = np.concatenate([lp, [m], soc_rows])
        A1, b1 = A1[order], b1[order]
        scale = float(sp.linalg.norm(Ar, ord=1)) if Ar.nnz else 1.0
        P1 = sp.diags(np.concatenate([np.full(n, 1e-9 * scale), [0.0]])).tocsc()
        q1 = np.zeros(n + 1)
        q1[n] = -1.0
        sub = SchurIPM(P1, A1, cones1, backend=self.backend)
        sol = sub.solve(P1, q1, A1, b1, cones1, cancel=cancel, max_iter=max_iter, phase1=False,
                        tol_gap=1e-8, tol_feas=TOL_FEAS)
        if sol.outcome == "cancelled":
            return "cancelled", sol.iterations
        if sol.x is None:
            return "unknown", sol.iterations
        t = float(sol.x[n])
        if t > 0 and sub.cones.margin(b1 - A1 @ sol.x) >= 0:
            return "feasible", sol.iterations
        info = sub.last_info
        # max t < 0 by both the primal and the dual objective of a nearly optimal pair (the
        # Schur complement's accuracy floor can stop the dual residual near 1e-6 before
        # TOL_FEAS; the margin 1e-6 on t covers it).
        if (info is not None and info["pres"] <= 1e-6 and info["dres"] <= 1e-5
                and info["pobj"] > 1e-6 and info["dobj"] > 1e-6):
            return "infeasible", sol.iterations
        return "unknown", sol.iterations


def solve_conic(P, q, A, b, cones, cancel=None, max_iter=MAX_ITER, x0=None, backend="auto",
                tol_gap=TOL_GAP, tol_feas=TOL_FEAS):
    """Minimise ``x^T P x / 2 + q^T x`` subject to ``A x + s = b``, ``s`` in the cones.

    Drop-in for ``conic.solve_conic`` (same arguments and ``ConicSolution``) plus a start ``x0``.
    For repeated solves with one sparsity pattern build a ``SchurIPM`` once instead.

    Parameters
    ----------
    P : (n,n) sparse symmetric PSD
    q : (n,) float
    A : (m,n) sparse
    b : (m,) float
    cones : list of (kind, dim), kind in {"nonneg", "soc"}
    cancel : object with is_set(), optional; checked once per iteration
    max_iter : int
    x0 : (n,) float, optional start (strictly feasible for a feasible start)
    backend : "auto", "qdldl" or "splu"

    Returns
    -------
    ConicSolution
    """
    t0 = time.perf_counter()
    try:
        solver = SchurIPM(P, A, cones, backend=backend)
    except (ValueError, MemoryError) as exc:
        return ConicSolution(None, "error", f"{type(exc).__name__}: {exc}", 0,
                             time.perf_counter() - t0, float("nan"))
    sol = solver.solve(P, q, A, b, cones, cancel=cancel, max_iter=max_iter, x0=x0,
                       tol_gap=tol_gap, tol_feas=tol_feas)
    return ConicSolution(sol.x, sol.outcome, sol.status, sol.iterations,
                         time.perf_counter() - t0, sol.objective)
