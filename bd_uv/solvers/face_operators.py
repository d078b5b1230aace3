"""Sparse operators of an island assembled straight from each face's three corner coefficients.

Every face's gradient of a linear function is ``gx . u[tris]``, ``gy . u[tris]`` (three numbers
each), so the global step's Laplacian ``L = sum_f A_f (gx gx^T + gy gy^T)`` and the lift of a map to
every face's alpha and beta are written as triplets in a few whole-array operations, with one
conversion to a compressed matrix, rather than by products and slices of scipy matrices (a fixed
cost of ~3 ms on a 223-face island against ~0.5 ms here: issue 21, "no fixed costs").
"""
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
from scipy.sparse import _sparsetools as _st

__all__ = ["face_gradients", "gradient_rows", "laplacian_blocks", "laplacian_block_arrays",
           "alpha_beta_lift",
           "free_lift_arrays", "CscArrays", "as_csc", "csc_arrays"]


def face_gradients(Gx, Gy, tris):
    """Per-face gradient coefficients of the csr operators ``Gx``, ``Gy`` (k, nv), whose row f
    has its entries among the columns ``tris[f]`` (entries that are exact zeros may be absent).

    Returns
    -------
    gx, gy : (k,3) float64, the coefficient of each corner of each face (0 where absent)
    """
    k = len(tris)
    out = []
    for G in (Gx, Gy):
        G = sp.csr_array(G)
        rows = np.repeat(np.arange(k), np.diff(G.indptr))
        corner = np.argmax(tris[rows] == G.indices[:, None], axis=1)
        g = np.zeros((k, 3))
        np.add.at(g, (rows, corner), G.data)
        out.append(g)
    return out[0], out[1]


def gradient_rows(gx, gy, tris):
    """The compressed rows (indptr, indices, data) of ``global_step.GlobalStep.G`` (2k, nv):
    face j's d/dx coefficients ``gx[j]`` on its corners ``tris[j]`` in row j, its d/dy ``gy[j]``
    in row k + j, each row's columns increasing and its exact zeros left out, as the sums of
    the operators it is made of (``energies.jacobian_operators``' halves) leave them."""
    k = len(tris)
    order = np.argsort(tris, axis=1, kind="stable")
    cols = np.take_along_axis(tris, order, axis=1)
    data = np.concatenate([np.take_along_axis(gx, order, axis=1),
                           np.take_along_axis(gy, order, axis=1)]).ravel()
    cols = np.concatenate([cols, cols]).ravel()
    keep = data != 0.0
    indptr = np.zeros(2 * k + 1, np.int64)
    np.cumsum(keep.reshape(2 * k, 3).sum(axis=1), out=indptr[1:])
    return indptr, cols[keep], data[keep]


def laplacian_blocks(gx, gy, area, tris, free, fixed, nv):
    """``L = sum_f A_f (gx gx^T + gy gy^T)`` split into its free-free block (csc, canonical:
    duplicates summed, indices sorted) and its free-fixed block (csc).

    Parameters
    ----------
    gx, gy : (k,3) from ``face_gradients``; area : (k,); tris : (k,3) int64
    free, fixed : vertex ids (a partition of 0..nv-1), in the order of the blocks' rows and
        columns (``global_step.GlobalStep``'s free vertices may be in an elimination order)
    """
    return tuple(as_csc(b) for b in laplacian_block_arrays(gx, gy, area, tris, free, fixed, nv))


