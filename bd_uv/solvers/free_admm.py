"""``bound_search``'s ADMM iterations on a small island: its free unknowns, in every face's frame.

Up to ``bound_search.ONE_PRODUCT_FACES`` faces an iteration pays per array operation more than
for arithmetic (k = 223: ~1.6 us a call of a few hundred multiply-adds), so it is written for few
calls:
- the unknowns are the free vertices' ``x = [u_free; v_free]`` in one vector (back-solved into its
  halves, no scatter into the whole map), lifted by the free columns onto the fixed vertices'
  share, the right-hand side built onto its fixed share;
- the lift is turned into every face's frame once per target: rows ``Re(w 2alpha)``,
  ``Im(w 2alpha)``, ``Re 2beta``, ``Im 2beta`` (the lift's alpha rows rotated by the frame ``w``;
  an orthogonal change of coordinates per face, so the area-weighted least-squares step is the
  same step). The cone ``|beta| <= kappa Re(w alpha)`` then reads on the first row alone: the
  projection moves only that row and scales the beta rows (no product with the frames and back an
  iteration);
- the max distortion ``|beta|^2 / |alpha|^2`` (rotation-invariant) from one square of the lift;
- the compiled sparse products straight (``bound_search._matvec``'s), buffers preallocated, the
  loop inlined (the search's watch decides each stop, as for the large islands);
- the right-hand side's product with the lift's transpose in compressed rows of its own (each
  free unknown's entries gathered, not each face's row scattered: ~25-30 % less of that product
  on 223-1,112 faces), its entries in increasing order of the lift's rows within each, so each
  unknown's sum is added in the same order as the scattering product's: the same bits.
"""
import functools
import itertools
import math

import numpy as np
import scipy.sparse as sp

from ..array_calls import quiet

__all__ = ["FreeLift", "run_free", "sparse_product", "transposed"]


def sparse_product(fmt, shape, indptr, indices):
    """``data, x, out -> out += M x`` for the csr or csc float64 matrix M of the given index
    arrays, any data of their pattern: the compiled product straight, without scipy's dispatch
    (~10 us a call against ~5 us of arithmetic on a 500-face island); scipy's product where
    scipy lacks it."""
    try:
        from scipy.sparse._sparsetools import csc_matvec, csr_matvec
    except ImportError:     # a scipy that moved it: the public product
        make = sp.csc_array if fmt == "csc" else sp.csr_array
        return lambda data, x, out: out.__iadd__(make((data, indices, indptr), shape=shape) @ x)
    product = csc_matvec if fmt == "csc" else csr_matvec
    return functools.partial(product, shape[0], shape[1], indptr, indices)


def transposed(shape, indptr, indices):
    """The compressed rows (indptr, indices) of the transpose of the (nr, nc) csr pattern
    given, each row's entries in increasing order of the given rows, and ``perm``: the
    transpose's data is ``data.take(perm)`` for the given data (scipy's compiled conversion,
    a stable bucket sort, of the entries' own places)."""
    nr, nc = shape
    nnz = len(indices)
    tptr, tind, where = np.empty(nc + 1, np.int64), np.empty(nnz, np.int64), np.empty(nnz)
    try:
        from scipy.sparse._sparsetools import csr_tocsc
        csr_tocsc(nr, nc, indptr, indices, np.arange(nnz, dtype=np.float64), tptr, tind, where)
    except ImportError:     # a scipy that moved it: the public conversion (the same order)
        T = sp.csr_array((np.arange(nnz, dtype=np.float64), indices, indptr),
                         shape=shape).tocsc()
        tptr[...], tind[...], where[...] = T.indptr, T.indices, T.data
    return tptr, tind, where.astype(np.int64)


