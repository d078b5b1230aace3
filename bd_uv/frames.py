"""Frame fields and the initial maps they come from (Lipman 2012, section 4, "Framing of M").

A frame is stored as a unit complex number ``w`` per face: the rotation from the face's canonical
local frame (see ``geometry.local_coordinates``) to the frame. A map whose similarity part is
``alpha`` in the canonical frame has similarity part ``w * alpha`` in the frame ``w``.
"""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .energies import jacobian_operators
from .errors import BDError
from .geometry import corner_angles

try:  # LDL^T with AMD ordering for the symmetric (LSCM) systems; SuperLU without it
    import qdldl
except ImportError:  # pragma: no cover - exercised where qdldl is absent
    qdldl = None


def frames_from_map(alpha):
    """Frames that make a map's similarity part real and positive (eq. 4.21).

    Parameters
    ----------
    alpha : (k,) complex, the map's similarity part per face in the canonical frames

    Returns
    -------
    w : (k,) complex128 unit numbers, ``w * alpha = |alpha|``. Faces with ``alpha = 0`` get ``w = 1``.
    """
    a = np.abs(alpha)
    ok = a > 0
    w = np.ones(len(alpha), dtype=np.complex128)
    w[ok] = np.conj(alpha[ok]) / a[ok]
    return w


def lscm_map(Z, tris, nv, loops, pins=None, ops=None):
    """Least-squares conformal map (Levy et al. 2002), the free-boundary conformal initial map.

    Parameters
    ----------
    Z : (k,3) complex, local corner coordinates
    tris : (k,3) int
    nv : int, number of island vertices
    loops : sequence of (b,) int arrays, boundary loops (longest first)
    pins : tuple (idx (p,) int, uv (p,) complex), optional. Without at least two pins, the two
        boundary vertices farthest apart are fixed at 0 and 1.
    ops : energies.JacobianOperators of (Z, tris, nv), optional (built here when not given)

    Returns
    -------
    u : (nv,) complex128
    """
    if ops is None:
        ops = jacobian_operators(Z, tris, nv)
    W = sp.diags(ops.area)
    Q = (ops.Bre.T @ W @ ops.Bre + ops.Bim.T @ W @ ops.Bim).tocsc()
    if pins is not None and len(pins[0]) >= 2:
        idx, val = np.asarray(pins[0]), np.asarray(pins[1])
    else:
        idx, val = _far_pair(Z, tris, nv, loops[0])
    return _solve_fixed(Q, nv, idx, val)


def _far_pair(Z, tris, nv, loop):
    """Two boundary vertices about half the boundary length apart, pinned at 0 and 1."""
    L = _loop_lengths(Z, tris, nv, loop)
    s = np.concatenate([[0.0], np.cumsum(L)[:-1]])
    j = int(np.argmin(np.abs(s - 0.5 * L.sum())))
    return np.array([loop[0], loop[j]]), np.array([0.0, 1.0], dtype=np.complex128)


def _edge_length_lookup(Z, tris, nv):
    """Sparse matrix of edge lengths from the local coordinates (symmetric)."""
    a = tris.ravel()
    b = np.roll(tris, -1, axis=1).ravel()
    l = np.abs(np.roll(Z, -1, axis=1) - Z).ravel()
    return sp.coo_array((l, (a, b)), shape=(nv, nv)).tocsr()


def _loop_lengths(Z, tris, nv, loop):
    """Length of each boundary edge loop[i] -> loop[i+1]: the face's edge either way round
    (a boundary edge is one face's), looked up among the faces' edges sorted by their ends
    (the sum ``E[a, b] + E[b, a]`` that the symmetric lookup ``_edge_length_lookup`` gives,
    without its sparse matrices: ~0.4 ms of a 1k-face island)."""
    tris = np.asarray(tris, dtype=np.int64)
    loop = np.asarray(loop, dtype=np.int64)
    key = (tris * nv + np.roll(tris, -1, axis=1)).ravel()
    order = np.argsort(key)         # (distinct keys: a stable sort is ~5x slower here)
    key = key.take(order)
    lens = np.abs(np.roll(Z, -1, axis=1) - Z).ravel().take(order)
    nxt = np.roll(loop, -1)

    def lookup(a, b):
        want = a * nv + b
        at = np.minimum(np.searchsorted(key, want), len(key) - 1)
        return np.where(key.take(at) == want, lens.take(at), 0.0)
    return lookup(loop, nxt) + lookup(nxt, loop)


def hole_fans(Z, tris, nv, holes):
    """Triangles filling each hole: a fan around a new centre vertex (ids nv, nv + 1, ...).

    Parameters
    ----------
    Z : (k,3) complex local corner coordinates, tris : (k,3) int, nv : int
    holes : sequence of (b,) int hole loops, each running with the island's faces on its left
        (``bijectivity.oriented_loop``), so the fan faces are oriented like the island's

    Returns
    -------
    Z_fill : (q,3) complex, each fan face as an isosceles triangle on its hole edge (height from
        the radius of a circle of the hole's perimeter), tris_fill : (q,3) int64, q = sum of b
    """
    E = _edge_length_lookup(Z, tris, nv)
    E = E + E.T
    extra_Z, extra_T = [], []
    for h, loop in enumerate(holes):
        c = nv + h
        nxt = np.roll(loop, -1)
        # Boundary edge loop -> nxt runs along the island; the fan face (nxt, loop, c) is
        # oriented like the island's faces. Its shape: an isosceles triangle on the edge.
        le = np.asarray(E[loop, nxt]).ravel()
        radius = max(le.sum() / (2 * np.pi), 1e-300)
        height = np.sqrt(np.maximum(radius ** 2 - (le / 2) ** 2, (0.1 * le) ** 2))
        extra_Z.append(np.stack([np.zeros_like(le), le + 0j, le / 2 + 1j * height], 1))
        extra_T.append(np.stack([nxt, loop, np.full(len(loop), c)], 1))
    return np.concatenate(extra_Z), np.concatenate(extra_T).astype(np.int64)


