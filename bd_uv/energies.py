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
    """Sparse (k, 2nv) operators with ``Are @ x = Re(alpha)`` and so on; ``area`` (k,);
    ``tris`` (k,3) the faces they were built on (for the vertex mass of "biharmonic");
    ``gx``, ``gy`` (k,3) each face's gradient coefficients on its corners ``tris`` (d/dx and d/dy
    of a linear function, ``geometry.gradient_operators``), when built from them: the projection
    solver's global step is written from them without reading them back out of the operators."""
    Are: sp.csr_array
    Aim: sp.csr_array
    Bre: sp.csr_array
    Bim: sp.csr_array
    area: np.ndarray
    tris: np.ndarray = None
    gx: np.ndarray = None
    gy: np.ndarray = None


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
    G, area = face_operators(Z)
    g0, g1 = G[:, 0, :].ravel(), G[:, 1, :].ravel()
    cols = np.concatenate([tris, tris + nv], axis=1).ravel()    # six entries a face's row
    indptr = np.arange(0, 6 * k + 1, 6)
    shape = (k, 2 * nv)

    def op(vx, vy):
        # Written in compressed rows straight (a triplet matrix's conversion is ~0.15 ms of
        # fixed cost each, four per island); made canonical as that conversion leaves it (which
        # sorts the indices in place: each matrix its own copy).
        M = sp.csr_array((np.concatenate([vx.reshape(k, 3), vy.reshape(k, 3)], axis=1).ravel(),
                          cols.copy(), indptr.copy()), shape=shape)
        M.sum_duplicates()
        return M

    # Re a = (u_x + v_y)/2, Im a = (v_x - u_y)/2, Re b = (u_x - v_y)/2, Im b = (v_x + u_y)/2.
    return JacobianOperators(op(0.5 * g0, 0.5 * g1), op(-0.5 * g1, 0.5 * g0),
                             op(0.5 * g0, -0.5 * g1), op(0.5 * g1, 0.5 * g0), area,
                             np.asarray(tris, dtype=np.int64), G[:, 0, :], G[:, 1, :])


def face_operators(Z):
    """(G (k,2,3) each face's gradient operator: d/dx, d/dy of a linear function from its corner
    values, area (k,)) of the faces with local corner coordinates Z (k,3) complex: the geometry
    ``jacobian_operators`` builds its operators from (``unwrapping.disk_auto`` uses it bare)."""
    G = gradient_operators(Z)
    area = 0.5 * np.abs(((Z[:, 1] - Z[:, 0]).conj() * (Z[:, 2] - Z[:, 0])).imag)
    return G, area


def rotated_alpha(ops, w):
    """Operators for Re(w alpha) and Im(w alpha), each (k, 2nv)."""
    c = sp.diags(w.real)
    s = sp.diags(w.imag)
    return (c @ ops.Are - s @ ops.Aim).tocsr(), (s @ ops.Are + c @ ops.Aim).tocsr()


def energy(method, ops, w):
    """Quadratic form of an energy: ``E(x) = x^T P x / 2 + q^T x + const``.

    Parameters
    ----------
    method : "lscm" (sum A |beta|^2), "dirichlet" (sum A (|alpha|^2 + |beta|^2)), "arap"
        (sum A (|w alpha - 1|^2 + |beta|^2), frames ``w`` from the previous map) or "biharmonic"
        (``U* L M^-1 L U``, eq. 6.1, see ``biharmonic_matrix``).
    ops : JacobianOperators
    w : (k,) complex frames (used by "arap")

    Returns
    -------
    P : (2nv, 2nv) csc, q : (2nv,), const : float
    """
    if method == "biharmonic":
        K = biharmonic_matrix(ops)
        return sp.csc_array(2.0 * sp.block_diag([K, K])), np.zeros(2 * K.shape[0]), 0.0
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
        raise ValueError(f"unknown method {method!r}: use 'lscm', 'arap', 'dirichlet' or "
                         "'biharmonic' ('stretch-l1' is a cone program: stretch_l1_program)")
    return sp.csc_array(2.0 * P), q, const


