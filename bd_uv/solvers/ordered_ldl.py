"""LDL^T of a sparse symmetric positive definite matrix in an elimination order the caller
gives, through the QDLDL and AMD functions qdldl's extension module exports (``ctypes``).

``qdldl.Solver`` runs SuiteSparse AMD on every matrix, and on the seam search's systems that is
most of the factorisation (a 1,000-row system: ~0.9 ms of AMD for ~0.1 ms of numeric factor),
while most of its systems are pieces or unions of charts already ordered (``seams.orders``).
Here the order is given, its fill is known from the elimination tree before the numeric factor
(so a caller can refuse an order that fills too much and ask for AMD), and AMD runs only when
asked for, on the graph the caller chooses (the chart's vertices rather than their 2n unknowns).

Where the module does not export the functions (a build that hides them), its index type is not
64-bit, or qdldl is another release than the ones checked (``TESTED``), ``available()`` is False
and callers use ``lscm.spd_solver``.
"""
import ctypes
import functools
import os

import numpy as np
from scipy.sparse import _sparsetools as _st

try:
    import qdldl
except ImportError:  # pragma: no cover - exercised where qdldl is absent
    qdldl = None

# Arrays go to C as their data addresses (``ndarray.ctypes.data``: ``data_as`` cost ~10 us a
# call, a few hundred microseconds a factor on the small systems); the arrays are held alive by
# the caller (``Factor``) while C reads them.
_A = ctypes.c_void_p
# The qdldl releases whose exported C functions these signatures were checked against (the one
# requirements.txt pins and the zips bundle): a wrong argument list is not an error ctypes can
# catch but a crash (inside Blender, the user's session), so any other release takes qdldl's own
# order (``qdldl.Solver``).
TESTED = ("0.1.9.post1",)


def _version():
    """qdldl's installed release: first a tested release's ``dist-info`` folder beside the
    module (a wheel installs it there; no scan), else ``importlib.metadata`` (whose import alone
    cost the first search of a process ~12 ms: the C = 5 unfold of three_peaks' 554-face centre
    took 17-22 ms in a fresh process against 5.5 after)."""
    if qdldl is not None:
        here = os.path.dirname(os.path.abspath(qdldl.__file__))
        for v in TESTED:
            if os.path.isfile(os.path.join(here, f"qdldl-{v}.dist-info", "METADATA")):
                return v
    try:
        from importlib.metadata import PackageNotFoundError, version
        return version("qdldl")
    except (ImportError, PackageNotFoundError, ValueError):   # vendored, no metadata
        return None


@functools.lru_cache(maxsize=1)
def _lib():
    """The extension module's functions with their signatures, or None where they are not
    exported or their integers are not int64 (checked on a 3 x 3 matrix of known fill)."""
    if qdldl is None or _version() not in TESTED:
        return None
    try:
        lib = ctypes.CDLL(qdldl.__file__)
        lib.amd_l_order.argtypes = [ctypes.c_int64, _A, _A, _A, _A, _A]
        lib.amd_l_order.restype = ctypes.c_int64
        lib.QDLDL_etree.argtypes = [ctypes.c_int64] + [_A] * 5
        lib.QDLDL_etree.restype = ctypes.c_int64
        lib.QDLDL_factor.argtypes = [ctypes.c_int64] + [_A] * 13
        lib.QDLDL_factor.restype = ctypes.c_int64
        lib.QDLDL_solve.argtypes = [ctypes.c_int64] + [_A] * 5
        lib.QDLDL_solve.restype = None
    except (OSError, AttributeError):
        return None
    # A dense 3 x 3 upper triangle: L has 3 entries below the diagonal; read as int32, these
    # arrays give a column without entries (-1) or another count.
    Ap = np.array([0, 1, 3, 6], np.int64)
    Ai = np.array([0, 0, 1, 0, 1, 2], np.int64)
    work, lnz, et = (np.empty(3, np.int64) for _ in range(3))
    if lib.QDLDL_etree(3, _p(Ap), _p(Ai), _p(work), _p(lnz), _p(et)) != 3:
        return None
    return lib


def _p(a):
    return a.ctypes.data