def harmonic_map(Z, tris, nv, loops):
    """Flip-free harmonic embedding onto a disk (Tutte/Floater, mean-value weights).

    The longest boundary loop goes to the unit circle by arc length. Every other loop (a hole) is
    filled, for this solve only, by a fan around a virtual centre vertex, so the embedding of the
    filled disk is a valid convex-combination map (Floater 2003) and its restriction to the
    island's faces has no flipped face.

    Returns
    -------
    u : (nv,) complex128
    """
    outer, holes = loops[0], loops[1:]
    # Mean-value weights per corner: w_ij += tan(theta_i / 2) / |e_ij|.
    ZZ, TT, n_all = Z, tris, nv
    if holes:
        extra_Z, extra_T = hole_fans(Z, tris, nv, holes)
        ZZ = np.concatenate([Z, extra_Z])
        TT = np.concatenate([tris, extra_T])
        n_all = nv + len(holes)
    ang = np.abs(corner_angles(ZZ))
    t = np.tan(ang / 2)
    lens = np.abs(np.roll(ZZ, -1, axis=1) - ZZ)  # edge c -> c+1
    i = TT.ravel()
    j = np.roll(TT, -1, axis=1).ravel()
    k = np.roll(TT, -2, axis=1).ravel()
    lij = lens.ravel()
    lik = np.roll(lens, 1, axis=1).ravel()  # edge c-1 -> c, same length as c -> c-1
    tt = t.ravel()
    rows = np.concatenate([i, i])
    cols = np.concatenate([j, k])
    vals = np.concatenate([tt / lij, tt / lik])
    Wm = sp.coo_array((vals, (rows, cols)), shape=(n_all, n_all)).tocsr()
    L = (sp.diags(np.asarray(Wm.sum(axis=1)).ravel()) - Wm).tocsr()
    seg = _loop_lengths(Z, tris, nv, outer)
    s = np.concatenate([[0.0], np.cumsum(seg)[:-1]]) / seg.sum()
    ub = np.exp(2j * np.pi * s)
    return _solve_fixed(L, n_all, outer, ub, symmetric=False)[:nv]


def _solve_fixed(Q, n, idx, val, symmetric=True):
    """Minimise (or solve, for a Laplacian) with vertices ``idx`` fixed to complex ``val``.

    For ``symmetric`` Q acts on [Re u; Im u] (size 2n), else Q (n x n) acts on each coordinate.
    """
    idx = np.asarray(idx, dtype=np.int64)
    val = np.asarray(val, dtype=np.complex128)
    if symmetric:
        fixed = np.concatenate([idx, idx + n])
        xval = np.concatenate([val.real, val.imag])
        N = 2 * n
    else:
        fixed, xval, N = idx, val, n
    free = np.setdiff1d(np.arange(N), fixed)
    Q = sp.csc_array(Q)
    rhs = -(Q[free][:, fixed] @ xval)
    A = Q[free][:, free].tocsc()
    if symmetric and qdldl is not None and not np.iscomplexobj(rhs):
        # LDL^T of the symmetric positive definite LSCM system: 3-4x faster than SuperLU here
        # (hemisphere.obj, 2k vertices: 0.1 s -> 0.03 s); a zero pivot falls back to SuperLU.
        try:
            xf = qdldl.Solver(sp.triu(A, format="csc"), upper=True).solve(
                np.ascontiguousarray(rhs, dtype=np.float64))
        except ValueError:
            xf = None
        if xf is not None and np.all(np.isfinite(xf)):
            x = np.zeros(N)
            x[fixed] = xval
            x[free] = xf
            return x[:n] + 1j * x[n:]
    try:
        # A symmetric system (LSCM) factors about twice as fast with a symmetric ordering.
        lu = (spla.splu(A, permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True})
              if symmetric else spla.splu(A))
        if np.iscomplexobj(rhs):
            sol = lu.solve(np.ascontiguousarray(np.stack([rhs.real, rhs.imag], axis=1)))
            xf = sol[:, 0] + 1j * sol[:, 1]
        else:
            xf = lu.solve(np.ascontiguousarray(rhs))
    except RuntimeError as exc:  # singular factor
        raise BDError(f"initial map: the linear system is singular ({exc})") from exc
    x = np.zeros(N, dtype=val.dtype if not symmetric else np.float64)
    x[fixed] = xval
    x[free] = xf
    return x[:n] + 1j * x[n:] if symmetric else x


def planar_map(V):
    """Coordinates of a planar mesh in its own plane, for constant frames.

    Parameters
    ----------
    V : (nv,3) float

    Returns
    -------
    u : (nv,) complex128

    Raises
    ------
    BDError when the vertices are not coplanar.
    """
    c = V - V.mean(axis=0)
    _, s, vt = np.linalg.svd(c, full_matrices=False)
    if s[0] == 0 or s[2] > 1e-9 * s[0]:
        raise BDError("constant frames need a planar mesh; this island is not planar "
                      "(use frames='auto')")
    return c @ vt[0] + 1j * (c @ vt[1])
