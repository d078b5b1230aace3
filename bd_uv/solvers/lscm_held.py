"""LSCM (Levy et al. 2002) with any set of vertices held where a given map has them, solved again
and again as the set grows (``unwrapping.mean_relax``).

``lscm.lscm_pinned`` assembles its system for the pins it is given; here the energy's upper
triangle over every vertex's unknowns is assembled once (``lscm._lscm_system`` with no pin) and
each solve keeps the entries between free unknowns and moves those to held ones to the right-hand
side: the same system as ``lscm_pinned``'s for those pins (the same terms, summed in the same
order), without its assembly and sort each time (on a 554-face disk about half of a solve).
"""
import numpy as np
import scipy.sparse as sp

from . import ordered_ldl
from .lscm import _lscm_system, ranked_triplet_solver, spd_solver

__all__ = ["HeldLSCM"]


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

    def solve(self, u, held):
        """The map minimising the energy with the vertices ``held`` ((n,) bool, at least two of
        them apart) where u (n,) complex has them. Returns (n,) complex128."""
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
        y = u.astype(np.complex128)
        y[free] = xf[:nf] + 1j * xf[nf:]
        return y


def _solver(rows, cols, vals, n, keys):
    """The solve of the system of upper-triangle triplets (unknowns ``[u; v]`` of the free
    vertices), eliminated in the order of the free vertices' ``keys`` (u and v of a vertex side
    by side, as ``lscm.ranked_triplet_solver``), or by ``lscm.spd_solver`` where that cannot run."""
    solve = (ranked_triplet_solver(rows, cols, vals, keys)
             if keys is not None and ordered_ldl.available() else None)
    return solve or spd_solver(sp.csc_matrix((vals, (rows, cols)), shape=(n, n)), upper=True)
