"""A mesh that is one clean disk, unwrapped in one pass (issue 21 item 2: no fixed costs on small
meshes).

An artist unwraps small pieces all day, most of them one disk: no seam, no pin, one boundary
loop. For such a mesh the general path (``mesh.checked_islands``, ``batched.conformal_islands``,
``overlap_certificate``) builds per-island tables, cut vertices and boundary loops for any number
of islands, and measures each face's geometry three times; here one pass over the half-edges finds
the island and everything its conformal map and certificate need, the geometry is measured once,
and the stored UVs are certified by ``disk_certificate``.

Nothing is assumed: ``find`` accepts only a mesh that ``mesh.checked_islands`` would make one
island with no error (every edge in at most two faces, consistently oriented, no repeated or
degenerate face, finite coordinates, one component, one boundary loop and Euler characteristic 1,
which together leave no bow-tie vertex and no handle), with the same vertex order, triangles and
loop. Anything else, a map over the bound or a boundary the certificate cannot clear at once goes
the general way, which words its errors, bends maps and cuts overlaps.
"""
from dataclasses import dataclass
import time

import numpy as np

from ..errors import CancelledError
from ..geometry import components, gradient_operators, local_frame
from ..array_calls import einsum, quiet
from ..mesh import DEGENERATE_RATIO, Island
from ..solvers.forest import component_count
from ..solvers.ordered_ldl import FIXED_RANKED, edge_ranks
from .disk_certificate import certify_disk, certify_measured_disk
from .disk_conformal import conformal
from .margins import STORE_HEADROOM
from .results import IslandResult, UnwrapResult

# Up to this many boundary edges the loop is walked in Python (a few tenths of a microsecond a
# step); a longer one goes the general way (``geometry.ordered_loops``' pointer jumping).
WALK = 4096


class _kept:
    """``functools.cached_property`` without its lock (Python 3.11 takes an RLock on every read
    until the value is kept: ~1-2 us, three a small disk's call): made on first read, then kept
    in the instance's dict, which shadows this descriptor. A Disk is made and read within one
    unwrap call; two threads reading it first at once would each make the same value."""

    def __init__(self, fn):
        self.fn, self.name, self.__doc__ = fn, fn.__name__, fn.__doc__

    def __set_name__(self, owner, name):
        self.name = name

    def __get__(self, obj, cls=None):
        if obj is None:
            return self
        value = obj.__dict__[self.name] = self.fn(obj)
        return value


@dataclass(frozen=True)
class Disk:
    """A mesh found to be one clean disk.

    Attributes
    ----------
    island : mesh.Island, as ``mesh.checked_islands`` makes it (index 0, every face)
    twins : (2, h) int64, the two half-edges (flat corners ``3 f + k``: the side from corner k to
        k + 1) of every interior edge
    loop : (b,) int64, the boundary half-edges in order along the loop (``island.loops[0]`` are
        their start vertices)
    first : (nv,) int64, each island vertex's first corner (flat)
    e01, e02 : (m,3) float64, each face's edges from its first corner
    area : (m,) float64, each face's area (``geometry.face_areas``' bits)
    Z, G : (m,3) complex128 each face's corners in its local frame and (m,2,3) float64 its
        gradient operator (``geometry.local_coordinates``, ``gradient_operators``: the same bits
        as of V and F), made on first use and kept: the conformal map, ``finish``'s measure and
        the disk certificate share them
    ranks : (nv,) int64 or None, the vertices' elimination order, made on first use (the
        conformal map's and the bound search's factorisations share it), up to ``most``
        vertices (``ordered_ldl.RANKED_VERTICES`` where None)
    factors : dict, the conformal system's factorisation (in qdldl's own order, or for
        ``bound="auto"`` in the order ``ranks``), kept for the disk's later conformal solves of
        other shapes (``capped``, ``angle_start``: the same pattern, refilled), made on first
        use; ``forget_factors`` drops it
    """
    island: Island
    twins: np.ndarray
    loop: np.ndarray
    first: np.ndarray
    e01: np.ndarray
    e02: np.ndarray
    area: np.ndarray
    most: int = None        # the most vertices ``ranks`` orders (``find``'s)

    @_kept
    def Z(self):
        return local_frame(self.e01, self.e02)

    @_kept
    def G(self):
        return gradient_operators(self.Z)

    @_kept
    def factors(self):
        return {}       # (``disk_conformal._qdldl_solve`` keeps and refills it)

    def forget_factors(self):
        self.__dict__.pop("factors", None)      # their memory, once the disk's solves are made

    @_kept
    def ranks(self):
        """The vertices' elimination order (``ordered_ldl.vertex_ranks`` of the island's
        triangles, as the general path finds it; here from the edges known: ``edge_ranks``, the
        same order without sorting the triangles' sides), shared by the conformal map and the
        bound search (of ``bound="auto"``, or of a C whose conformal map lies over itself), at a
        fixed C as the batched path (the same bits); None where the ordered factorisation
        cannot run."""
        flat = self.island.tris.ravel()
        edges = np.concatenate([self.twins[0], self.loop])
        return edge_ranks(flat.take(edges), flat.take(edges - edges % 3 + _NEXT.take(edges % 3)),
                          len(self.island.vertices), self.most)