# Loaded with the module, not at the first factorisation in its own order: ~0.15-0.3 ms (the
# handle, the 3 x 3 check) that a process's first unwrap in that order paid (nefertiti at C = 5,
# the first call after a warm-up on a 36-vertex grid: 2.3 -> 1.95 ms, main 1.8-2.0).
_lib()


def available():
    """Whether the ordered factorisation can run here."""
    return _lib() is not None


def amd(indptr, indices, n):
    """SuiteSparse AMD order (n,) int64 of the symmetric pattern given by one or both
    triangles in compressed columns (int64 arrays); None when AMD refuses it."""
    lib = _lib()
    P = np.empty(n, np.int64)
    Ap = np.ascontiguousarray(indptr, np.int64)
    Ai = np.ascontiguousarray(indices, np.int64)
    if lib.amd_l_order(n, _p(Ap), _p(Ai), _p(P), None, None) < 0:
        return None
    return P


# Up to this many vertices a piece's systems are factorised in its vertices' AMD order
# (``vertex_ranks``); above, the conformal map's factor in that order (u and v side by side)
# holds 10-17 % more entries than in qdldl's AMD of its 2n unknowns, and its numeric
# factorisation costs more than the AMD saved (CPU, C = 5: face.obj, 26k vertices, 315 -> 390
# ms; lion-head, 8.4k, 79 -> 89; hemisphere, 2k, 20 -> 23.5; nefertiti, 299, 3.2 -> 3.0-3.2).
RANKED_VERTICES = 1000
# A conformal map alone (at a fixed C, no search after it) is factorised in that order from this
# many vertices (``batched.conformal_islands``, ``one_disk.unwrap_disk``: the same rule, the same
# bits); below, in qdldl's own. One process, find + conformal map, least of 400 x 2 (qdldl's ->
# the ranks): face:100 (77 vertices) 452 -> 472 us, face:200 (138) 652 -> 636, lion-head:300
# (189) 779 -> 744, mushroom:500 (305) 1126 -> 1044, face:800 (456) 1447 -> 1328; between
# Blender's unwraps (bench_cpu_small, C = 5 / ABF) face:200 0.76-0.77 -> 0.79-0.80,
# three_peaks:250 (158) 0.65-0.67 -> 0.68-0.69, lion-head:300 0.58-0.59 -> 0.59,
# mushroom:500 0.38-0.39 -> 0.37-0.38
FIXED_RANKED = 200
# ``bound="auto"`` on one disk factorises several systems of its vertices (the conformal map, the
# angle start's, the bound search's Laplacian, the mean relax's): one order of the vertices
# serves them all, and the search's back-solves pair u and v (``_paired``), so it pays up to this
# many vertices (``one_disk.find``'s ``most``; instructions per warm call, RANKED_VERTICES ->
# this: homer's 1,982-face strip 282.1 -> 258.2 M; the same C, mean and iterations)
AUTO_RANKED_VERTICES = 4000


def edge_ranks(a, b, n, most=None):
    """``vertex_ranks`` of the graph of n vertices whose edges are (a[i], b[i]) (int64 arrays),
    each edge once (a mesh piece whose edges are known: ``unwrapping.one_disk``): no sort and
    no duplicate to sum (the same order as ``vertex_ranks`` of its triangles). ``most``: the
    most vertices ordered (RANKED_VERTICES by default)."""
    if not 0 < n <= (RANKED_VERTICES if most is None else most) or not available():
        return None
    return _graph_ranks(a, b, n, twice=False)


def vertex_ranks(tris, n):
    """Each of n vertices' place (n,) int64 in the AMD order of the graph of the triangles'
    edges, or None where the ordered factorisation cannot run, AMD refuses the graph or n is
    above RANKED_VERTICES (the callers then let qdldl order each system). One
    order of a mesh piece's vertices serves every system on its vertices: the conformal map's
    (u and v of a vertex side by side, ``lscm.lscm_pinned``) and the bound search's Laplacian
    (``global_step.GlobalStep``), each restricted to its free vertices (the fill of an order
    restricted to a subgraph is within the whole's). AMD of the n vertices costs about half of
    qdldl's own on the conformal map's 2n unknowns (nefertiti, 299 vertices: ~0.29 against
    ~0.62 ms), and once for both systems instead of once each."""
    if not 0 < n <= RANKED_VERTICES or not available():
        return None
    tris = np.asarray(tris, np.int64)
    return _graph_ranks(tris.ravel(), tris[:, [1, 2, 0]].ravel(), n, twice=True)


