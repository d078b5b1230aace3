"""LSCM (Levy et al. 2002) with any set of vertices held where a given map has them, solved again
and again as the set grows (``unwrapping.mean_relax``).

``lscm.lscm_pinned`` assembles its system for the pins it is given; here the energy's upper
triangle over every vertex's unknowns is assembled once (``lscm._lscm_system`` with no pin) and
each solve keeps the entries between free unknowns and moves those to held ones to the right-hand
side: the same system as ``lscm_pinned``'s for those pins (the same terms, summed in the same
order), without its assembly and sort each time (on a 554-face disk about half of a solve).

A set grown by a few vertices from the last one factorised (``BORDER`` unknowns at most, the same
map u) is solved with that factor, bordered: holding a free unknown j at x_j is the constraint
``e_j^T x = x_j`` on the last system ``K y = b`` (K its free block, b its right-hand side, y its
answer): ``x = y - W lam`` with ``W = K^-1 E`` (a back-solve per unknown held since, kept for the
next set) and ``(E^T W) lam = E^T y - x_E`` (a dense system of the new unknowns). The same
minimiser as the new system's, to rounding (not its bits); the held values are written as u has
them. On knight's 803-face patch the relax's rounds 3 and 4 add 6 and 1 vertices to round 2's 41:
14 back-solves of ~40 us against two factorisations of ~0.6-0.8 ms.
"""
import numpy as np
import scipy.sparse as sp

from . import ordered_ldl
from .lscm import _lscm_system, ranked_triplet_solver, spd_solver

__all__ = ["HeldLSCM"]

# Unknowns (two a vertex) held beyond the last factorised set that are solved with its factor,
# bordered (see the module's docstring; a back-solve each, kept for the next set); more and the
# set is factorised anew. A back-solve costs 1/15-1/20 of a factorisation on the 300-450 free
# vertices of the relaxed disks measured (knight's 803-face patch: ~40 against 600-850 us with
# its set-up; three_peaks' 554-face centre: ~35 against 470-530 us)
BORDER = 16


class HeldLSCM:
    """The LSCM energy of a triangulation, to be minimised with sets of vertices held.

    Parameters
    ----------
    cbw, cb : (k,3) complex128, each face's term of the energy (``lscm.FaceGeometry``)
    tris : (k,3) int64 into n vertices
    sides : ``lscm.lscm_pinned``'s, optional
    ranks : (n,) int64, optional, the vertices' elimination order (``ordered_ldl.vertex_ranks``):
        the free unknowns are eliminated in it, u and v of a vertex side by side (qdldl's AMD
        otherwise, or where that factorisation fails)
    """

    def __init__(self, cbw, cb, tris, n, sides=None, ranks=None):
        none = np.zeros(0, dtype=np.int64)
        A = _lscm_system(cbw, cb, tris, n, none, none.astype(np.complex128), sides,
                         triplets=True)[0]
        self.rows, self.cols, self.vals = A.rows, A.cols, A.vals
        self.n, self.ranks = n, ranks
        self._last = None       # the last factorised set: (u, held, pos, nf, solve, y, columns)

    def solve(self, u, held):
        """The map minimising the energy with the vertices ``held`` ((n,) bool, at least two of
        them apart) where u (n,) complex has them. Returns (n,) complex128."""
        last = self._last
        if last is not None and last[0] is u:
            more = held & ~last[1]
            if not (last[1] & ~held).any() and 2 * int(np.count_nonzero(more)) <= BORDER:
                try:
                    return self._bordered(u, more, last)
                except np.linalg.LinAlgError:   # (not met: E^T K^-1 E of a K that factorised)
                    pass
        free = ~held
        nf = int(np.count_nonzero(free))
        free2 = np.concatenate([free, free])
        pos = np.cumsum(free2) - 1          # u of the free vertices, then their v
        r, c, v = self.rows, self.cols, self.vals
        fr, fc = free2.take(r), free2.take(c)
        x = np.concatenate([u.real, u.imag])
        # the upper triangle's entries between a free and a held unknown, either way round
        to_r, to_c = fr & ~fc, ~fr & fc
        rhs = -(np.bincount(pos[r[to_r]], v[to_r] * x[c[to_r]], 2 * nf)
                + np.bincount(pos[c[to_c]], v[to_c] * x[r[to_c]], 2 * nf))
        both = fr & fc
        solve = _solver(pos[r[both]], pos[c[both]], v[both], 2 * nf,
                        None if self.ranks is None else self.ranks[free])
        xf = solve(rhs)
        self._last = (u, held.copy(), pos, nf, solve, xf, {})
        y = u.astype(np.complex128)
        y[free] = xf[:nf] + 1j * xf[nf:]
        return y

    def _bordered(self, u, more, last):
        """``solve`` of the last factorised set with the vertices ``more`` ((n,) bool, free in
        it) held too, by its factor (see the module's docstring)."""
        _, was, pos, nf, solve, xf, columns = last
        y = u.astype(np.complex128)
        if not more.any():
            y[~was] = xf[:nf] + 1j * xf[nf:]
            return y
        v = more.nonzero()[0]
        j = pos.take(v)
        J = np.concatenate([j, j + nf])             # their u, then their v, in the free order
        for i in J.tolist():
            if i not in columns:
                e = np.zeros(2 * nf)
                e[i] = 1.0
                columns[i] = solve(e).copy()        # (a solver may answer in its own buffer)
        W = np.stack([columns[i] for i in J.tolist()], axis=1)
        uv = u.take(v)
        lam = np.linalg.solve(W.take(J, axis=0), xf.take(J) - np.concatenate([uv.real, uv.imag]))
        x = xf - np.einsum("ij,j->i", W, lam)
        y[~was] = x[:nf] + 1j * x[nf:]
        y[v] = u.take(v)                            # held where u has them, to the bit
        return y


def _solver(rows, cols, vals, n, keys):
    """The solve of the system of upper-triangle triplets (unknowns ``[u; v]`` of the free
    vertices), eliminated in the order of the free vertices' ``keys`` (u and v of a vertex side
    by side, as ``lscm.ranked_triplet_solver``), or by ``lscm.spd_solver`` where that cannot run."""
    solve = (ranked_triplet_solver(rows, cols, vals, keys)
             if keys is not None and ordered_ldl.available() else None)
    return solve or spd_solver(sp.csc_matrix((vals, (rows, cols)), shape=(n, n)), upper=True)
