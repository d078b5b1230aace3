"""The steps of a live frame: the energy's local/global iterations with the pins held, and the
similarity of the pins that is always feasible.

The energies share one global matrix with the projection iterations (``solvers.projection``):
``L = sum_j A_j G_j^T G_j``, the area-weighted Frobenius distance of each face's Jacobian to a
target, so one factorisation per pin set serves both. Per method the local step's target is
(Lipman 2012, section 6.1):

- "arap": the rotation nearest each face's Jacobian, ``alpha / |alpha|`` (BD-ARAP);
- "lscm": the similarity part ``alpha`` itself (BD-LSCM / ASAP: the iterations converge to the
  least-squares conformal map with the pins);
- "dirichlet": the identity (the rest shape's Jacobian): the harmonic map with the pins, one step.
"""
import numpy as np
import scipy.sparse as sp

from ..errors import CancelledError

__all__ = ["EnergySteps", "pin_similarity", "LIVE_METHODS"]

LIVE_METHODS = ("arap", "lscm", "dirichlet")


class EnergySteps:
    """Local/global iterations of one energy with a fixed set of pinned vertices.

    Parameters
    ----------
    G : (2k, n) csr, rows d/dx then d/dy of each face against the rest shape
    area : (k,) float64, rest areas
    pins : (p,) int64, distinct vertices held
    solve : callable, back-solve with the global matrix over the free vertices (``factor_spd``)

    Attributes
    ----------
    free : (n - p,) int64
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
        self.L_fF = sp.csr_array(L[self.free][:, self.pins])
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
