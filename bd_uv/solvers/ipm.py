"""A primal-dual interior-point method that factorises only the Schur complement onto x.

Problem (the same form and result as ``conic.solve_conic``)::

    minimise  x^T P x / 2 + q^T x   subject to   A x + s = b,   s in K,

K a product of nonnegative orthants and second-order cones (Lipman 2012, eqs. 4.15-4.17 as
``spaces.bounded_distortion_space`` builds them: one ``("nonneg", k)`` block, then one
``("soc", 3)`` per face).

Method: the infeasible-start primal-dual path-following method of CVXOPT's ``coneqp``
(Vandenberghe 2010, "The CVXOPT linear and quadratic cone program solvers", sections 3-7) with
Nesterov-Todd scaling and Mehrotra's predictor-corrector. With the NT scaling W (``W z = W^-1 s =
lambda``), the Newton system eliminates ds and dz, leaving one symmetric positive definite system

    H dx = r,   H = P + A^T W^-2 A                                                     (Schur)

in the free vertex unknowns only. Every cone block of the bounded-distortion space involves one
face's 3 vertices, so H has the LSCM/Laplacian pattern whatever W is: its symbolic analysis is done
once (``SchurIPM``) and each iteration only refactorises numerically (qdldl's ``update``, else
scipy's SuperLU).

Infeasibility: when F_C is empty the dual iterates diverge along a Farkas certificate z in K*,
``A^T z = 0``, ``b^T z < 0``; the method stops with ``"infeasible"`` once the current z certifies
this to a relative tolerance, and confirms a stalled run with a phase-1 problem (maximise the
margin t with ``b - A x - t e`` in K, e the cone's identity).
"""
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .conic import ConicSolution

try:  # qdldl: LDL^T with AMD ordering, numeric refactorisation on a fixed pattern
    import qdldl
except ImportError:  # pragma: no cover - exercised where qdldl is absent
    qdldl = None

MAX_ITER = 80
TOL_GAP = 1e-6      # absolute and relative duality gap s^T z (as conic.TOL_GAP)
TOL_FEAS = 1e-7     # relative primal and dual residuals (as conic.TOL_FEAS)
TOL_INFEAS = 1e-7   # ||A^T z|| <= TOL_INFEAS * (-b^T z) * scale certifies primal infeasibility
STEP = 0.99         # fraction of the step to the cone boundary
_DEBUG = False
REFINE = 3          # iterative refinement steps per Newton solve (at most)
REG = 1e-11         # static regularisation of H, relative to its largest diagonal entry


