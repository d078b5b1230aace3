"""Sparse symmetric positive definite factorisation, factorised once and back-solved with several
right-hand sides at once (the global step of ``projection``; usable for any Laplacian-like system).

Measured on face.obj's projection matrix (25.9k unknowns, 181k non-zeros, busy 2-core machine):
cholespy factorises in 0.14 s and back-solves 4 columns in 2.3 ms, qdldl 0.053 s and 4.9 ms, scipy's
SuperLU 0.080 s and 4.5 ms (``benchmarks/bench_projection.py --backends``). All three have wheels
for cp311 and cp313 on linux-x64, windows-x64, macos-arm64 and macos-x64.
"""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["factor_spd"]

try:  # qdldl: LDL^T with AMD ordering, numeric refactorisation on a fixed pattern
    import qdldl
except ImportError:  # pragma: no cover - exercised where qdldl is absent
    qdldl = None


_FOUND = []     # ``_backends``' answer, once a process (a failed import is ~0.3 ms each time)


def _backends():
    if _FOUND:
        return _FOUND
    found = []
    try:
        import cholespy  # noqa: F401
        found.append("cholespy")
    except ImportError:
        pass
    if qdldl is not None:
        found.append("qdldl")
    found.append("splu")
    _FOUND[:] = found
    return found


def upper_triangle(M):
    """``sp.triu(M, format="csc")`` of a canonical csc matrix (the entries on and above
    the diagonal, in their order), without scipy's round trip through triplets (~0.2 ms on a
    300-vertex island); scipy's for any other matrix."""
    M = sp.csc_array(M)
    if not M.has_canonical_format:
        return sp.triu(M, format="csc")
    n = M.shape[1]
    col = np.repeat(np.arange(n), np.diff(M.indptr))
    keep = M.indices <= col
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(col[keep], minlength=n), out=indptr[1:])
    return sp.csc_array((M.data[keep], M.indices[keep], indptr), shape=M.shape)


def factor_spd(M, backend="auto"):
    """Factorise a sparse symmetric positive definite matrix once.

    Parameters
    ----------
    M : (n, n) sparse, symmetric positive definite
    backend : "auto" | "cholespy" | "qdldl" | "splu"
        "auto" takes the first installed of cholespy (supernodal Cholesky, fastest back-solves),
        qdldl (LDL^T), scipy's SuperLU.

    Returns
    -------
    solve : callable, ``solve(B)`` with B (n,) or (n, r) float64 -> same shape; where the
        backend has it, ``solve.vector(b)`` for a contiguous float64 b (n,) without the checks
    name : str, the backend used
    """
    if backend == "auto":
        backend = _backends()[0]
    M = sp.csc_array(M)
    n = M.shape[0]
    if backend == "cholespy":
        import cholespy

        C = sp.coo_array(M)
        fac = cholespy.CholeskySolverD(n, np.ascontiguousarray(C.row, dtype=np.int32),
                                       np.ascontiguousarray(C.col, dtype=np.int32),
                                       np.ascontiguousarray(C.data, dtype=np.float64),
                                       cholespy.MatrixType.COO)

        def solve(B):
            B = np.ascontiguousarray(B, dtype=np.float64)
            X = np.empty_like(B)
            fac.solve(B, X)
            return X
    elif backend == "qdldl":
        if qdldl is None:
            raise ImportError("qdldl is not installed")
        fac = qdldl.Solver(upper_triangle(M), upper=True)

        def solve(B):
            B = np.asarray(B, dtype=np.float64)
            if B.ndim == 1:
                return fac.solve(B)
            return np.stack([fac.solve(np.ascontiguousarray(B[:, i]))
                             for i in range(B.shape[1])], axis=1)
        solve.vector = fac.solve    # for a contiguous float64 (n,) alone, without the checks
    elif backend == "splu":
        lu = spla.splu(M, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})

        def solve(B):
            return lu.solve(np.asarray(B, dtype=np.float64))
    else:
        raise ValueError(f"unknown backend {backend!r}: use 'auto', 'cholespy', 'qdldl' or "
                         "'splu'")
    return solve, backend