def _graph_ranks(a, b, n, twice):
    """Each of n vertices' place (n,) int64 in the AMD order of the graph whose edges are
    (a[i], b[i]), or None where AMD refuses it; ``twice``: an edge may come twice (an interior
    edge's two sides, summed into one entry), else each comes once (no sort, no sum)."""
    r, c = np.concatenate([a, b]), np.concatenate([b, a])
    nnz = len(r)
    Ap, Ai, Ax = np.empty(n + 1, np.int64), np.empty(nnz, np.int64), np.empty(nnz)
    _st.coo_tocsr(n, n, nnz, r, c, np.ones(nnz), Ap, Ai, Ax)   # symmetric: its csr is its csc
    # sorted within each column: AMD takes a jumbled pattern too, but sorts a copy of it first
    # (``amd_preprocess``: the same order, ~10 % of AMD's time on a 439-vertex disk, more than
    # this sort)
    _st.csr_sort_indices(n, Ap, Ai, Ax)
    if twice:
        _st.csr_sum_duplicates(n, n, Ap, Ai, Ax)
    p = amd(Ap, Ai[:Ap[-1]], n)
    if p is None:
        return None
    rank = np.empty(n, np.int64)
    rank[p] = np.arange(n)
    return rank


def solver_in_order(M):
    """LDL^T of a canonical csc symmetric positive definite matrix M (both triangles or the
    upper one) eliminated in its own order, no reordering: ``solve(b)`` for b (n,) or (n, r) ->
    a new array; its ``vector(b)`` for b (n,) alone -> a buffer of the solver's, overwritten by
    the next call (the search's iterations copy it out at once). No permutation either way, and
    ``vector`` calls the C solve with its arguments converted once (a call with them as Python
    integers costs ~2 us more: 4.9 against 7.8 us a solve on 144 unknowns, qdldl's own 4.6).
    None where it cannot run or a pivot is zero."""
    if not available():
        return None
    n = M.shape[0]
    cols = np.arange(n, dtype=np.int64).repeat(M.indptr[1:] - M.indptr[:-1])
    rows = M.indices.astype(np.int64)
    up = rows <= cols
    f = Factor(rows[up], cols[up], M.data[up], n, np.arange(n, dtype=np.int64))
    if f.lnz < 0 or not f.factor():
        return None
    buf = np.empty(n)
    args = (ctypes.c_int64(n),) + tuple(ctypes.c_void_p(a) for a in f._args[1:]) + (
        ctypes.c_void_p(buf.ctypes.data),)
    qdldl_solve = _bare_solve()

    def vector(b):
        buf[...] = b
        qdldl_solve(*args)
        return buf

    def solve(B):
        B = np.asarray(B, dtype=np.float64)
        if B.ndim == 1:
            return vector(B).copy()
        return np.stack([vector(B[:, i]).copy() for i in range(B.shape[1])], axis=1)
    solve.vector, solve.factor = vector, f      # the factor held while its solves live
    made = []

    def paired():
        if not made:
            made.append(_paired(f))
        return made[0]
    solve.paired = paired
    return solve