class FreeLift:
    """The lift on the free unknowns of a small island and its transpose, ready to be turned into
    any frames.

    Parameters
    ----------
    arrays : ``face_operators.free_lift_arrays``' answer: the lift's compressed rows on the free
        unknowns (4k, 2nf) (rows ``Re 2alpha``, ``Im 2alpha``, ``Re 2beta``, ``Im 2beta``), the
        same data weighted by half each face's area (the right-hand side operator's columns), the
        entries on the fixed vertices
    Ufix : (2nv,) ``[u; v]`` with the fixed vertices' values (anything elsewhere)
    rhs_fixed : (2nf,) the fixed vertices' share of the right-hand side
    """

    def __init__(self, arrays, Ufix, rhs_fixed):
        indptr, indices, data, wdata, (frows, fcols, fdata) = arrays
        self.k = k = (len(indptr) - 1) // 4
        self.nf = nf = len(rhs_fixed) // 2
        self.indptr, self.indices, self.data, self.wdata = indptr, indices, data, wdata
        # the fixed vertices' share of the lift, row by row in the entries' order
        self.lift_fixed = np.bincount(frows, weights=fdata * Ufix.take(fcols), minlength=4 * k)
        self.rhs_fixed = rhs_fixed
        self.n1 = int(indptr[k])            # entries of the Re 2alpha rows (as many as Im's)
        self.rows = np.arange(k).repeat(indptr[1:k + 1] - indptr[:k])   # their faces
        self.lift = sparse_product("csr", (4 * k, 2 * nf), indptr, indices)
        # the right-hand side operator (2nf, 4k): the lift's transpose in rows of its own
        tptr, tind, self._tperm = transposed((4 * k, 2 * nf), indptr, indices)
        self.rhs = sparse_product("csr", (2 * nf, 4 * k), tptr, tind)
        self._framed = (data.copy(), wdata.copy(), self.lift_fixed.copy(), np.empty(len(wdata)))

    def lift_map(self, x, out=None):
        """(4, k) doubled alpha and beta of the map of free unknowns x (2nf,)."""
        out = np.empty((4, self.k)) if out is None else out
        flat = out.reshape(-1)
        np.copyto(flat, self.lift_fixed)
        self.lift(self.data, x, flat)
        return out

    def framed(self, w):
        """(lift data, right-hand side data (``rhs``'s: in the transpose's order), fixed share
        of the lift) turned into the frames w (k,) unit complex: the alpha rows ``a0 = Re
        2alpha``, ``a1 = Im 2alpha`` become ``c a0 - s a1`` and ``s a0 + c a1`` (``c + i s =
        w``), the beta rows stay. In buffers of this lift's, overwritten by the next call."""
        n1, k = self.n1, self.k
        c, s = w.real.take(self.rows), w.imag.take(self.rows)
        d, wd, lf, wdt = self._framed
        for src, dst, cc, ss in ((self.data, d, c, s), (self.wdata, wd, c, s),
                                 (self.lift_fixed, lf, w.real, w.imag)):
            m = n1 if dst is not lf else k
            a0, a1 = src[:m], src[m:2 * m]
            np.multiply(cc, a0, out=dst[:m])
            dst[:m] -= ss * a1
            np.multiply(ss, a0, out=dst[m:2 * m])
            dst[m:2 * m] += cc * a1
        wd.take(self._tperm, out=wdt)
        return d, wdt, lf