def laplacian_block_arrays(gx, gy, area, tris, free, fixed, nv):
    """``laplacian_blocks``' two blocks as bare ``CscArrays`` (the same arrays and bits; no
    scipy matrix is made: its constructor's checks are ~10-25 us a matrix, which a small
    island's search paid twice)."""
    vals = area[:, None, None] * (gx[:, :, None] * gx[:, None, :] + gy[:, :, None] * gy[:, None, :])
    # each entry's row and column, written by broadcasting assignments (np.broadcast_to's
    # Python wrapper costs ~4 us a call; the same arrays)
    r, c = np.empty(vals.shape, np.int64), np.empty(vals.shape, np.int64)
    r[...] = tris[:, :, None]
    c[...] = tris[:, None, :]
    r, c = r.ravel(), c.ravel()
    vals = vals.ravel()
    pos = np.empty(nv, dtype=np.int64)
    pos[free] = np.arange(len(free))
    pos[fixed] = np.arange(len(fixed))
    is_free = np.zeros(nv, dtype=bool)
    is_free[free] = True
    fr, fc = is_free[r], is_free[c]
    ff, fF = fr & fc, fr & ~fc
    return (_summed(vals[ff], pos[r[ff]], pos[c[ff]], len(free), len(free)),
            _summed(vals[fF], pos[r[fF]], pos[c[fF]], len(free), len(fixed)))


class CscArrays(NamedTuple):
    """A canonical csc matrix as its bare arrays (``laplacian_block_arrays``): what
    ``ordered_ldl.solver_in_order`` reads of a matrix (``shape``, ``indptr``, ``indices``,
    ``data``); ``as_csc`` makes the scipy matrix, ``times`` its product with a dense matrix."""
    data: np.ndarray
    indices: np.ndarray
    indptr: np.ndarray
    shape: tuple

    @property
    def nnz(self):
        """The stored entries (what ``qdldl.Solver`` reads of a matrix besides the arrays)."""
        return int(self.indptr[-1])

    def times(self, X):
        """``M @ X`` for X (ncols, r) float64: scipy's compiled product, column by column of X
        (each entry of the answer summed in the same order: the same bits), without its
        dispatch."""
        nr, nc = self.shape
        X = np.asarray(X, dtype=np.float64)
        out = np.zeros((nr, X.shape[1]))
        for j in range(X.shape[1]):
            y = np.zeros(nr)
            _st.csc_matvec(nr, nc, self.indptr, self.indices, self.data,
                           np.ascontiguousarray(X[:, j]), y)
            out[:, j] = y
        return out


def as_csc(arrays):
    """The scipy csc matrix (canonical) of ``CscArrays``, on the same arrays."""
    M = sp.csc_array((arrays.data, arrays.indices, arrays.indptr), shape=arrays.shape,
                     copy=False)
    M.has_canonical_format = True
    return M


def csc_arrays(vals, rows, cols, nr, nc):
    """``CscArrays`` of the triplets (vals, rows, cols) (int64 rows and columns) of an (nr, nc)
    matrix: scipy's conversion's arrays (``_summed``), no scipy matrix made."""
    return _summed(vals, rows, cols, nr, nc)


def _summed_csc(vals, rows, cols, nr, nc):
    """``sp.csc_array((vals, (rows, cols)), shape=(nr, nc))`` (int64 rows and columns): scipy's
    own compiled steps of that conversion, called straight (``_summed``), without the ~0.1 ms
    of its checks and conversions a matrix."""
    return as_csc(_summed(vals, rows, cols, nr, nc))


def _summed(vals, rows, cols, nr, nc):
    """``_summed_csc``'s arrays (``CscArrays``): the same arrays, bits and order of summing
    duplicates as scipy's conversion (triplets bucketed by column, sorted within a column only
    when not sorted yet, duplicates summed)."""
    n = len(vals)
    indptr, indices, data = np.empty(nc + 1, np.int64), np.empty(n, np.int64), np.empty(n)
    _st.coo_tocsr(nc, nr, n, cols, rows, vals, indptr, indices, data)
    if not _st.csr_has_canonical_format(nc, indptr, indices):
        if not _st.csr_has_sorted_indices(nc, indptr, indices):
            _st.csr_sort_indices(nc, indptr, indices, data)
        _st.csr_sum_duplicates(nc, nr, indptr, indices, data)
        k = int(indptr[-1])
        indices, data = indices[:k].copy(), data[:k].copy()
    return CscArrays(data, indices, indptr, (nr, nc))


