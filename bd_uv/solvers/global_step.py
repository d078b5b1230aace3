"""The global step of projection iterations onto the bounded-distortion set (Kovalsky, Galun and
Lipman 2015): a map ``u`` (nv,) complex is lifted to its per-face Jacobians (the linear operators
of ``energies.jacobian_operators``, Lipman 2012 eq. 4.19), and the map whose Jacobians are closest
to given ones in the area-weighted Frobenius norm, with the fixed vertices held, is one back-solve
with a Laplacian factorised once. ``projection.ProjectionSolver`` iterates it with the local step;
``bound_search.BoundSearch`` uses it for its ADMM.
"""
import time

import numpy as np
import scipy.sparse as sp

from ..geometry import components
from ..array_calls import quiet
from .face_operators import as_csc, face_gradients, gradient_rows, laplacian_block_arrays
from .factor import factor_spd
from .ordered_ldl import solver_in_order

__all__ = ["GlobalStep"]


class GlobalStep:
    """The projection iterations' global step (Kovalsky et al. 2015): the maps' lift to their
    Jacobians and the area-weighted least-squares step back, one factorisation.

    Works on one island or on a union of disjoint islands (operators built over the concatenated
    triangles); every connected component needs at least one fixed vertex.

    Parameters
    ----------
    ops : energies.JacobianOperators over (k, 2 nv)
    nv : int
    fixed_idx : (p,) int, vertices held at given values (at least one per component)
    tris : (k,3) int, the triangles ``ops`` was built over (for the connected components)
    backend : see :func:`factor.factor_spd`
    connected : bool, the triangles are known to be one connected piece (a ``mesh.Island``):
        its components are not searched for
    ranks : (nv,) int64, optional, the vertices' elimination order
        (``ordered_ldl.vertex_ranks``): the free vertices are numbered in it (``free``), so the
        matrix over them is factorised in its own order (no AMD of its own) and back-solved
        without permutation; ``backend``'s factorisation where that cannot run

    Attributes
    ----------
    n_components : int
    setup_seconds : float, operators and components
    factor_seconds : float, the factorisation (0 until an iteration needed it)
    backend : str
    """

    def __init__(self, ops, nv, fixed_idx, tris, backend="auto", connected=False, ranks=None):
        t0 = time.perf_counter()
        self.nv = nv = int(nv)
        self.area = np.asarray(ops.area, dtype=np.float64)
        self._Gx = self._Gy = None     # the gradient operators, made on first use (``Gx``)
        tris = np.asarray(tris, dtype=np.int64)
        self.ops, self.tris = ops, tris
        self.n_components, comp = ((1, np.zeros(nv, dtype=np.int64)) if connected else
                                   components(nv, np.concatenate([tris[:, 0], tris[:, 1]]),
                                              np.concatenate([tris[:, 1], tris[:, 2]])))
        self.component = comp.astype(np.int64)
        self.face_comp = self.component[tris[:, 0]]
        fixed = np.asarray(fixed_idx, dtype=np.int64).ravel()
        fixed = fixed.copy() if len(fixed) == 1 else np.unique(fixed)   # (np.unique's answer)
        if not len(fixed) or (self.n_components > 1 and np.any(np.bincount(
                self.component[fixed], minlength=self.n_components) == 0)):
            raise ValueError("every connected component needs at least one fixed vertex")
        self.fixed = fixed
        self.fixed_given = np.asarray(fixed_idx, dtype=np.int64)
        is_free = np.empty(nv, dtype=bool)
        is_free.fill(True)
        is_free[fixed] = False
        self.free = is_free.nonzero()[0]        # np.setdiff1d's answer without its sort
        self.ranks = ranks
        if ranks is not None:                   # in elimination order
            self.free = self.free[np.argsort(ranks[self.free], kind="stable")]
        self.free_comp = self.component[self.free]
        if self.n_components > 1:   # faces sorted by component, for per-component maxima
            self._order = np.argsort(self.face_comp, kind="stable")
            counts = np.bincount(self.face_comp, minlength=self.n_components)
            self._starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
            self._has_faces = counts > 0
        else:
            self._has_faces = np.array([len(tris) > 0])
        self._blocks = self._csc = self._G = self._GT = self._g = None
        self._solve, self.backend = None, backend
        self.setup_seconds = time.perf_counter() - t0
        self.factor_seconds = 0.0

    @property
    def Gx(self):
        """(k, nv) csr: d/dx of a scalar function on every face. With J = [[u_x, u_y], [v_x,
        v_y]], Re a = (u_x + v_y)/2, Im a = (v_x - u_y)/2, Re b = (u_x - v_y)/2, Im b = (v_x +
        u_y)/2, so ``Gx`` is (Are + Bre) and ``Gy`` (Bim - Aim) on the u columns."""
        if self._Gx is None:
            ops, nv, k = self.ops, self.nv, len(self.tris)
            if self._own_gradients():
                # from each face's coefficients (``face_operators.gradient_rows``: the same
                # rows as the operators' sums, ~0.7 ms of scipy sums, slices and a stack on a
                # 1k-face island), G's two halves as views of its arrays
                ptr, ind, dat = gradient_rows(ops.gx, ops.gy, self.tris)
                nx = int(ptr[k])
                self._G = sp.csr_array((dat, ind, ptr), shape=(2 * k, nv))
                self._Gx = sp.csr_array((dat[:nx], ind[:nx], ptr[:k + 1]), shape=(k, nv))
                self._Gy = sp.csr_array((dat[nx:], ind[nx:], ptr[k:] - nx), shape=(k, nv))
            else:
                self._Gx = sp.csr_array((ops.Are + ops.Bre)[:, :nv])
                self._Gy = sp.csr_array((ops.Bim - ops.Aim)[:, :nv])
        return self._Gx

    @property
    def Gy(self):
        """(k, nv) csr: d/dy of a scalar function on every face (made with ``Gx``)."""
        if self._Gy is None:
            self.Gx
        return self._Gy

    @property
    def G(self):
        """(2k, nv) csr: rows d/dx of every face, then d/dy (made on first use)."""
        if self._G is None:
            self.Gx     # (makes G too where the faces' gradient coefficients are at hand)
        if self._G is None:
            self._G = sp.csr_array(sp.vstack([self.Gx, self.Gy]))
        return self._G

    @property
    def GT(self):
        if self._GT is None:
            self._GT = sp.csr_array(self.G.T)
        return self._GT

    def face_gradients(self):
        """(gx, gy), each (k,3): every face's gradient coefficients on its corners."""
        if self._g is None:
            o = self.ops
            self._g = ((o.gx, o.gy) if self._own_gradients()
                       else face_gradients(self.Gx, self.Gy, self.tris))
        return self._g

    def _own_gradients(self):
        """Whether ``ops`` holds its faces' gradient coefficients for these triangles."""
        o = self.ops
        return getattr(o, "gx", None) is not None and o.tris is not None and (
            o.tris.shape == self.tris.shape and np.array_equal(o.tris, self.tris))

    def _assemble(self):
        """The global step's normal matrix, scalar and shared by both coordinates:
        ``L = sum_j A_j G_j^T G_j`` (minimises ``sum_j A_j |J_j - P_j|_F^2``), split into free and
        fixed columns (``face_operators.laplacian_block_arrays``: from each face's coefficients),
        kept as bare arrays (``_L_ff``, ``_L_fF``: their scipy matrices, made when asked for)."""
        if self._blocks is None:
            gx, gy = self.face_gradients()
            self._blocks = laplacian_block_arrays(gx, gy, self.area, self.tris, self.free,
                                                  self.fixed, self.nv)

    @property
    def _L_ff(self):
        """(nf, nf) csc: the free-free block (``_assemble`` first)."""
        return self._block_csc()[0]

    @property
    def _L_fF(self):
        """(nf, nfixed) csc: the free-fixed block (``_assemble`` first)."""
        return self._block_csc()[1]

    def _block_csc(self):
        if self._csc is None:
            self._csc = tuple(as_csc(b) for b in self._blocks)
        return self._csc

    def fixed_share(self, UF):
        """``L_fF @ UF`` (nf, r) for the fixed vertices' values UF (nfixed, r): the right-hand
        side's share of the fixed vertices, from the bare block (the same bits as the scipy
        product)."""
        self._assemble()
        return self._blocks[1].times(UF)

    def global_matrix(self):
        """The global step's matrix over the free vertices, (nf, nf) csc, symmetric positive
        definite."""
        self._assemble()
        return self._L_ff

    def factorize(self):
        """Factorise the global step's matrix (done on the first iteration that needs it, so a
        map that already fits costs no factorisation)."""
        if self._solve is None:
            t0 = time.perf_counter()
            self._assemble()
            # in its own order from the bare arrays (what ``solver_in_order`` reads of a csc
            # matrix), no scipy matrix made
            solve = None if self.ranks is None else solver_in_order(self._blocks[0])
            if solve is not None:
                self._solve, self.backend = solve, "qdldl-ordered"
            else:
                self._solve, self.backend = factor_spd(self._L_ff, self.backend)
            self.factor_seconds = time.perf_counter() - t0
        return self._solve

    # -- pieces -------------------------------------------------------------------------------
    def jacobians(self, U):
        """Lift: per-face (u_x, u_y, v_x, v_y) of ``U`` (nv, 2) real, as four (k,) arrays."""
        return (self.Gx @ U[:, 0], self.Gy @ U[:, 0], self.Gx @ U[:, 1], self.Gy @ U[:, 1])

    @staticmethod
    def _alpha_beta(J):
        ux, uy, vx, vy = J
        return 0.5 * ((ux + vy) + 1j * (vx - uy)), 0.5 * ((ux - vy) + 1j * (vx + uy))

    def _per_comp_max(self, v):
        if self.n_components == 1:
            return np.array([v.max() if len(v) else -np.inf])
        out = np.full(self.n_components, -np.inf)
        if len(v):
            m = np.maximum.reduceat(v[self._order], self._starts[self._has_faces])
            out[self._has_faces] = m
        return out

    def component_scale(self, u):
        """sqrt(UV area / 3D area) of each component, from unsigned face areas, (c,)."""
        U = np.empty((len(u), 2))
        U[:, 0], U[:, 1] = u.real, u.imag
        a, b = self._alpha_beta(self.jacobians(U))
        uv = self.area * np.abs(np.abs(a) ** 2 - np.abs(b) ** 2)
        A = np.bincount(self.face_comp, weights=self.area, minlength=self.n_components)
        S = np.bincount(self.face_comp, weights=uv, minlength=self.n_components)
        with quiet("invalid", "divide"):
            s = np.sqrt(S / A)
        return np.where(np.isfinite(s) & (s > 0), s, 1.0)
