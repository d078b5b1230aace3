"""Free-boundary conformal maps (LSCM, Levy et al. 2002) of many islands or charts in one sparse
solve, assembled from per-face terms (no sparse operator products), factored by LDL^T.

Used by the batched unwrap (``unwrapping.batched``: every island whose conformal map fits the
bound) and by the seam search (``seams.charts``: every candidate chart, every round), which share
one way of pinning (two far boundary vertices at 0 and 1) so a map solved by one is the other's.
"""
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..geometry import face_areas, gradient_operators, local_coordinates
from ..array_calls import einsum
from . import ordered_ldl, radix
from .face_operators import csc_arrays
from ..trim import CHUNK

try:  # LDL^T with AMD ordering; SuperLU without it
    import qdldl
except ImportError:  # pragma: no cover - exercised where qdldl is absent
    qdldl = None

__all__ = ["FaceGeometry", "face_geometry", "face_geometry_of", "lscm_pinned", "spd_solver"]


@dataclass(frozen=True)
class FaceGeometry:
    """What an LSCM solve needs of each face (``seams.charts.chart_maps`` computes it once per
    mesh: the seam search maps the same faces again in every round).

    Only ``cb`` is kept per corner: alpha's coefficients are its conjugates (both come from the
    same real gradients, ``(G_x -/+ i G_y) / 2``) and the energy's weights are ``zarea cb^*``, so
    both are formed for the faces at hand (``ca``, ``cbw``), not held for the whole mesh (on a
    500k-face mesh: 48 MB fewer through the seam search).

    Attributes
    ----------
    area : (m,) float64, 3D area
    cb : (m,3) complex128, beta's coefficient of each corner (eq. 4.19) in the face's local
        frame at its 3D size
    zarea : (m,) float64, the face's area in its local frame (the LSCM energy's weight)
    """
    area: np.ndarray
    cb: np.ndarray
    zarea: np.ndarray

    def ca(self, faces=slice(None)):
        """alpha's coefficients (f,3) complex128 of ``faces`` (all by default)."""
        return self.cb[faces].conj()

    def cbw(self, faces=slice(None)):
        """``area cb^*`` (f,3) complex128 of ``faces``: the face's term of the LSCM energy
        ``u^H H u`` is ``h = cbw cb^T`` (the same at any scale of the chart: the coefficients
        grow as the area shrinks), kept as its two factors (a third of the memory of the 3x3
        terms)."""
        if isinstance(faces, slice):
            return self.zarea[faces][:, None] * self.cb[faces].conj()
        # (``take``: numpy's row gather by a fancy index is ~4x dearer, the same values)
        return self.zarea.take(faces)[:, None] * self.cb.take(faces, axis=0).conj()


def face_geometry(V, F):
    """``FaceGeometry`` of every face of (V, F), ``CHUNK`` faces at a time (per-face numbers:
    the same bits; the local frames and gradients of a 500k-face mesh at once were ~120 MB)."""
    m = len(F)
    area, zarea = np.empty(m), np.empty(m)
    cb = np.empty((m, 3), dtype=np.complex128)
    for i in range(0, m, CHUNK):
        f = F[i:i + CHUNK]
        Z = local_coordinates(V, f)
        G = gradient_operators(Z)
        zarea[i:i + CHUNK] = 0.5 * np.abs(((Z[:, 1] - Z[:, 0]).conj() * (Z[:, 2] - Z[:, 0])).imag)
        with np.errstate(invalid="ignore"):    # NaN gradients of zero-area faces
            cb[i:i + CHUNK] = 0.5 * (G[:, 0] + 1j * G[:, 1])
        area[i:i + CHUNK] = face_areas(V, f)
    return FaceGeometry(area, cb, zarea)


