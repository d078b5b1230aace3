"""The steps of a live frame: the energy's local/global iterations with the pins held, and the
similarity of the pins that is always feasible.

The energies share one global matrix with the projection iterations (Kovalsky, Galun and Lipman
2015): ``L = sum_j A_j G_j^T G_j``, the area-weighted Frobenius distance of each face's Jacobian to
a target, so one factorisation per pin set serves both. The projection here is that of
``solvers.projection`` (the tangent step included) for one component with its pins held, lean
enough for a frame: on a 10k-face disk the general solver's per-call set-up alone took about
10 ms, a frame's budget being 33. Per method the local step's target is
(Lipman 2012, section 6.1):

- "arap": the rotation nearest each face's Jacobian, ``alpha / |alpha|`` (BD-ARAP);
- "lscm": the similarity part ``alpha`` itself (BD-LSCM / ASAP: the iterations converge to the
  least-squares conformal map with the pins);
- "dirichlet": the identity (the rest shape's Jacobian): the harmonic map with the pins, one step.
"""
import time

import numpy as np
import scipy.sparse as sp

from ..errors import CancelledError
from ..solvers.factor import factor_spd
from ..solvers.local_projection import nearest_jacobian_parts, project_singular_values

__all__ = ["EnergySteps", "pin_similarity", "apply_similarity", "project_frame", "LIVE_METHODS"]

LIVE_METHODS = ("arap", "lscm", "dirichlet")


class EnergySteps:
    """Local/global iterations of one energy with a fixed set of pinned vertices.

    Parameters
    ----------
    G : (2k, n) csr, rows d/dx then d/dy of each face against the rest shape
    area : (k,) float64, rest areas
    pins : (p,) int64, distinct vertices held
    solve : callable, back-solve with ``L_ff`` (``factor_spd``); may be set after construction

    Attributes
    ----------
    free : (n - p,) int64
    L_ff : (n - p, n - p) csc, the global matrix over the free vertices, symmetric positive
        definite; L_fF its columns of the pins
    """

    def __init__(self, G, area, pins, solve):
        self.G, self.GT = G, sp.csr_array(G.T)
        self.k = len(area)
        self.area2 = np.concatenate([area, area])[:, None]
        n = G.shape[1]
        self.pins = np.asarray(pins, dtype=np.int64)
        self.free = np.setdiff1d(np.arange(n), self.pins)
        W = sp.diags_array(self.area2[:, 0])
        L = (self.GT @ W @ self.G).tocsr()
        Lf = L[self.free]
        self.L_ff = sp.csc_array(Lf[:, self.free])
        self.L_fF = sp.csr_array(Lf[:, self.pins])
        self.solve = solve

    def targets(self, method, U):
        """Per-face target Jacobians (2k, 2) of the local step for ``U`` (n,2)."""
        k = self.k
        R = self.G @ U
        ux, uy, vx, vy = R[:k, 0], R[k:, 0], R[:k, 1], R[k:, 1]
        P = np.empty_like(R)
        if method == "dirichlet":
            P[:k, 0], P[k:, 0], P[:k, 1], P[k:, 1] = 1.0, 0.0, 0.0, 1.0
            return P
        are, aim = 0.5 * (ux + vy), 0.5 * (vx - uy)      # alpha
        if method == "arap":
            r = np.hypot(are, aim)
            ok = r > 0
            c = np.where(ok, are / np.where(ok, r, 1.0), 1.0)
            s = np.where(ok, aim / np.where(ok, r, 1.0), 0.0)
            are, aim = c, s
        P[:k, 0], P[k:, 0], P[:k, 1], P[k:, 1] = are, -aim, aim, are
        return P

    def iterate(self, method, U, iterations, cancel=None):
        """``iterations`` local/global steps from ``U`` (n,2), pins held at ``U[pins]``.

        Returns the new (n,2) map (a copy); ``dirichlet`` needs one step."""
        U = np.array(U, dtype=np.float64, copy=True)
        rhs_fixed = self.L_fF @ U[self.pins]
        for _ in range(1 if method == "dirichlet" else iterations):
            if cancel is not None and cancel.is_set():
                raise CancelledError("live frame cancelled")
            B = (self.GT @ (self.area2 * self.targets(method, U)))[self.free] - rhs_fixed
            U[self.free] = self.solve(B)
        return U


def pin_similarity(P, T):
    """The similarity ``z -> s z + t`` taking the pins ``P`` (p,2) nearest to ``T`` (p,2) in the
    least-squares sense (exact for two pins): returns complex ``s, t``. A single pin (or pins at
    one point) gives a translation."""
    p = P[:, 0] + 1j * P[:, 1]
    q = T[:, 0] + 1j * T[:, 1]
    pm, qm = p.mean(), q.mean()
    dp, dq = p - pm, q - qm
    den = float(np.sum(np.abs(dp) ** 2))
    s = complex(np.sum(np.conj(dp) * dq) / den) if den > 0 else 1.0 + 0j
    return s, qm - s * pm