class _Cones:
    """Index arrays of a cone list: one nonnegative block and second-order blocks per dimension.

    Parameters
    ----------
    cones : list of (kind, dim), kind in {"nonneg", "soc"}
    """

    def __init__(self, cones):
        lp, soc = [], {}
        start = 0
        for kind, dim in cones:
            dim = int(dim)
            if kind == "nonneg":
                lp.append(np.arange(start, start + dim))
            elif kind == "soc":
                if dim < 1:
                    raise ValueError("a second-order cone needs dimension >= 1")
                soc.setdefault(dim, []).append(start)
            else:
                raise ValueError(f"cone kind {kind!r} is not supported: use 'nonneg' or 'soc'")
            start += dim
        self.m = start
        self.lp = np.concatenate(lp) if lp else np.zeros(0, np.int64)
        # soc[d]: (nb, d) row indices of every d-dimensional cone
        self.soc = {d: np.asarray(s)[:, None] + np.arange(d) for d, s in sorted(soc.items())}
        self.degree = len(self.lp) + sum(len(r) for r in self.soc.values())
        self.key = tuple((kind, int(dim)) for kind, dim in cones)

    def identity(self):
        """e: ones on the orthant, (1, 0, ..., 0) on each second-order cone."""
        e = np.zeros(self.m)
        e[self.lp] = 1.0
        for rows in self.soc.values():
            e[rows[:, 0]] = 1.0
        return e

    def margin(self, s):
        """Largest t with s - t e in K (negative when s is outside K)."""
        t = np.inf
        if len(self.lp):
            t = min(t, float(s[self.lp].min()))
        for rows in self.soc.values():
            u = s[rows]
            t = min(t, float(np.min(u[:, 0] - np.linalg.norm(u[:, 1:], axis=1))))
        return t

    def step(self, s, ds):
        """Largest alpha >= 0 (up to inf) with s + alpha ds in K, for s in int K."""
        a = np.inf
        if len(self.lp):
            d = ds[self.lp]
            neg = d < 0
            if neg.any():
                a = min(a, float(np.min(-s[self.lp][neg] / d[neg])))
        for rows in self.soc.values():
            u, d = s[rows], ds[rows]
            # f(alpha) = aa alpha^2 + 2 bb alpha + cc, cc > 0; the first positive root (or none)
            aa = d[:, 0] ** 2 - np.sum(d[:, 1:] ** 2, axis=1)
            bb = u[:, 0] * d[:, 0] - np.sum(u[:, 1:] * d[:, 1:], axis=1)
            cc = np.maximum(u[:, 0] ** 2 - np.sum(u[:, 1:] ** 2, axis=1), 0.0)
            disc = bb * bb - aa * cc
            hit = (aa < 0) | ((bb < 0) & (disc >= 0))
            if hit.any():
                den = -bb[hit] + np.sqrt(np.maximum(disc[hit], 0.0))
                with np.errstate(divide="ignore"):
                    a = min(a, float(np.min(np.where(den > 0, cc[hit] / den, 0.0))))
        return a


def _jdot(u):
    """u^T J u per row of (nb, d)."""
    return u[:, 0] ** 2 - np.sum(u[:, 1:] ** 2, axis=1)


class _Scaling:
    """Nesterov-Todd scaling W of a pair (s, z) in int K (Vandenberghe 2010, section 4.3).

    Orthant: W = diag(sqrt(s/z)). Second-order cone of dimension d: with a = sqrt(s^T J s),
    b = sqrt(z^T J z), beta = sqrt(a/b), s' = s/a, z' = z/b, gamma = sqrt((1 + s'^T z')/2),
    w = (s' + J z') / (2 gamma):  W = beta [[w0, w1^T], [w1, I + w1 w1^T / (1 + w0)]].
    Then W z = W^-1 s = lambda.
    """

    def __init__(self, cones, s, z):
        self.cones = cones
        self.d_lp = np.sqrt(s[cones.lp] / z[cones.lp])      # (nlp,)
        self.W, self.Winv = {}, {}
        for d, rows in cones.soc.items():
            us, uz = s[rows], z[rows]
            a = np.sqrt(np.maximum(_jdot(us), 1e-300))
            bq = np.sqrt(np.maximum(_jdot(uz), 1e-300))
            beta = np.sqrt(a / bq)
            sn, zn = us / a[:, None], uz / bq[:, None]
            gamma = np.sqrt(np.maximum((1.0 + np.sum(sn * zn, axis=1)) / 2.0, 1e-300))
            Jz = zn.copy()
            Jz[:, 1:] *= -1.0
            w = (sn + Jz) / (2.0 * gamma[:, None])
            w0, w1 = w[:, 0], w[:, 1:]
            nb = len(rows)
            M = np.empty((nb, d, d))
            M[:, 0, 0] = w0
            M[:, 0, 1:] = w1
            M[:, 1:, 0] = w1
            M[:, 1:, 1:] = (np.eye(d - 1)[None] + w1[:, :, None] * w1[:, None, :]
                            / (1.0 + w0)[:, None, None])
            Minv = M.copy()
            Minv[:, 0, 1:] *= -1.0
            Minv[:, 1:, 0] *= -1.0
            self.W[d] = beta[:, None, None] * M
            self.Winv[d] = Minv / beta[:, None, None]

    def apply(self, v, inverse=False, power=1):
        """W^p v or W^-p v, p in {1, 2}, for v of size m."""
        out = np.empty_like(v)
        c = self.cones
        dl = 1.0 / self.d_lp if inverse else self.d_lp
        out[c.lp] = v[c.lp] * dl ** power
        mats = self.Winv if inverse else self.W
        for d, rows in c.soc.items():
            u = v[rows]
            for _ in range(power):
                u = np.einsum("bij,bj->bi", mats[d], u)
            out[rows] = u
        return out

    def inv2_blocks(self):
        """W^-2 per block: (nlp,) diagonal and {d: (nb, d, d)}."""
        return self.d_lp ** -2, {d: Mi @ Mi for d, Mi in self.Winv.items()}