def face_geometry_of(Z, G, area):
    """``FaceGeometry`` of faces with local corner coordinates Z (m,3) complex
    (``geometry.local_coordinates``), their gradient operators G (m,2,3)
    (``geometry.gradient_operators``) and areas (m,): ``face_geometry``'s arithmetic on what
    the caller already holds (``unwrapping.one_disk``)."""
    zarea = 0.5 * np.abs(((Z[:, 1] - Z[:, 0]).conj() * (Z[:, 2] - Z[:, 0])).imag)
    return FaceGeometry(area, 0.5 * (G[:, 0] + 1j * G[:, 1]), zarea)


def spd_solver(A, upper=False):
    """Factor a sparse symmetric positive definite matrix once; return its solve.

    LDL^T with an AMD ordering (qdldl), about twice as fast as SuperLU on the LSCM and dual
    Laplacian systems here; SuperLU with a symmetric ordering where qdldl is missing or the
    factorisation breaks down.

    Parameters
    ----------
    A : (N,N) sparse, symmetric positive definite; with ``upper`` only its upper triangle
        (diagonal included), in canonical CSC form (no duplicate entries)
    upper : bool

    Returns
    -------
    callable((N,) float64) -> (N,) float64

    Raises
    ------
    RuntimeError when the matrix is singular
    """
    if qdldl is not None:
        try:
            return qdldl.Solver(A if upper else sp.triu(A, format="csc"), upper=True).solve
        except ValueError:  # zero pivot: let SuperLU (with pivoting) try
            pass
    if upper:
        A = A + sp.triu(A, k=1, format="csc").T
    lu = spla.splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True})
    return lu.solve


def lscm_pinned(cbw, cb, tris, n, idx, val, sides=None, ranks=None, kept=None):
    """LSCM (minimise ``sum_f area_f |beta_f|^2``) with vertices ``idx`` fixed to ``val``.

    The energy is ``u^H H u`` with ``H = sum_f h_f`` (n x n Hermitian, ``h_f = area_f cb_f^*
    cb_f^T = cbw_f cb_f^T``); on x = [Re u; Im u] it is ``x^T Q x`` with ``Q = [[Re H, -Im H], [Im H, Re H]]``.
    H's entries are summed first (the diagonal per vertex, the rest per edge), then only Q's upper
    triangle on the free unknowns is written: the two ``Re H`` blocks' diagonal and upper entries
    and the block ``-Im H`` (H's diagonal is real; off the boundary Im H vanishes). The pinned values enter the right-hand
    side as ``-[Re; Im](H u_pinned)``.

    Parameters
    ----------
    cbw, cb : (f,3) complex128, each face's term of H as ``cbw cb^T`` (``FaceGeometry``);
    tris : (f,3) int64 into n vertices
    idx : (p,) int64, pinned vertices; val : (p,) complex128, their positions
    sides : (s1, s2, sb) int64 arrays, optional, the edges when known (``unwrapping.one_disk``):
        face sides (flat ``3 f + k``, the side from corner k to k + 1) of each interior edge,
        s1 < s2, and of each boundary edge; found by sorting the sides otherwise
    ranks : (n,) int64, optional, the vertices' elimination order (``ordered_ldl.vertex_ranks``):
        the free vertices' unknowns are eliminated in it, u and v of a vertex side by side
        (qdldl's AMD of the 2n unknowns otherwise, or where that factorisation fails)
    kept : dict, optional, with ``ranks``: ``ranked_triplet_solver``'s (the factor kept there
        for a later system of the same places, refilled: ``one_disk.Disk.factors``)

    Returns
    -------
    u : (n,) complex128
    """
    # The triplets as they are: the ordered factorisation sorts them into its own order (the
    # same compressed matrix as from ``Upper.csc``, the same bits), and the matrix is made only
    # for qdldl's own order (no ranks, or that factorisation failing).
    A, rhs, u0, free = _lscm_system(cbw, cb, tris, n, idx, val, sides, triplets=True)
    solve = None if ranks is None else ranked_triplet_solver(A.rows, A.cols, A.vals, ranks[free],
                                                             kept)
    x = (spd_solver(A.csc(), upper=True) if solve is None else solve)(rhs)
    u = u0
    nf = len(free)
    u[free] = x[:nf] + 1j * x[nf:]
    return u