def cotangent_laplacian(ops):
    """Cotangent stiffness matrix ``L`` (nv, nv), positive semidefinite.

    ``u^T L u = sum_j Area_j |grad u|^2`` for real vertex values u (nv,).

    Built from the Jacobian operators: ``|alpha|^2 + |beta|^2 = (|grad Re u|^2 + |grad Im u|^2)/2``
    per face, so the Dirichlet form in x is ``blockdiag(L, L) / 2``.
    """
    nv = ops.Are.shape[1] // 2
    W = sp.diags(ops.area)
    D = ops.Are.T @ W @ ops.Are + ops.Aim.T @ W @ ops.Aim + ops.Bre.T @ W @ ops.Bre \
        + ops.Bim.T @ W @ ops.Bim
    return sp.csr_array(2.0 * sp.csr_array(D)[:nv][:, :nv])


def lumped_mass(ops):
    """Lumped (barycentric) mass of each vertex, (nv,): a third of the area of its faces."""
    nv = ops.Are.shape[1] // 2
    return np.bincount(ops.tris.ravel(), weights=np.repeat(ops.area / 3.0, 3), minlength=nv)


def biharmonic_matrix(ops):
    """``K = L M^-1 L`` (nv, nv) of the biharmonic energy ``U* K U`` (Lipman 2012, eq. 6.1).

    ``L`` is the cotangent Laplacian and ``M`` the lumped mass matrix (the linear finite elements
    of Jacobson et al. 2011). The energy acts on Re u and Im u alike.
    """
    L = cotangent_laplacian(ops)
    return sp.csr_array(L @ sp.diags(1.0 / lumped_mass(ops)) @ L)


def stretch_l1_program(ops, A, b, cones):
    """The L1 stretch energy ``sum (|alpha_j| + |beta_j|) Area_j`` over a space, as a cone program.

    Lipman 2012, section 6.1 ("Dirichlet and stretch energy"). Epigraph variables ``t = [ta; tb]``
    (2k) with ``|alpha_j| <= ta_j`` and ``|beta_j| <= tb_j`` (second-order cones); the objective
    ``sum Area_j (ta_j + tb_j)`` is linear. The space's rows ``(A, b, cones)`` (e.g. from
    ``spaces.bounded_distortion_space``, optionally stacked with ``spaces.stretch_space``) are
    padded with zero columns for t.

    Parameters
    ----------
    ops : JacobianOperators
    A : (rows, 2nv) sparse, b : (rows,), cones : list of (kind, dim), the space's rows

    Returns
    -------
    P : (2nv+2k, 2nv+2k) csc (zero), q : (2nv+2k,), A : csc, b, cones
        Unknowns ``[x; ta; tb]``; the first 2nv entries of the solution are ``x = [Re u; Im u]``.
    """
    k = len(ops.area)
    n = A.shape[1]
    perm = np.arange(3 * k).reshape(3, k).T.ravel()
    Ik = sp.identity(k, format="csr")
    Z = sp.csr_array((k, k))
    # (ta_j, Re alpha_j, Im alpha_j) in SOC(3): s = 0 - [-ta; -Are x; -Aim x]
    rows_a = sp.vstack([sp.hstack([sp.csr_array((k, n)), -Ik, Z]),
                        sp.hstack([-ops.Are, Z, Z]), sp.hstack([-ops.Aim, Z, Z])]).tocsr()[perm]
    rows_b = sp.vstack([sp.hstack([sp.csr_array((k, n)), Z, -Ik]),
                        sp.hstack([-ops.Bre, Z, Z]), sp.hstack([-ops.Bim, Z, Z])]).tocsr()[perm]
    Ax = sp.hstack([sp.csr_array(A), sp.csr_array((A.shape[0], 2 * k))])
    A_all = sp.vstack([Ax, rows_a, rows_b]).tocsc()
    b_all = np.concatenate([b, np.zeros(6 * k)])
    q = np.concatenate([np.zeros(n), ops.area, ops.area])
    P = sp.csc_array((n + 2 * k, n + 2 * k))
    return P, q, A_all, b_all, list(cones) + [("soc", 3)] * (2 * k)