def _paired(f):
    """Both halves of a (2n,) vector back-solved by one call, in place: the factor of the
    block-diagonal ``diag(M, M)``, its two blocks the factor ``f``'s entries side by side (the same
    arithmetic entry by entry as two solves, one C call and no copies instead of two calls and four
    copies: the bound search's iterations solve u and v with one matrix). Returns ``solve()``,
    which solves its ``buffer`` (2n,) in place."""
    n, lnz = f.n, int(f.Lp[-1])
    # Lp and Li in one int64 buffer, Lx, Dinv and the vector in one float64 buffer: two
    # addresses taken, not five (the same values as the concatenations they were).
    ints, reals = np.empty(2 * n + 1 + 2 * lnz, np.int64), np.empty(2 * lnz + 4 * n)
    Lp, Li = ints[:2 * n + 1], ints[2 * n + 1:]
    Lp[:n + 1] = f.Lp
    np.add(f.Lp[1:], lnz, out=Lp[n + 1:])
    Li[:lnz] = f.Li[:lnz]
    np.add(f.Li[:lnz], n, out=Li[lnz:])
    Lx, Dinv, buf = reals[:2 * lnz], reals[2 * lnz:2 * lnz + 2 * n], reals[2 * lnz + 2 * n:]
    Lx[:lnz] = Lx[lnz:] = f.Lx[:lnz]
    Dinv[:n] = Dinv[n:] = f.Dinv
    i0, f0 = _p(ints), _p(reals)
    args = (ctypes.c_int64(2 * n),) + tuple(ctypes.c_void_p(a) for a in (
        i0, i0 + 8 * (2 * n + 1), f0, f0 + 8 * 2 * lnz, f0 + 8 * (2 * lnz + 2 * n)))
    qdldl_solve = _bare_solve()

    def solve():
        qdldl_solve(*args)
    solve.buffer, solve.arrays = buf, (Lp, Li, Lx, Dinv)    # held while C reads them
    return solve


@functools.lru_cache(maxsize=1)
def _bare_solve():
    """``QDLDL_solve`` without argument conversion (its arguments passed as ctypes values of
    the types ``_lib`` checked): a second handle on the same loaded module."""
    fn = ctypes.CDLL(qdldl.__file__).QDLDL_solve
    fn.restype = None
    return fn