def ranked_triplet_solver(rows, cols, vals, keys, kept=None):
    """The solve of the system given as upper-triangle triplets (unknowns ``[u; v]`` of the free
    vertices) eliminated in the order of the free vertices' ``keys``, u and v of a vertex side
    by side; None where the factorisation fails (``lscm_pinned``, ``lscm_held``).

    kept : dict, optional (``one_disk.Disk.factors``): a factor of an earlier system of the
        same triplets' places (the same ``rows`` and ``cols``) and keys is refilled with these
        values (``ordered_ldl.Factor.refill``: the same factor bit for bit, without the
        conversions and the elimination tree), and this one kept there for the next."""
    last = None if kept is None else kept.get("ranked")
    if last is not None and _same_arrays(last[1:], (rows, cols, keys)):
        f = last[0].refill(vals)
    else:
        nf = len(keys)
        p = np.argsort(keys, kind="stable")
        perm = np.empty(2 * nf, np.int64)        # u and v of a vertex side by side
        perm[0::2], perm[1::2] = p, p + nf
        f = ordered_ldl.Factor(rows, cols, vals, 2 * nf, perm, keep=kept is not None)
        if kept is not None:
            kept["ranked"] = (f, rows, cols, keys)
    return f.solve if f.lnz >= 0 and f.factor() else None


def _same_arrays(a, b):
    return all(x is y or (len(x) == len(y) and np.array_equal(x, y)) for x, y in zip(a, b))


