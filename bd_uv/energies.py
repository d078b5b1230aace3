"""Linear Jacobian operators and the quadratic energies of section 6 (Lipman 2012).

Variables are ``x = [Re u; Im u]`` (size 2 nv) for the island's vertex positions ``u``. Per face the
map is ``z -> alpha z + beta conj(z) + delta`` (eq. 4.6); alpha and beta are linear in x (eq. 4.19).
"""
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .geometry import gradient_operators


@dataclass(frozen=True)
class JacobianOperators:
    """Sparse (k, 2nv) operators with ``Are @ x = Re(alpha)`` and so on; ``area`` (k,)."""
    Are: sp.csr_array
    Aim: sp.csr_array
    Bre: sp.csr_array
    Bim: sp.csr_array
    area: np.ndarray


def jacobian_operators(Z, tris, nv):
    """Operators giving each face's alpha and beta from the vertex positions (eq. 4.19).

    Parameters
    ----------
    Z : (k,3) complex, local corner coordinates
    tris : (k,3) int
    nv : int

    Returns
    -------
    JacobianOperators
    """
    k = len(tris)
    G = gradient_operators(Z)  # (k,2,3): d/dx, d/dy of a linear function from corner values
    g0, g1 = G[:, 0, :].ravel(), G[:, 1, :].ravel()
    rows = np.repeat(np.arange(k), 3)
    cx, cy = tris.ravel(), tris.ravel() + nv
    shape = (k, 2 * nv)

    def op(vx, vy):
        return sp.coo_array((np.concatenate([vx, vy]), (np.concatenate([rows, rows]),
                                                        np.concatenate([cx, cy]))),
                            shape=shape).tocsr()

    # Re a = (u_x + v_y)/2, Im a = (v_x - u_y)/2, Re b = (u_x - v_y)/2, Im b = (v_x + u_y)/2.
    area = 0.5 * np.abs(((Z[:, 1] - Z[:, 0]).conj() * (Z[:, 2] - Z[:, 0])).imag)
    return JacobianOperators(op(0.5 * g0, 0.5 * g1), op(-0.5 * g1, 0.5 * g0),
                             op(0.5 * g0, -0.5 * g1), op(0.5 * g1, 0.5 * g0), area)


def rotated_alpha(ops, w):
    """Operators for Re(w alpha) and Im(w alpha), each (k, 2nv)."""
    c = sp.diags(w.real)
    s = sp.diags(w.imag)
    return (c @ ops.Are - s @ ops.Aim).tocsr(), (s @ ops.Are + c @ ops.Aim).tocsr()


def energy(method, ops, w):
    """Quadratic form of an energy: ``E(x) = x^T P x / 2 + q^T x + const``.

    Parameters
    ----------
    method : "lscm" (sum A |beta|^2), "dirichlet" (sum A (|alpha|^2 + |beta|^2)) or "arap"
        (sum A (|w alpha - 1|^2 + |beta|^2), frames ``w`` from the previous map).
    ops : JacobianOperators
    w : (k,) complex frames (used by "arap")

    Returns
    -------
    P : (2nv, 2nv) csc, q : (2nv,), const : float
    """
    W = sp.diags(ops.area)
    P = ops.Bre.T @ W @ ops.Bre + ops.Bim.T @ W @ ops.Bim
    q = np.zeros(P.shape[0])
    const = 0.0
    if method == "dirichlet":
        P = P + ops.Are.T @ W @ ops.Are + ops.Aim.T @ W @ ops.Aim
    elif method == "arap":
        Ra, Ia = rotated_alpha(ops, w)
        P = P + Ra.T @ W @ Ra + Ia.T @ W @ Ia
        q = -2.0 * (Ra.T @ ops.area)
        const = float(ops.area.sum())
    elif method != "lscm":
        raise ValueError(f"unknown method {method!r}: use 'lscm', 'arap' or 'dirichlet'")
    return sp.csc_array(2.0 * P), q, const