def apply_similarity(U, s, t):
    """``s z + t`` applied to ``U`` (n,2); returns (n,2)."""
    z = s * (U[:, 0] + 1j * U[:, 1]) + t
    return np.column_stack([z.real, z.imag])


def project_frame(steps, U, C, max_iter, margin=0.9, floor=1e-3, cancel=None):
    """Projection iterations from ``U`` (n,2) onto the maps with every face within C, pins held
    at ``U[pins]`` (Kovalsky et al. 2015: the local step is ``local_projection``, exact per face;
    the global step one back-solve with the shared factorisation, accelerated by their tangent
    step).

    Parameters
    ----------
    steps : EnergySteps of the pin set
    U : (n,2) float64, the start (may flip)
    C : float > 1; the projection aims at ``max(1 + 1e-3, margin C)``
    max_iter : int, global steps at most
    floor : float, lower bound on sigma_2 relative to the map's scale (keeps faces from collapse)
    cancel : object with ``is_set()``

    Returns
    -------
    U : (n,2) float64, the first iterate with every face within C and none flipped, or the last
    within : bool, iterations : int
    """
    U = np.array(U, dtype=np.float64, copy=True)
    k, G = steps.k, steps.G
    area = steps.area2[:k, 0]
    kappa = max(1.0 + 1e-3, margin * C)
    lo, prev_err = None, np.inf
    for it in range(max_iter + 1):
        R = G @ U
        ux, uy, vx, vy = R[:k, 0], R[k:, 0], R[:k, 1], R[k:, 1]
        are, aim, bre, bim = ux + vy, vx - uy, ux - vy, vx + uy       # 2 alpha, 2 beta
        na, nb = 0.5 * np.hypot(are, aim), 0.5 * np.hypot(bre, bim)
        s1, s2 = na + nb, na - nb
        if np.all(s1 <= C * s2) and np.all(s2 > 0):
            return U, True, it
        if it == max_iter:
            break
        if cancel is not None and cancel.is_set():
            raise CancelledError("live frame cancelled")
        if lo is None:
            scale = np.sqrt(max(float(np.sum(area * np.abs(s1 * s2))) / float(area.sum()),
                                1e-300))
            lo = np.full(k, floor * scale)
        t1, t2, moved = project_singular_values(s1, s2, kappa, lo, np.inf)
        m = np.flatnonzero(moved)
        pre, pim, qre, qim = nearest_jacobian_parts(t1[m], t2[m], na[m], nb[m], are[m], aim[m],
                                                    bre[m], bim[m])
        # The normal N = J - P, non-zero on the moved faces only: rows m (d/dx) and k + m (d/dy).
        rows = np.concatenate([m, k + m])
        N = np.empty((len(rows), 2))
        N[:len(m), 0], N[len(m):, 0] = ux[m] - (pre + qre), uy[m] - (qim - pim)
        N[:len(m), 1], N[len(m):, 1] = vx[m] - (pim + qim), vy[m] - (pre - qre)
        aN = steps.area2[rows] * N
        err = float(np.sum(aN * N))
        # Global step, with the tangent step of Kovalsky et al. (the lifted map on the hyperplane
        # through P orthogonal to N) unless the distance to the set grew. With P = J - N the
        # plain step is U_free - L_ff^-1 (G^T A N)_free, since G^T A J = L U: only the moved
        # faces' rows of G are needed; 4 columns, one solve.
        GmT = steps.G[rows].T
        GB = GmT @ np.concatenate([aN, N], axis=1)        # (n, 4): G^T A N, G^T N
        B = GB[steps.free]
        Y = steps.solve(B)
        Xc = U[steps.free] - Y[:, :2]
        if err <= prev_err * (1 + 1e-12):
            UF = U[steps.pins]
            nP = float(np.sum(N * (R[rows] - N)))
            r = nP - float(np.sum(GB[steps.pins, 2:] * UF))
            cxc = float(np.sum(B[:, 2:] * Xc))
            cxn = float(np.sum(B[:, 2:] * Y[:, 2:]))
            lam = (cxc - r) / cxn if cxn != 0 else 0.0
            if np.isfinite(lam):
                Xc = Xc - lam * Y[:, 2:]
        prev_err = err
        U[steps.free] = Xc
    return U, False, max_iter


class _PinSet:
    """What one pin set needs: the energy's and the projection's steps, one factorisation."""

    def __init__(self, G, area, pins, backend):
        self.pins = pins                                  # sorted, distinct
        self.steps = EnergySteps(G, area, pins, None)
        t0 = time.perf_counter()
        self.steps.solve, self.backend = factor_spd(self.steps.L_ff, backend)
        self.factor_seconds = time.perf_counter() - t0