_NEXT = np.array([1, 2, 0])
# A face is accepted here when twice its area exceeds DEGENERATE_RATIO times its longest edge
# squared by this factor more: its squared edges are summed in another order than
# checked_islands', which this covers many times over.
_CLEAR = 1.0 + 1e-9


def find(V, F, most=None):
    """The ``Disk`` of checked arrays (V float64, F int64 in range), or None when the mesh is not
    one clean disk (``mesh.checked_islands`` decides then). ``most``: the most vertices its
    ``ranks`` orders (``ordered_ldl.AUTO_RANKED_VERTICES`` for ``bound="auto"``; by default
    ``RANKED_VERTICES``)."""
    n, m = len(V), len(F)
    src = F.ravel()
    dst = F.take(_NEXT, axis=1).ravel()
    key = np.minimum(src, dst) * n + np.maximum(src, dst)
    order = key.argsort()
    ks = key.take(order)
    same = ks[1:] == ks[:-1]
    # (ufunc reductions: ndarray.any/all/min's Python wrappers cost ~1.5 us a call)
    if np.logical_or.reduce(same[1:] & same[:-1]):         # an edge in three faces or more
        return None
    i = same.nonzero()[0]
    h1, h2 = order.take(i), order.take(i + 1)
    if not np.logical_and.reduce(src.take(h1) == dst.take(h2)):   # oriented against a neighbour
        return None
    # Degenerate or not finite (a face repeating a vertex has no area; coordinates that overflow
    # make an area or a squared edge inf or NaN).
    P = V.take(F, axis=0)
    with quiet("invalid", "over"):
        e01 = P[:, 1] - P[:, 0]
        e02 = P[:, 2] - P[:, 0]
        e12 = P[:, 2] - P[:, 1]
        area = 0.5 * _cross_norm(e01, e02)
        lmax2 = np.maximum(np.maximum(einsum("ij,ij->i", e01, e01),
                                      einsum("ij,ij->i", e02, e02)),
                           einsum("ij,ij->i", e12, e12))
        if not (np.logical_and.reduce(2 * area > (DEGENERATE_RATIO * _CLEAR) * lmax2)
                and np.logical_and.reduce(np.isfinite(area))):
            return None
    interior = np.zeros(3 * m, dtype=bool)
    interior[h1] = True
    interior[h2] = True
    bnd = (~interior).nonzero()[0]
    nb = len(bnd)
    if nb == 0 or nb > WALK:
        return None
    # One boundary loop: every boundary vertex starts one boundary half-edge, and the walk from
    # the first comes back to it after all of them.
    bsrc = src.take(bnd)
    pos = np.empty(n, dtype=np.int64)
    pos.fill(-1)
    pos[bsrc] = np.arange(nb)
    nxt = pos.take(dst.take(bnd))
    if (not np.logical_and.reduce(pos.take(bsrc) == np.arange(nb))
            or np.minimum.reduce(nxt) < 0):
        return None
    seq = _walk(nxt.tolist())
    if seq is None:
        return None
    # Vertices numbered by their first corner, as checked_islands numbers cut vertices.
    first = np.empty(n, dtype=np.int64)
    first.fill(3 * m)
    first[src[::-1]] = np.arange(3 * m)[::-1]
    first_corner = (first.take(src) == np.arange(3 * m)).nonzero()[0]
    verts = src.take(first_corner)
    nv = len(verts)
    # Euler characteristic 1 with one boundary loop: genus 0 and no bow-tie (a vertex of several
    # corner fans would count once here and once per fan in the cut mesh), given one component
    # (which also leaves out two faces on the same three vertices: a closed piece of their own).
    if nv - (len(h1) + nb) + m != 1:
        return None
    f1, f2 = h1 // 3, h2 // 3
    count = component_count(f1, f2, m)
    if (components(m, f1, f2)[0] if count is None else count) != 1:
        return None
    local = np.empty(n, dtype=np.int64)
    local[verts] = np.arange(nv)
    tris = local.take(F)
    loop = bnd.take(seq)
    island = Island(0, np.arange(m, dtype=np.int64), verts, tris, (local.take(bsrc.take(seq)),))
    return Disk(island, np.array([h1, h2]), loop, first_corner, e01, e02, area, most)


def _cross_norm(a, b):
    """``geometry._cross_norm``'s arithmetic (the same bits as ``geometry.face_areas``)."""
    c0 = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    c1 = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    c2 = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return np.sqrt(c0 * c0 + c1 * c1 + c2 * c2)


def _walk(nl):
    """The order of a successor list that is one cycle through every entry, from entry 0; None
    when it is not."""
    seq, j, b = [0], nl[0], len(nl)
    while j != 0 and len(seq) < b:
        seq.append(j)
        j = nl[j]
    return seq if j == 0 and len(seq) == b else None


