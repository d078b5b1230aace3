"""The conformal map of a ``one_disk.Disk``: ``batched.conformal_islands``' map of the one island
(``_far_pair`` pinned at 0 and 1), solved as ``lscm.lscm_pinned`` solves it, without the scipy
matrix it makes first.
"""
import numpy as np

try:  # lscm.spd_solver's factorisation (SuperLU there where it is missing)
    import qdldl
except ImportError:  # pragma: no cover - exercised where qdldl is absent
    qdldl = None

from ..solvers.face_operators import CscArrays, csc_arrays
from ..solvers.lscm import (_lscm_system, face_geometry_of, lscm_pinned,
                             ranked_triplet_solver, spd_solver)
from ..solvers.lscm_patch import PatchedLSCM

missing = object()      # (``conformal``'s ``rebuilt`` not given)

__all__ = ["conformal"]


def conformal(V, disk, Z, G, ranks, geom=None, rebuilt=missing, keep=False):
    """The conformal map (nv,) complex128 of a ``Disk`` whose faces have the local corners Z
    (m,3) complex and gradient operators G (m,2,3) (its own: ``batched.conformal_islands``'
    map; or other shapes: ``capped``), pinned as the batched path pins an island (``_far_pair``
    at 0 and 1), factorised in the vertices' order ``ranks``. ``geom``: their
    ``lscm.face_geometry_of(Z, G, disk.area)`` where the caller holds it. ``rebuilt``: in
    qdldl's own order (``ranks`` None), the faces (int64) rebuilt since the disk's last solve
    given ``rebuilt``, or None for a system assembled anew and kept (``angle_start``'s solves:
    ``solvers.lscm_patch``, the same bits); in the vertices' order ``ranks`` likewise, and the
    factor refilled (``lscm.ranked_triplet_solver``'s ``kept``: ``capped``'s solves, and
    ``angle_start``'s there); not given, nothing is kept but with ``keep`` (the disk's own
    shapes in the order ``ranks``: ``one_disk.unwrap_disk`` for ``bound="auto"``), whose
    factor is kept in ``disk.factors`` for the angle start's first solve, the same places
    (refilled: the same bits, without its conversions and elimination tree)."""
    isl = disk.island
    geom = face_geometry_of(Z, G, disk.area) if geom is None else geom
    idx = _far_pair(V.take(isl.vertices, axis=0), isl.loops[0])
    args = (geom.cbw(), geom.cb, isl.tris, len(isl.vertices), idx, np.array([0.0, 1.0], complex),
            (disk.twins[0], disk.twins[1], disk.loop))
    if ranks is not None and rebuilt is missing:
        # its triplets straight to the ordered factorisation
        return lscm_pinned(*args, ranks, kept=disk.factors if keep else None)
    # In qdldl's own order (below FIXED_RANKED vertices at a fixed C), qdldl reads the canonical
    # arrays (``Upper.csc_arrays``) without the scipy matrix ``lscm_pinned`` makes (~50-70 us of
    # its constructor on a 115-face disk). The same bits.
    if rebuilt is missing:
        A, rhs, u, free = _lscm_system(*args, triplets=True)
    else:
        kept = disk.factors.get("patched")
        if rebuilt is None or kept is None or not np.array_equal(kept.idx, idx):
            kept = disk.factors["patched"] = PatchedLSCM(geom, *args[2:])
            A, rhs, u, free = kept.system()
        else:
            A, rhs, u, free = kept.rebuilt(geom, rebuilt)
    if ranks is not None:
        # in the disk's vertex order (``lscm_pinned``'s), the factor of its last system of the
        # same places refilled (``capped``'s and ``angle_start``'s solves after the first: the
        # same triplets' places, the same bits)
        solve = ranked_triplet_solver(A.rows, A.cols, A.vals, ranks.take(free), disk.factors)
        x = (spd_solver(A.csc(), upper=True) if solve is None else solve)(rhs)
        nf = len(free)
        u[free] = x[:nf] + 1j * x[nf:]
        return u
    solve = _qdldl_solve(_canonical(A, disk.factors), disk.factors)
    if solve is None:                   # lscm_pinned's way where qdldl refuses the arrays
        return lscm_pinned(*args)
    x = solve(rhs)
    nf = len(free)
    u[free] = x[:nf] + 1j * x[nf:]
    return u