def _jprod(cones, u, v):
    """Jordan product u o v (orthant: elementwise; SOC: (u^T v, u0 v1 + v0 u1))."""
    out = np.empty_like(u)
    out[cones.lp] = u[cones.lp] * v[cones.lp]
    for rows in cones.soc.values():
        a, b = u[rows], v[rows]
        r = np.empty_like(a)
        r[:, 0] = np.sum(a * b, axis=1)
        r[:, 1:] = a[:, :1] * b[:, 1:] + b[:, :1] * a[:, 1:]
        out[rows] = r
    return out


def _jdiv(cones, lam, r):
    """u with lam o u = r (lam in int K)."""
    out = np.empty_like(r)
    out[cones.lp] = r[cones.lp] / lam[cones.lp]
    for rows in cones.soc.values():
        lm, rr = lam[rows], r[rows]
        l0 = lm[:, 0]
        u0 = (l0 * rr[:, 0] - np.sum(lm[:, 1:] * rr[:, 1:], axis=1)) / _jdot(lm)
        u = np.empty_like(rr)
        u[:, 0] = u0
        u[:, 1:] = (rr[:, 1:] - u0[:, None] * lm[:, 1:]) / l0[:, None]
        out[rows] = u
    return out


def _jinv(cones, s):
    """s^-1 (s o s^-1 = e): 1/s on the orthant, J s / (s^T J s) on each second-order cone."""
    out = np.empty_like(s)
    out[cones.lp] = 1.0 / s[cones.lp]
    for rows in cones.soc.values():
        u = s[rows].copy()
        u[:, 1:] *= -1.0
        out[rows] = u / _jdot(s[rows])[:, None]
    return out