def run_free(lift, solve, x0, w, kappa, C, watch, alpha, cancel, count):
    """ADMM towards F_C with frames ``w`` from the free unknowns ``x0`` (2nf,) of a small island
    (``bound_search.BoundSearch.run``'s iterations, in the frames: see the module's docstring).

    Parameters
    ----------
    lift : FreeLift; solve : the global step's back-solve (nf,) -> (nf,) (its ``paired`` where
        it has one: both halves in place, ``ordered_ldl._paired``; else its ``vector`` where it
        has one: an answer that may be the solver's buffer, copied out before the next call)
    w : (k,) unit complex frames; kappa : float, the cones' aperture; C : float, the target
    watch : ``bound_search``'s watch of a target (``seen(D, it, C) -> (better, stop)``, ``best``)
    alpha : float, the over-relaxation
    count : callable(n), called once with the number of iterations run (the search's count)

    Returns
    -------
    (x of the least max distortion below the watch's start or None, that max)
    """
    k, nf = lift.k, lift.nf
    data, wdata, lift_fixed = lift.framed(w)
    rhs_fixed = lift.rhs_fixed
    paired = getattr(solve, "paired", None)
    paired = paired() if paired is not None else None
    solve = getattr(solve, "vector", solve)
    c = 1.0 / (1.0 + kappa * kappa)
    # with the paired solve (``ordered_ldl``: u and v in one call, in place) the right-hand side
    # is built in x itself and solved there; else into ``rhs``, each half solved and copied out
    x = x0.copy() if paired is None else paired.buffer
    if paired is not None:
        x[...] = x0
    xu, xv = x[:nf], x[nf:]
    rhs = np.empty(2 * nf) if paired is None else x
    ru, rv = rhs[:nf], rhs[nf:]
    GU = np.empty((4, k))
    flat_gu = GU.reshape(-1)
    flat_gu[...] = lift_fixed
    lift.lift(data, x, flat_gu)
    # ADMM with the multipliers lam = GU - T folded in: T is the last least-squares target, the
    # projection's point is GU + lam = 2 GU - T, and the next target z - lam = alpha P + (1 -
    # alpha) GU - lam = T + alpha (P - GU) (two array operations fewer an iteration)
    T = GU.copy()                       # lam = 0
    flat_t = T.reshape(-1)
    P = np.empty_like(GU)
    sq = np.empty_like(GU)
    nb, t, f = np.empty(k), np.empty(k), np.empty(k)
    p0, pb, sb = P[0], P[2:], sq[2:]
    s0, s1, s2, s3 = sq                 # rows as views made once (~0.15 us an index)
    # the constants as 0-d arrays: a Python float operand costs a ufunc call ~2-3 us of
    # conversion at these sizes (six such calls an iteration), a 0-d array none; the same bits
    kappa_, kc, c_, alpha_ = (np.array(v) for v in (kappa, kappa * c, c, alpha))
    zero, one = np.zeros(()), np.ones(())
    kept = None
    with quiet("invalid", "divide", "over"):
        for it in itertools.count():
            if cancel is not None and cancel.is_set():
                break
            if it:
                # max |beta|^2 / |alpha|^2 (rotation-invariant), as bound_search's
                np.multiply(GU, GU, out=sq)
                np.add(s2, s3, out=nb)
                np.add(s0, s1, out=t)
                np.divide(nb, t, out=nb)
                r = float(np.maximum.reduce(nb))     # (ndarray.max's wrapper: ~2 us)
                if not r < 1.0:
                    D = np.inf
                else:
                    r = math.sqrt(r)
                    D = (1.0 + r) / (1.0 - r)
                better, stop = watch.seen(D, it, C)
                if better:
                    kept = x.copy()
                    if watch.ask is not None and watch.accepts(kept):
                        break
                if stop:
                    break
            np.subtract(GU, T, out=P)
            P += GU
            # the cone |beta| <= kappa x on the first row (framed_cone_projection's point):
            # with t = max(x + kappa |beta|, 0), the boundary ray's point is t / (1 + kappa^2);
            # beta scales by min(1, kappa t / ((1 + kappa^2) |beta|)) (fmin: 1 where |beta| = 0),
            # x becomes max(x, t / (1 + kappa^2)) (no larger than x exactly inside the cone)
            np.multiply(pb, pb, out=sb)
            np.add(s2, s3, out=nb)
            np.sqrt(nb, out=nb)
            np.multiply(nb, kappa_, out=t)
            t += p0
            np.maximum(t, zero, out=t)
            np.multiply(t, kc, out=f)
            np.divide(f, nb, out=f)
            np.fmin(f, one, out=f)
            pb *= f
            t *= c_
            np.maximum(p0, t, out=p0)
            P -= GU                             # the target T + alpha (P - GU)
            P *= alpha_
            T += P
            rhs[...] = rhs_fixed               # (np.copyto's Python wrapper: ~1 us more)
            lift.rhs(wdata, flat_t, rhs)
            if paired is not None:
                paired()
            else:
                xu[...] = solve(ru)
                xv[...] = solve(rv)
            flat_gu[...] = lift_fixed
            lift.lift(data, x, flat_gu)
    count(it)                                   # the steps run: one before each measure
    return kept, watch.best