def _lscm_system(cbw, cb, tris, n, idx, val, sides=None, triplets=False):
    """``lscm_pinned``'s system: Q's upper triangle on the free unknowns (csc; with
    ``triplets`` an ``Upper``, unsorted: a factorisation in an order of its own sorts them
    anyway), the right-hand side, the map with the pinned values set (zeros elsewhere), the free
    vertices. Its own function so that the assembly's temporaries (a few times the matrix) are
    freed before the factorisation, which is the memory peak of a large chart."""
    idx = np.asarray(idx, dtype=np.int64)
    pinned = np.zeros(n, dtype=bool)
    pinned[idx] = True
    u0 = np.zeros(n, dtype=np.complex128)
    u0[idx] = val
    flat = tris.ravel()
    diag = np.bincount(flat, (cbw * cb).real.ravel(), n)
    if np.isfinite(diag).all():
        # Every face's terms finite (diag sums area |cb|^2 >= 0 over the corners: a NaN or
        # inf in cb or cbw shows there): u0 is 0 but at the pinned vertices, so a face without
        # one adds exact zeros, which leave bincount's sums as they are (the same bits); only
        # the faces at a pinned vertex are formed.
        pt = pinned.take(tris)      # (columns or-ed: numpy's reduction along a length-3 axis
        near = (pt[:, 0] | pt[:, 1] | pt[:, 2]).ravel().nonzero()[0]      # is ~10x dearer)
        t = tris.take(near, axis=0)
        hu = (cbw.take(near, axis=0) * einsum("fb,fb->f", cb.take(near, axis=0),
                                              u0.take(t))[:, None]).ravel()
        at = t.ravel()
    else:
        hu = (cbw * einsum("fb,fb->f", cb, u0[tris])[:, None]).ravel()      # (h u0) per corner
        at = flat
    rhs_c = -(np.bincount(at, hu.real, n) + 1j * np.bincount(at, hu.imag, n))
    pos = (~pinned).cumsum() - 1            # (np.cumsum's and .sum's wrappers: ~1.5 us each)
    nf = n - int(np.count_nonzero(pinned))
    # One entry per face side (j, k), summed per edge {lo, hi}: Re H and Im H[lo, hi].
    J, K = tris, tris.take([1, 2, 0], axis=1)
    # (not ``take``: the fancy index's columns are laid out strided, and numpy multiplies
    # complex arrays laid out otherwise to other last bits: the maps would move by rounding)
    hjk = (cbw * cb[:, [1, 2, 0]]).ravel()
    lo, hi = np.minimum(J, K).ravel(), np.maximum(J, K).ravel()
    im = np.where((J < K).ravel(), hjk.imag, -hjk.imag)
    if sides is None:
        edge, inv, count = radix.unique(lo * n + hi, n * n)
        re_e, im_e = np.bincount(inv, hjk.real, len(edge)), np.bincount(inv, im, len(edge))
        lo, hi, rim = edge // n, edge % n, count == 1
    else:   # the edges known: each interior edge's two sides (in increasing order), then the
        # boundary's; the same sums as bincount's (0 + first + second)
        s1, s2, sb = sides
        re = hjk.real
        lo, hi = np.concatenate([lo[s1], lo[sb]]), np.concatenate([hi[s1], hi[sb]])
        re_e = np.concatenate([re[s1] + re[s2], re[sb]])
        im_e = np.concatenate([np.zeros(len(s1)), im[sb]])
        rim = np.zeros(len(lo), dtype=bool)
        rim[len(s1):] = True
    on = ~pinned[lo] & ~pinned[hi]
    # (``compress``: numpy 1.26's boolean index is ~3x dearer, the same elements)
    pl, ph, re_e = pos[lo.compress(on)], pos[hi.compress(on)], re_e.compress(on)
    # Im H is the signed area term: the two faces of an interior edge cancel (to rounding), so
    # only boundary edges couple the real and imaginary parts. Leaving the interior zeros out
    # keeps the two Laplacian blocks apart but for the boundary: half the fill to factor.
    rim &= on
    bl, bh, im_b = pos[lo.compress(rim)], pos[hi.compress(rim)], im_e.compress(rim)
    free = (~pinned).nonzero()[0]
    pd = pos[free]
    # No two entries share a place (one per free vertex, per edge, per boundary edge and side).
    A = Upper(np.concatenate([pd, pl, pd + nf, pl + nf, bl, bh]),
              np.concatenate([pd, ph, pd + nf, ph + nf, bh + nf, bl + nf]),
              np.concatenate([diag[free], re_e, diag[free], re_e, -im_b, im_b]), 2 * nf)
    rhs = np.concatenate([rhs_c.real[free], rhs_c.imag[free]])
    return (A if triplets else A.csc()), rhs, u0, free


@dataclass(frozen=True)
class Upper:
    """The upper triangle (diagonal included) of an n x n symmetric matrix as triplets, no two
    at one place, in no particular order (``_lscm_system``'s, for a factorisation that sorts
    them in its own order: ``seams.orders.ordered_solver``)."""
    rows: np.ndarray
    cols: np.ndarray
    vals: np.ndarray
    n: int

    def csc(self):
        """The canonical csc matrix: the entries sorted by (column, row), no triplet conversion
        (scipy's is ~0.4 ms of fixed cost on a 200-face island)."""
        n, rows, cols = self.n, self.rows, self.cols
        order = radix.order(cols * n + rows, n * n)
        indptr = np.zeros(n + 1, dtype=np.int64)
        np.cumsum(np.bincount(cols, minlength=n), out=indptr[1:])
        return sp.csc_matrix((self.vals[order], rows[order], indptr), shape=(n, n))

    def csc_arrays(self):
        """``csc``'s arrays (``face_operators.CscArrays``: what qdldl reads of a matrix) without
        the scipy matrix (its constructor: ~50-60 us on a 115-face disk's system); scipy's
        compiled conversion (``face_operators.csc_arrays``), cheaper here than ``csc``'s radix
        order (10 against 11 us at 150 unknowns, 12 against 23 at 276)."""
        return csc_arrays(self.vals, self.rows, self.cols, self.n, self.n)