def _qdldl_solve(M, kept=None):
    """``lscm.spd_solver(M, upper=True)``'s solve of the canonical upper triangle M
    (``CscArrays``) by qdldl, or None where qdldl is missing or refuses it: a zero pivot
    (ValueError), or a release that wants a scipy matrix rather than its arrays (the caller
    then goes ``lscm_pinned``'s way).

    kept : dict, optional (``Disk.factors``): the factorisation of an earlier system of the
        same pattern (the same disk and pins, other shapes) is refilled (``update``: qdldl's
        order and symbolic steps are the pattern's, so the same bits as a new one, without
        them: homer's 1,982-face strip 0.7 against 2.4 ms), and a new one is kept there."""
    if qdldl is None:
        return None
    s, pattern = (None, None) if kept is None else kept.pop("qdldl", (None, None))
    try:
        if s is not None and _same(pattern, M):
            s.update(M, upper=True)
        else:
            s = qdldl.Solver(M, upper=True)
    except (ValueError, TypeError, AttributeError):
        return None         # (a failed refill is not kept)
    if kept is not None:
        kept["qdldl"] = (s, (M.indptr, M.indices))
    return s.solve


def _canonical(A, kept):
    """The canonical csc arrays (``face_operators.CscArrays``) of the triplets A
    (``lscm.Upper``: no two at one place) of a disk's conformal system, as
    ``Upper.csc_arrays`` makes them. Every system of one disk with the same pins has its
    triplets at the same places in the same order (``_lscm_system``: the free vertices'
    diagonal, edges and boundary edges, whatever the faces' shapes), so from the second such
    system on (``kept``: ``Disk.factors``; ``angle_start``'s and ``capped``'s solves) the values
    are taken in the order the conversion put the first ones in: the same arrays (a
    permutation: nothing is summed), without the conversion and its sort (~0.25 ms a solve on
    homer's 3,521-face patch). A disk solved once pays nothing but keeping the places."""
    if kept is None:
        return A.csc_arrays()
    last = kept.get("csc")
    if last is None or not (last[0] == A.n and _equal(last[1], A.rows)
                            and _equal(last[2], A.cols)):
        kept["csc"] = (A.n, A.rows, A.cols, None)
        return A.csc_arrays()
    n, rows, cols, M = last
    if M is None:
        # the conversion of the triplets' positions (exact as float64): where each value goes
        M = csc_arrays(np.arange(len(rows), dtype=np.float64), rows, cols, n, n)
        M = M._replace(data=M.data.astype(np.int64))
        kept["csc"] = (n, rows, cols, M)
    return CscArrays(A.vals.take(M.data), M.indices, M.indptr, (n, n))


def _equal(a, b):
    return a is b or np.array_equal(a, b)      # (a patched system's are the kept ones)


def _same(pattern, M):
    """Whether ``pattern`` (indptr, indices) is M's (``CscArrays``)."""
    if pattern is None:
        return False
    if pattern[0] is M.indptr and pattern[1] is M.indices:     # (``_canonical``'s, kept)
        return True
    return np.array_equal(pattern[0], M.indptr) and np.array_equal(pattern[1], M.indices)


def _far_pair(P, lv):
    """``batched._far_pairs`` of one loop ``lv`` (island vertex ids along it) of vertices at P:
    its first vertex and the one about half the loop's length from it, the same arithmetic."""
    Q = P.take(lv, axis=0)
    d = np.concatenate([Q[1:], Q[:1]]) - Q
    seg = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])
    cum = seg.cumsum()
    total = np.bincount(np.zeros(len(seg), dtype=np.int64), seg, 1)[0]
    return np.array([lv[0], lv[int(np.abs((cum - seg) - 0.5 * total).argmin())]])