def _lift_entries(gx, gy, tris, nv):
    """The lift's entries, six a row (row-major): data (24k,) and columns (24k,) into
    ``[u; v]`` (2nv), rows ``u_x + v_y``, ``v_x - u_y``, ``u_x - v_y``, ``v_x + u_y``."""
    k = len(tris)
    cu, cv = tris, tris + nv
    # per block row: (coefficients on u, coefficients on v)
    data = np.empty((4, k, 6))
    data[0, :, :3], data[0, :, 3:] = gx, gy
    data[1, :, :3], data[1, :, 3:] = -gy, gx
    data[2, :, :3], data[2, :, 3:] = gx, -gy
    data[3, :, :3], data[3, :, 3:] = gy, gx
    cols = np.empty((4, k, 6), dtype=np.int64)
    cols[:, :, :3], cols[:, :, 3:] = cu, cv
    return data.reshape(-1), cols.reshape(-1)


def _free_entries(data, cols, area, free, nv):
    """The entries on the free unknowns ``[free; free + nv]``: (their positions there, the
    mask of them among all, the compressed rows' pointer (4k + 1,), each entry's weight: half
    its face's area)."""
    k = len(area)
    pos = np.empty(2 * nv, dtype=np.int64)
    pos.fill(-1)
    nf = len(free)
    pos[free] = np.arange(nf)
    pos[free + nv] = np.arange(nf, 2 * nf)
    tr = pos[cols]
    keep = tr >= 0
    w = np.empty((4, k, 6))
    w[...] = (0.5 * area)[None, :, None]
    w = w.reshape(-1)
    indptr = np.zeros(4 * k + 1, dtype=np.int64)
    indptr[1:] = keep.cumsum()[5::6]        # kept entries up to each row's end
    return tr, keep, indptr, w


def alpha_beta_lift(gx, gy, area, tris, free, nv, free_lift=False):
    """The lift of a map ``[u; v]`` (2nv) to every face's doubled alpha and beta (4k): rows
    ``u_x + v_y``, ``v_x - u_y``, ``u_x - v_y``, ``v_x + u_y`` (csr, six entries a row), and the
    least-squares step's right-hand side operator ``B_free^T diag(A, A, A, A) / 2`` (csc: the
    compressed rows of the weighted lift on the free unknowns read as columns, so no sort; rows
    the free unknowns ``[free; free + nv]``).

    Returns
    -------
    B : (4k, 2nv) csr; BtA : (2 len(free), 4k) csc; with ``free_lift`` also B's columns of the
    free unknowns ``[free; free + nv]``, (4k, 2 len(free)) csr (the same arrays as BtA's)
    """
    k, nf = len(tris), len(free)
    data, cols = _lift_entries(gx, gy, tris, nv)
    B = sp.csr_array((data, cols, np.arange(0, 24 * k + 1, 6)), shape=(4 * k, 2 * nv))
    tr, keep, indptr, w = _free_entries(data, cols, area, free, nv)
    BtA = sp.csc_array(((data * w)[keep], tr[keep], indptr), shape=(2 * nf, 4 * k))
    if free_lift:
        return B, BtA, sp.csr_array((data[keep], tr[keep], indptr), shape=(4 * k, 2 * nf))
    return B, BtA


def free_lift_arrays(gx, gy, area, tris, free, nv):
    """``alpha_beta_lift``'s free columns as bare arrays (no scipy matrix is made: a small
    island's search pays per call): ``(indptr, indices, data, wdata, fixed)``, the compressed
    rows of the lift on the free unknowns ``[free; free + nv]`` (4k, 2 len(free)), ``wdata``
    their data weighted by half each face's area (the right-hand side operator's, its columns
    these rows), and ``fixed = (rows, columns into [u; v], data)`` of the entries on the fixed
    vertices (the fixed vertices' share of the lift)."""
    data, cols = _lift_entries(gx, gy, tris, nv)
    tr, keep, indptr, w = _free_entries(data, cols, area, free, nv)
    d = data[keep]
    drop = ~keep
    rows = np.flatnonzero(drop) // 6        # six entries a row
    return indptr, tr[keep], d, d * w[keep], (rows, cols[drop], data[drop])
