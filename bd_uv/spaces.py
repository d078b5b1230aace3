"""The convex bounded-distortion spaces as conic constraints (Lipman 2012, eqs. 4.15-4.18, 4.22).

With ``r_j = Re(w_j alpha_j)`` substituted (a larger r only widens eq. 4.15, so the optimum sets
r_j = Re(w_j alpha_j)), face j's constraints are

    Re(w_j alpha_j) >= sigma                      (4.16, 4.17)
    |beta_j| <= k Re(w_j alpha_j),  k = (C-1)/(C+1)   (4.15, second-order cone), or
    |Re beta_j|, |Im beta_j| <= k Re(w_j alpha_j) / sqrt(2)  (4.22, the L-infinity variant)

and continuity (4.18) holds by construction, alpha and beta being linear in the vertex positions.
In Clarabel's form ``A x + s = b, s in K``.
"""
import numpy as np
import scipy.sparse as sp

from .energies import rotated_alpha


def cone_factor(C):
    """k = (C-1)/(C+1) of eq. 4.15."""
    return (C - 1.0) / (C + 1.0)


def bounded_distortion_space(ops, w, C, sigma, cone="soc"):
    """Constraint blocks of F_C (``cone="soc"``) or F_C^inf (``cone="linf"``) for frames ``w``.

    Parameters
    ----------
    ops : energies.JacobianOperators
    w : (k,) complex unit frames
    C : float >= 1, the distortion bound
    sigma : float > 0, lower bound on Re(w alpha) (eq. 4.17 as r >= sigma)
    cone : "soc" or "linf"

    Returns
    -------
    A : (rows, 2nv) csc, b : (rows,), cones : list of (kind, dim) with kind in {"nonneg", "soc"}
    """
    k = cone_factor(C)
    Ra, _ = rotated_alpha(ops, w)
    nf = Ra.shape[0]
    # Re(w alpha) >= sigma:  -Ra x + s = -sigma, s >= 0
    blocks = [-Ra]
    b = [np.full(nf, -sigma)]
    if cone == "soc":
        # (k Ra x, Bre x, Bim x) in SOC(3), interleaved per face: s = 0 - (-[...] x)
        stack = sp.vstack([k * Ra, ops.Bre, ops.Bim]).tocsr()
        perm = np.arange(3 * nf).reshape(3, nf).T.ravel()
        blocks.append(-stack[perm])
        b.append(np.zeros(3 * nf))
        cones = [("nonneg", nf)] + [("soc", 3)] * nf
    elif cone == "linf":
        kk = k / np.sqrt(2.0)
        # kk Ra x -/+ Bre x >= 0 and the same for Bim
        rows = [kk * Ra - ops.Bre, kk * Ra + ops.Bre, kk * Ra - ops.Bim, kk * Ra + ops.Bim]
        blocks.extend(-r for r in rows)
        b.append(np.zeros(4 * nf))
        cones = [("nonneg", 5 * nf)]
    else:
        raise ValueError(f"unknown cone {cone!r}: use 'soc' or 'linf'")
    return sp.vstack(blocks).tocsc(), np.concatenate(b), cones