class Factor:
    """LDL^T of ``P A P^T`` for a symmetric A given by its upper triangle (rows, cols, vals:
    triplets with no duplicates, or with ``repeats`` triplets that may share a place, summed
    here) and an order ``perm`` (the unknown eliminated k-th is ``perm[k]``). ``lnz``: the
    factor's entries, known before the numeric factorisation (``factor`` may then be skipped).
    Call ``factor()`` (False on a zero pivot), then ``solve(b)``. The matrix in elimination
    order is written here (rows sorted in each column, the diagonal last, as ``QDLDL_etree``
    requires)."""

    def __init__(self, rows, cols, vals, n, perm, repeats=False, keep=False):
        self.n, self.perm = n, perm
        self._kept = None
        pinv = np.empty(n, np.int64)
        pinv[perm] = np.arange(n)
        r, c = pinv[rows], pinv[cols]
        r, c = np.minimum(r, c), np.maximum(r, c)
        # Rows by row (counting sort), then the transpose to columns (counting sort again),
        # which leaves each column's rows in increasing order: O(entries), no comparison sort.
        nnz = len(r)
        Rp, Rj, Rx = np.empty(n + 1, np.int64), np.empty(nnz, np.int64), np.empty(nnz)
        _st.coo_tocsr(n, n, nnz, r, c, np.ascontiguousarray(vals, np.float64), Rp, Rj, Rx)
        # Ap, work, Lnz and etree are views of one buffer and C gets their addresses from its
        # one (``_p`` ~0.8-1.3 us a call, ~60 calls a small search's factorisations before).
        ints = np.empty(4 * n + 1, np.int64)
        self.Ap, self.work, self.Lnz, self.etree = (ints[:n + 1], ints[n + 1:2 * n + 1],
                                                    ints[2 * n + 1:3 * n + 1], ints[3 * n + 1:])
        self.Ai, self.Ax = np.empty(nnz, np.int64), np.empty(nnz)
        _st.csr_tocsc(n, n, Rp, Rj, Rx, self.Ap, self.Ai, self.Ax)
        if repeats:     # each column's rows sorted: a place's triplets side by side, summed
            _st.csr_sum_duplicates(n, n, self.Ap, self.Ai, self.Ax)
            self.Ai, self.Ax = self.Ai[:self.Ap[n]], self.Ax[:self.Ap[n]]
        if keep and not repeats:    # for ``refill``: the places (where they go, when asked)
            self._kept = [self.Ai, r, c, None]
        at = _p(ints)
        self._at = (at, at + 8 * (n + 1), at + 8 * (2 * n + 1), at + 8 * (3 * n + 1))
        self._ai, self._ax = _p(self.Ai), _p(self.Ax)
        Ap, work, Lnz, etree = self._at
        self.lnz = int(_lib().QDLDL_etree(n, Ap, self._ai, work, Lnz, etree))

    def refill(self, vals):
        """A Factor (not yet factorised) of the triplets given to this one (made with
        ``keep``) with the values ``vals`` instead, in the same order: the same matrix in the
        same elimination order as a new Factor of them, so the same factor bit for bit, without
        the conversions and the elimination tree (the pattern's, shared: the numeric factor
        only reads them). None where this one was not made with ``keep``."""
        if self._kept is None:
            return None
        Ai, r, c, where = kept = self._kept
        if where is None:
            # where each triplet's value goes: the two conversions of their positions (exact
            # as float64), made at the first refill (a disk solved once pays nothing)
            n, nnz = self.n, len(r)
            Rp, Rj, Rx = np.empty(n + 1, np.int64), np.empty(nnz, np.int64), np.empty(nnz)
            _st.coo_tocsr(n, n, nnz, r, c, np.arange(nnz, dtype=np.float64), Rp, Rj, Rx)
            Cp, Ci, Cx = np.empty(n + 1, np.int64), np.empty(nnz, np.int64), np.empty(nnz)
            _st.csr_tocsc(n, n, Rp, Rj, Rx, Cp, Ci, Cx)
            where = kept[3] = Cx.astype(np.int64)
        f = object.__new__(Factor)
        f.n, f.perm, f.lnz, f._kept = self.n, self.perm, self.lnz, self._kept
        f.Ap, f.work, f.Lnz, f.etree, f._at = self.Ap, None, self.Lnz, self.etree, self._at
        f.Ai, f.Ax = Ai, np.ascontiguousarray(vals, np.float64).take(where)
        f._ai, f._ax = _p(f.Ai), _p(f.Ax)
        return f

    def repeated(self):
        """Whether two of the triplets given share a place (before ``factor``, which needs them
        summed first): equal rows side by side within a column."""
        Ai, Ap = self.Ai, self.Ap
        same = Ai[1:] == Ai[:-1]
        starts = Ap[1:-1]
        same[starts[(starts > 0) & (starts < len(Ai))] - 1] = False
        return bool(same.any())

    def factor(self):
        n, lib = self.n, _lib()
        if self.lnz < 0:
            return False
        # Lp, Li and iwork in one int64 buffer, Lx, D, Dinv and fwork in one float64 buffer:
        # three addresses taken instead of nine (the same arrays to C, the same arithmetic).
        lnz = max(self.lnz, 1)
        ints, reals = np.empty(4 * n + 1 + lnz, np.int64), np.empty(3 * n + lnz)
        self.Lp, self.Li = ints[:n + 1], ints[n + 1:n + 1 + lnz]
        self.Lx, self.Dinv = reals[:lnz], reals[lnz + n:lnz + 2 * n]   # D: reals[lnz:lnz + n]
        bwork = np.empty(n, np.ubyte)
        i0, f0 = _p(ints), _p(reals)
        Lp, Li, iwork = i0, i0 + 8 * (n + 1), i0 + 8 * (n + 1 + lnz)
        Lx, Dp, Dinv, fwork = f0, f0 + 8 * lnz, f0 + 8 * (lnz + n), f0 + 8 * (lnz + 2 * n)
        Ap, _, Lnz, etree = self._at
        pos = lib.QDLDL_factor(n, Ap, self._ai, self._ax, Lp, Li, Lx, Dp, Dinv, Lnz, etree,
                               _p(bwork), iwork, fwork)
        self.Ai = self.Ax = self.work = None     # the matrix, no longer needed
        # The factor's pointers, made once: a solve (12 of them a Fiedler system) passes them.
        self._args = (n, Lp, Li, Lx, Dinv)
        return pos >= 0                          # -1: a zero pivot (as qdldl.Solver refuses)

    def solve(self, b):
        x = np.ascontiguousarray(b[self.perm], np.float64)
        _lib().QDLDL_solve(*self._args, x.ctypes.data)
        out = np.empty_like(x)
        out[self.perm] = x
        return out
