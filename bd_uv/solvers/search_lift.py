"""The lift of ``bound_search``'s maps to every face's doubled alpha and beta (Lipman 2012,
eq. 4.19) and their max conformal distortion: on the free unknowns in every face's frame
(``free_admm.FreeLift``: islands up to ``bound_search.ONE_PRODUCT_FACES`` faces, or any
``disk_auto`` searches), else by the gradient operator (``framed_cone.gradient_products``).

Split from ``bound_search`` (the search over C and its ADMM): the operators a search builds once
and every target and measure reads.
"""
import numpy as np
import scipy.sparse as sp

from ..array_calls import einsum, quiet
from .face_operators import free_lift_arrays
from .framed_cone import gradient_products
from .free_admm import FreeLift

__all__ = ["SearchLift"]


class SearchLift:
    """The lift and the max distortion of maps over a ``global_step.GlobalStep`` ``solver``,
    on the free path (``on_free``) or the whole map's. ``UF``: the fixed vertices' values the
    free lift holds (set by ``distortion_of``)."""

    def __init__(self, solver, on_free):
        self.solver, self.k, self.on_free = solver, len(solver.area), on_free
        self.UF = None
        self._rhs_fixed = None      # (UF, its share of the right-hand side; small: its FreeLift)
        self._B = self._free = None
        self._measured = None       # (the map distortion_of measured last, its max)

    def _operators(self):
        """The lift of a map straight to every face's doubled alpha and beta (eq. 4.19), one
        sparse product: ``B`` (4k, 2nv) takes ``[u; v]`` to rows ``Re 2alpha = u_x + v_y``,
        ``Im 2alpha = v_x - u_y``, ``Re 2beta = u_x - v_y``, ``Im 2beta = v_x + u_y``. The
        Jacobians' Frobenius norm is half this one's, so the area-weighted least-squares step in
        these coordinates is the same step (its right-hand side ``B_free^T A (z - lam) / 2``), and
        the cone projection needs no change of coordinates: about half the array operations an
        iteration made on the (u_x, u_y; v_x, v_y) rows. Returns (lift, rhs), each
        ``f(x, out)``: off the free path (``on_free``) by the gradient operator
        (``framed_cone.gradient_products``), the same values."""
        if self._B is None and self._free is None:
            s = self.solver
            if self.on_free:
                gx, gy = s.face_gradients()
                self._B = self._BtA = None      # the free lift's (``_free_lift``)
                self._free = free_lift_arrays(gx, gy, s.area, s.tris, s.free, s.nv)
            else:
                G = s.G
                GTA = s.GT[s.free] @ sp.diags_array(np.concatenate([s.area, s.area]))
                self._B, self._BtA = gradient_products(G, sp.csr_array(GTA), self.k, s.nv,
                                                         len(s.free))
        return self._B, self._BtA

    def max_distortion(self, W):
        """Max conformal distortion (eq. 4.9) of the map with doubled alpha and beta W (4, k)
        (``_operators``); inf when a face flips or collapses."""
        with quiet("invalid", "divide"):
            return self._max_distortion(W)

    @staticmethod
    def _max_distortion(W):
        """``max_distortion`` where the caller has silenced division warnings."""
        num = einsum("ij,ij->j", W[2:], W[2:])                      # |2 beta|^2
        num /= einsum("ij,ij->j", W[:2], W[:2])                     # over |2 alpha|^2
        r = float(np.maximum.reduce(num))                           # |beta|^2 / |alpha|^2
        if not r < 1.0:
            return np.inf
        r = np.sqrt(r)
        return (1.0 + r) / (1.0 - r)

    def _alpha2(self, U):
        """(k,) complex, every face's doubled alpha of the map U (2, nv)."""
        W = self._lift(U)
        return W[0] + 1j * W[1]

    def _lift(self, U, out=None):
        """(4, k) doubled alpha and beta of the map U (2, nv) (into ``out`` when given)."""
        if self._free is not None:
            free = self.solver.free
            return self._free_lift().lift_map(np.concatenate([U[0, free], U[1, free]]), out)
        out = np.empty((4, self.k)) if out is None else out
        self._B(U.ravel(), out.reshape(-1))
        return out

    def _free_lift(self):
        """The small island's ``free_admm.FreeLift`` at the fixed vertices' values ``UF``."""
        if self._rhs_fixed is None or self._rhs_fixed[0] is not self.UF:
            s = self.solver
            Ufix = np.zeros((2, s.nv))
            Ufix[:, s.fixed] = self.UF.T
            self._rhs_fixed = (self.UF, FreeLift(self._free, Ufix.ravel(),
                                                 -s.fixed_share(self.UF).T.ravel()))
        return self._rhs_fixed[1]

    def distortion_of(self, u):
        """Max conformal distortion (inf when a face flips) of the map u (nv,) complex, as
        ``search`` measures the map it starts from (its fixed vertices held where u has them;
        the lift kept when they are already there)."""
        if self._measured is not None and self._measured[0] is u:
            return self._measured[1]        # this very map, measured last (the same bits)
        U = np.array([u.real, u.imag])          # np.stack's rows, without its wrapper
        UF = U[:, self.solver.fixed].T
        if self.UF is None or not np.array_equal(self.UF, UF):
            self.UF = UF
        self.solver._assemble()
        self._operators()
        D = self.max_distortion(self._lift(U))
        # kept for ``search`` from the map its caller just measured (``disk_auto``); u is the
        # caller's array, read-only here: a copy of it (another object) is measured again
        self._measured = (u, D)
        return D