def unwrap_disk(V, F, disk, C, t0, progress=None, cancel=None):
    """The conformal map of a ``Disk`` at the bound C, certified from its UVs as stored.

    Returns
    -------
    (UnwrapResult, None, False) when the conformal map fits C (with STORE_HEADROOM) and the
    certificate clears it; else (None, u, overlaps), u (nv,) complex128 the conformal map as
    ``batched.conformal_islands`` solves it, for the general path to start from, and overlaps
    True when the map is flip-free and within C but its UV boundary is not one simple polygon
    (the map lies over itself: the general path would cut the disk)

    Raises
    ------
    CancelledError when ``cancel`` is set after a progress report (as ``unwrap_islands``)
    """
    report_step(progress, cancel, 0.01, "conformal maps of 1 islands")
    # for ``bound="auto"`` its factor kept (``Disk.factors``) for the angle start's first
    # solve, the same system's places (``angle_start``; dropped by ``forget_factors``)
    u = conformal(V, disk, disk.Z, disk.G, disk.ranks if C is None or len(disk.island.vertices)
                  >= FIXED_RANKED else None, keep=C is None)
    if C is None:
        return None, u, False
    done, cert, D, corner_uv = fitted(F, disk, u, C, t0, ("initial_map",), "")
    if done is None:
        fits = bool(np.isfinite(corner_uv).all() and D.max() * (1.0 + STORE_HEADROOM) <= C)
        return None, u, cert is None and fits
    report_step(progress, cancel, 1.0, "island 1/1: the conformal map fits the bound")
    if progress is not None:
        progress(1.0, "done")
    return done, None, False


def fitted(F, disk, u, C, t0, flags, note):
    """The map u (nv,) complex of a ``Disk`` placed as the batched path places an island (UV
    area = 3D area, bounding box at (0, 0)) and certified at C from its UVs as stored, with
    room for float32 (STORE_HEADROOM).

    Returns (UnwrapResult or None where it does not fit, the Certificate or None, each face's
    distortion, the corner UVs (m,3,2)); the result flagged ``flags``, ``note`` ending its
    message."""
    isl = disk.island
    nv = len(isl.vertices)
    uc = u.take(isl.tris)
    e1, e2 = uc[:, 1] - uc[:, 0], uc[:, 2] - uc[:, 0]
    one = np.zeros(len(F), dtype=np.int64)
    with quiet("invalid", "divide"):
        s = np.sqrt(np.bincount(one, disk.area, 1)[0]
                    / np.bincount(one, 0.5 * (e1.conj() * e2).imag, 1)[0])
    us = u * s
    us -= np.minimum.reduce(us.real) + 1j * np.minimum.reduce(us.imag)
    uv = us.view(np.float64).reshape(nv, 2)
    corner_uv = uv.take(isl.tris, axis=0)
    cert, D, smin, smax = certify_disk(corner_uv, disk.G, disk, C)
    if cert is None or not cert.max_distortion * (1.0 + STORE_HEADROOM) <= C:
        return None, cert, D, corner_uv
    mx = cert.max_distortion
    res = IslandResult(
        0, isl.faces, isl.vertices, isl.tris, uv=uv, status="certified",
        message=f"island 0: {len(F)} faces, max distortion {mx:.3f} <= {C:.4g}, 0 flipped{note}",
        bound_requested=C, bound_certified=float(C), max_distortion=mx,
        mean_distortion=cert.mean_distortion, flipped=0, frames="conformal",
        seconds=time.perf_counter() - t0, distortion=D, flags=flags,
        overlap_free=True, min_singular=smin, max_singular=smax,
        timings={"setup": 0.0, "solve": 0.0, "certify": 0.0})
    return (UnwrapResult(corner_uv, one, [res], time.perf_counter() - t0, "lscm",
                         certificates=(cert,)), cert, D, corner_uv)


def certify(disk, corner_uv, C, D=None):
    """The ``Certificate`` of a ``Disk``'s UVs as stored at the bound C, or None where
    ``disk_certificate`` does not clear them (``overlap_certificate`` decides then).

    D : (m,) float64, optional, each face's conformal distortion of these very UVs as
        ``metrics.certify_measured`` measured them (``finish``): not measured again (the same
        bits); the bound, the boundary and the mean are checked from the UVs as ever."""
    corner_uv = np.asarray(corner_uv, dtype=np.float64)
    if D is not None:
        return certify_measured_disk(corner_uv, D, disk, C)
    return certify_disk(corner_uv, disk.G, disk, C)[0]


def report_step(progress, cancel, fraction, message):
    """One progress report, then the cancel check (here and in ``disk_auto``)."""
    if progress is not None:
        progress(fraction, message)
    if cancel is not None and cancel.is_set():
        raise CancelledError("unwrap cancelled; nothing was changed")