class _Factor:
    """Factorisation of the SPD matrix H on a fixed upper-triangular CSC pattern."""

    def __init__(self, backend):
        if backend == "auto":
            backend = "qdldl" if qdldl is not None else "splu"
        if backend == "qdldl" and qdldl is None:
            raise ImportError("qdldl is not installed")
        if backend not in ("qdldl", "splu"):
            raise ValueError(f"unknown backend {backend!r}: use 'qdldl', 'splu' or 'auto'")
        self.backend = backend
        self.solver = None
        self.seconds = 0.0
        self.count = 0

    def factor(self, Hu):
        """Factorise from the upper triangle ``Hu`` (CSC; the pattern is fixed after the first)."""
        t = time.perf_counter()
        if self.backend == "qdldl":
            if self.solver is None:
                self.solver = qdldl.Solver(Hu, upper=True)
            else:
                self.solver.update(Hu, upper=True)
        else:
            full = Hu + sp.triu(Hu, 1, format="csc").T
            self.solver = spla.splu(full.tocsc(), permc_spec="MMD_AT_PLUS_A",
                                    options={"SymmetricMode": True})
        self.seconds += time.perf_counter() - t
        self.count += 1

    def solve(self, r):
        return self.solver.solve(r)


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
        self.cones = _Cones(cones)
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
        keys, srcs = [], []
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
            # H entries of the block: (cols[i], cols[j]) for i, j with row <= col (upper)
            ci = np.broadcast_to(cols[:, :, None], (nb, mc, mc))
            cj = np.broadcast_to(cols[:, None, :], (nb, mc, mc))
            ok = (ci >= 0) & (cj >= 0) & (ci <= cj)
            flat = np.flatnonzero(ok.ravel())
            keys.append(cj.ravel()[flat] * n + ci.ravel()[flat])  # column-major key: col*n+row
            srcs.append(flat)
            self.groups.append((kind, d, rows, gidx, flat))
        # P's upper triangle
        pc = np.repeat(np.arange(n), np.diff(Pu.indptr))
        keys.append(pc.astype(np.int64) * n + Pu.indices)
        diag_key = np.arange(n, dtype=np.int64) * (n + 1)
        keys.append(diag_key)  # the diagonal always (regularisation)
        allk = np.concatenate(keys)
        uk, inv = np.unique(allk, return_inverse=True)
        self.nnz = len(uk)
        hc, hr = uk // n, uk % n
        self.H_indptr = np.concatenate([[0], np.cumsum(np.bincount(hc, minlength=n))])
        self.H_indices = hr.astype(np.int32)
        offs = np.cumsum([0] + [len(k) for k in keys])
        self.targets = [inv[offs[i]:offs[i + 1]] for i in range(len(keys))]
        self.diag_pos = self.targets[-1]
        self.factor = _Factor(self.backend)

    def _same_pattern(self, P, A, cones):
        Ar = sp.csr_matrix(A)
        Ar.sum_duplicates()
        Ar.sort_indices()
        Pu = sp.csc_matrix(sp.triu(sp.csc_matrix(P), format="csc"))
        Pu.sum_duplicates()
        Pu.sort_indices()
        same = (tuple((k, int(d)) for k, d in cones) == self.cones.key
                and Ar.shape == (self.cones.m, self.n)
                and np.array_equal(Ar.indptr, self.A_indptr)
                and np.array_equal(Ar.indices, self.A_indices)
                and np.array_equal(Pu.indptr, self.P_indptr)
                and np.array_equal(Pu.indices, self.P_indices))
        return same, Ar, Pu

    def _schur(self, Pdata, Gs, scaling):
        """Upper triangle of H = P + A^T W^-2 A (+ REG) as CSC on the fixed pattern."""
        dlp, dsoc = scaling.inv2_blocks()
        vals = []
        for (kind, d, rows, gidx, flat), G in zip(self.groups, Gs):
            if kind == "lp":
                g = G[:, 0, :]
                contrib = dlp[:, None, None] * (g[:, :, None] * g[:, None, :])
            else:
                contrib = np.einsum("bik,bij,bjl->bkl", G, dsoc[d], G, optimize=True)
            vals.append(contrib.ravel()[flat])
        vals.append(Pdata)
        data = np.zeros(self.nnz)
        for t, v in zip(self.targets[:-1], vals):
            data += np.bincount(t, weights=v, minlength=self.nnz)
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
        x0 : (n,) float, optional; a start. When ``b - A x0`` is strictly inside K the method
            starts from x0 (a feasible start); otherwise x0 is shifted into the cone.
        tol_gap, tol_feas : float, stopping tolerances (absolute/relative gap; residuals)
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
            Ar = sp.csr_matrix(A)
            Ar.sum_duplicates()
            Ar.sort_indices()
            Pu = sp.csc_matrix(sp.triu(sp.csc_matrix(P), format="csc"))
            Pu.sum_duplicates()
            Pu.sort_indices()
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
        Gs = [Adata[g] for (_, _, _, g, _) in self.groups]
        Pdata = Pu.data
        e = c.identity()
        nq = max(1.0, float(np.max(np.abs(q)))) if n else 1.0
        nb_ = max(1.0, float(np.max(np.abs(b)))) if len(b) else 1.0

        def kkt(scaling, bx, bz, bs):
            """Solve P dx + A^T dz = bx, A dx + ds = bz, W dz + W^-1 ds = bs through H."""
            t = scaling.apply(scaling.apply(bs) - bz, inverse=True, power=2)
            dx = self.factor.solve(bx - At @ t)
            dz = scaling.apply(Ar @ dx + scaling.apply(bs) - bz, inverse=True, power=2)
            ds = scaling.apply(bs - scaling.apply(dz))
            return dx, ds, dz

        def newton(scaling, lam, rx, rz, rc):
            """Solve P dx + A^T dz = -rx, A dx + ds = -rz, lam o (W dz + W^-1 ds) = rc.

            The Schur complement loses accuracy as W becomes ill-conditioned near the optimum;
            a few steps of iterative refinement on the unreduced system restore it (each one
            back-solve with the same factors).
            """
            bx, bz, bs = -rx, -rz, _jdiv(c, lam, rc)      # W dz + W^-1 ds = bs
            dx, ds, dz = kkt(scaling, bx, bz, bs)
            scale = max(1.0, float(np.max(np.abs(bx))), float(np.max(np.abs(bz))),
                        float(np.max(np.abs(bs))))
            for _ in range(REFINE):
                ex = bx - Pfull @ dx - At @ dz
                ez = bz - Ar @ dx - ds
                es = bs - scaling.apply(dz) - scaling.apply(ds, inverse=True)
                err = max(float(np.max(np.abs(ex))), float(np.max(np.abs(ez))),
                          float(np.max(np.abs(es))))
                if err <= 1e-13 * scale:
                    break
                cx, cs, cz = kkt(scaling, ex, ez, es)
                dx, ds, dz = dx + cx, ds + cs, dz + cz
            return dx, ds, dz

        # Starting point.
        feasible_start = False
        if x0 is not None:
            x = np.asarray(x0, np.float64).copy()
            s = b - Ar @ x
            feasible_start = c.margin(s) > 0
        if feasible_start:
            # A feasible start: keep (x0, s0) and pick z = mu s^-1 on the central path, mu matched
            # to the size of the dual residual the start leaves (P x0 + q).
            sinv = _jinv(c, s)
            g = Pfull @ x + q
            ga = At @ sinv
            mu = float(np.linalg.norm(g) / max(np.linalg.norm(ga), 1e-300))
            mu = max(mu, 1e-8 * max(1.0, abs(float(0.5 * x @ g + 0.5 * q @ x))) / c.degree)
            z = mu * sinv
        else:
            # CVXOPT's default start: the W = I Newton system, then shift s and z into int K.
            ident = _Scaling(c, e, e)
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
                    gap <= tol_gap or gap <= tol_gap * max(1e-300, min(abs(pobj), abs(dobj)))):
                status = "Solved"
                break
            bz = float(b @ z)
            if bz < 0:
                atz = float(np.max(np.abs(At @ z))) if n else 0.0
                if atz <= TOL_INFEAS * (-bz) * max(1.0, float(np.max(np.abs(x)))):
                    status = "PrimalInfeasible"
                    break
            score = max(pres, dres, gap / max(1.0, abs(pobj)))
            if _DEBUG:
                print(f"{it:3d} pobj {pobj:+.6e} dobj {dobj:+.6e} gap {gap:.2e} pres {pres:.2e} "
                      f"dres {dres:.2e}")
            if not np.isfinite(score):
                status = "NumericalError"
                break
            if score < best[0] * 0.999:
                best = (score, x.copy())
                self.last_info = dict(pres=pres, dres=dres, gap=gap, pobj=pobj, dobj=dobj)
                stall = 0
            else:
                stall += 1
                if stall >= 10:
                    status = "InsufficientProgress"
                    break
            scaling = _Scaling(c, s, z)
            lam = scaling.apply(z)
            self.factor.factor(self._schur(Pdata, Gs, scaling))
            # predictor (affine scaling)
            lamsq = _jprod(c, lam, lam)
            dxa, dsa, dza = newton(scaling, lam, rx, rz, -lamsq)
            aa = min(1.0, c.step(s, dsa), c.step(z, dza))
            sigma = (1.0 - aa) ** 3
            # corrector (Mehrotra): second-order term (W^-1 ds_a) o (W dz_a)
            corr = _jprod(c, scaling.apply(dsa, inverse=True), scaling.apply(dza))
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
