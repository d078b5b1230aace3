"""The framed cones of ``bound_search``'s ADMM on the whole map (islands over
``bound_search.ONE_PRODUCT_FACES`` faces): the lift of a map to every face's doubled alpha and
beta by the gradient operator, the right-hand side operator back, and every face's projection onto
its cone ``|beta| <= kappa Re(w alpha)`` (Lipman 2012, eq. 4.15) on whole arrays.
"""
import numpy as np

from .free_admm import sparse_product

__all__ = ["framed_cone_projection", "gradient_products", "matvec", "project_framed"]


def matvec(M):
    """``x, out -> out = M @ x`` for a csr or csc float64 matrix M into a preallocated ``out``
    (``free_admm.sparse_product``: the compiled product straight); ``.add`` accumulates."""
    add = sparse_product(M.format, M.shape, M.indptr, M.indices)
    data = M.data

    def mv(x, out):
        out.fill(0.0)
        add(data, x, out)
        return out
    mv.add = lambda x, out: add(data, x, out)
    return mv


def framed_cone_projection(x, br, bi, kappa):
    """Nearest point of the cone ``|b| <= kappa x`` to ``(x, b)``, per face (Euclidean in
    ``(x, Re b, Im b)``: the Frobenius distance of Jacobians with the other part of alpha held).

    Parameters
    ----------
    x : (k,) float, Re(w alpha); br, bi : (k,) float, beta; kappa : float > 0

    Returns
    -------
    x, br, bi : (k,) float64, the projected point
    """
    nb = np.hypot(br, bi)
    inside = nb <= kappa * x
    polar = kappa * nb <= -x
    t = (x + kappa * nb) / (1.0 + kappa * kappa)   # on the cone's boundary ray
    with np.errstate(invalid="ignore", divide="ignore"):
        f = np.where(nb > 0, kappa * t / nb, 0.0)
    f = np.where(inside, 1.0, np.where(polar, 0.0, f))
    return np.where(inside, x, np.where(polar, 0.0, t)), f * br, f * bi


def gradient_products(G, GTA, k, nv, nf):
    """The lift of ``[u; v]`` (2nv) to every face's doubled alpha and beta (4k) and the
    least-squares step's right-hand side operator (``bound_search.BoundSearch._operators``'), by
    products with the gradient operator ``G`` (2k, nv) and ``GTA = (G^T diag(A, A))[free]`` (nf
    free vertices), coordinate by coordinate: half the multiply-adds of the (4k, 2nv) lift (k
    faces). Returns (lift, rhs), each ``f(x, out)``."""
    g, h = matvec(G), matvec(GTA)
    gu, gv = np.empty(2 * k), np.empty(2 * k)
    tu, tv = np.empty(2 * k), np.empty(2 * k)

    def lift(x, out):
        g(x[:nv], gu)
        g(x[nv:], gv)
        W = out.reshape(4, k)
        np.add(gu[:k], gv[k:], out=W[0])            # u_x + v_y
        np.subtract(gv[:k], gu[k:], out=W[1])       # v_x - u_y
        np.subtract(gu[:k], gv[k:], out=W[2])       # u_x - v_y
        np.add(gv[:k], gu[k:], out=W[3])            # v_x + u_y
        return out

    def rhs(z, out):
        Z = z.reshape(4, k)
        np.add(Z[0], Z[2], out=tu[:k])              # 2 u_x target
        np.subtract(Z[3], Z[1], out=tu[k:])         # 2 u_y
        np.add(Z[1], Z[3], out=tv[:k])              # 2 v_x
        np.subtract(Z[0], Z[2], out=tv[k:])         # 2 v_y
        np.multiply(tu, 0.5, out=tu)
        np.multiply(tv, 0.5, out=tv)
        h(tu, out[:nf])
        h(tv, out[nf:])
        return out
    return lift, rhs



def project_framed(Q, w2, kappa):
    """Every face's doubled (alpha, beta) of Q (4, k), in place, onto its cone ``|beta| <=
    kappa Re(w alpha)``; only faces outside it move. On whole arrays rather than on the faces
    outside: the cone moves only ``x = Re(w alpha)`` (alpha by ``conj(w) dx``; ``w2`` is
    ``(Re w, -Im w)``) and scales beta (``framed_cone_projection``'s point)."""
    # With t = max(x + kappa |beta|, 0) / (1 + kappa^2) (the boundary ray's point),
    # kappa t / |beta| >= 1 and t - x <= 0 exactly inside the cone, and < 1, >= 0 outside:
    # beta scales by min(1, kappa t / |beta|), x moves by max(t - x, 0), no mask needed.
    x = np.einsum("ij,ij->j", w2, Q[:2])                    # Re(w alpha)
    # |beta| (one product-sum and a root: hypot's careful scaling is not needed here)
    nb = np.sqrt(np.einsum("ij,ij->j", Q[2:], Q[2:]))
    t = kappa * nb
    t += x
    np.maximum(t, 0.0, out=t)
    t *= 1.0 / (1.0 + kappa * kappa)
    f = (kappa * t) / np.maximum(nb, 1e-300)
    np.minimum(f, 1.0, out=f)
    Q[2:] *= f
    t -= x
    np.maximum(t, 0.0, out=t)
    Q[:2] += w2 * t
    return Q
