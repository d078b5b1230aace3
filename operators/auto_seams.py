"""``uv.bd_unwrap`` with Seams "Add Where Needed": ``bd_uv.seams.unwrap_auto`` for Blender meshes.

The core works on the triangles Blender hands it (``mesh.loop_triangles``). A Blender UV map
cannot hold a cut along the diagonal of a quad or n-gon: the polygon's triangles share the loops
at the diagonal's ends, one UV each, and a diagonal is no edge that could be marked as a seam.
:func:`solve` therefore passes the polygon of every triangle to the core
(``unwrap_auto(polygons=)``), whose charts are then unions of whole polygons, certified as
returned on these very triangles. The seams are searched on quads triangulated one fixed way
(:func:`canonical_quads`), so a mesh gets the same seams in every session. Any chart that would
still give one Blender loop two UVs is failed, never written.

No ``bpy``: numpy and ``bd_uv`` only (tested without Blender; runs in the background job).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..bd_uv.seams import edge_table, unwrap_auto
from ..bd_uv.seams.pack_shape import atlas_cuts_of

# Rounds of giving split polygons to one chart and certifying the charts again.
REPAIR_ROUNDS = 3

__all__ = ["AutoSeams", "solve", "whole_polygons", "split_polygons", "torn_loops",
           "whole_polygon_labels", "canonical_quads", "canonical_triangles"]


@dataclass(frozen=True)
class AutoSeams:
    """What :func:`solve` returns.

    Attributes
    ----------
    result : UnwrapResult
        One island per chart, certified at C (failed islands are not written).
    added : (k,2) int64
        Vertex pairs (into the batch's V) of the seams added; every one an edge shared by two
        different polygons (smaller index first).
    charts : int
        Islands of ``result``.
    notes : tuple of str
        What was repaired before solving (Seams "Add Where Needed": ``needed_seams.solve``).
    atlas_cuts : dict or None
        Of ``added``, the seams cut for the atlas (``bd_uv.seams.pack_shape``): ``cuts``,
        ``length``, ``seams`` (vertex pairs into the batch's V), as ``UnwrapResult.atlas_cuts``.
    """

    result: object
    added: np.ndarray
    charts: int
    notes: tuple = ()
    atlas_cuts: dict = None


def split_polygons(face_island, tri_poly):
    """Polygons whose triangles lie in more than one island.

    Parameters
    ----------
    face_island : (m,) int, island of each triangle
    tri_poly : (m,) int, polygon of each triangle (unique over the batch)

    Returns
    -------
    (p,) int64, the polygon ids, sorted
    """
    pairs = np.unique(np.stack([np.asarray(tri_poly, np.int64),
                                np.asarray(face_island, np.int64)], axis=1), axis=0)
    again = np.r_[False, pairs[1:, 0] == pairs[:-1, 0]]  # a second island of the same polygon
    return np.unique(pairs[again, 0])


def whole_polygon_labels(face_island, tri_poly, area):
    """Each triangle's island replaced by the island holding most of its polygon's area.

    Parameters
    ----------
    face_island : (m,) int >= 0, tri_poly : (m,) int >= 0, area : (m,) float (3D areas)

    Returns
    -------
    (m,) int64, labels constant over every polygon
    """
    isl = np.asarray(face_island, np.int64)
    poly = np.asarray(tri_poly, np.int64)
    n = int(isl.max(initial=0)) + 1
    uniq, inv = np.unique(poly * n + isl, return_inverse=True)
    weight = np.bincount(inv.ravel(), np.asarray(area, np.float64), len(uniq))
    up, ui = uniq // n, uniq % n
    order = np.lexsort((-weight, up))            # by polygon, largest share first
    first = order[np.r_[True, up[order][1:] != up[order][:-1]]]
    best = np.zeros(int(poly.max(initial=0)) + 1, dtype=np.int64)
    best[up[first]] = ui[first]
    return best[poly]


def torn_loops(corner_uv, tri_loops, tol=0.0):
    """Triangles holding a Blender loop whose corners (in several triangles) got different UVs.

    Parameters
    ----------
    corner_uv : (m,3,2) float, tri_loops : (m,3) int (unique over the batch)

    Returns
    -------
    (m,) bool
    """
    loops = np.asarray(tri_loops, np.int64).ravel()
    uv = np.asarray(corner_uv, np.float64).reshape(-1, 2)
    nl = int(loops.max(initial=-1)) + 1
    hi = np.full((nl, 2), -np.inf)
    lo = np.full((nl, 2), np.inf)
    np.maximum.at(hi, loops, uv)
    np.minimum.at(lo, loops, uv)
    with np.errstate(invalid="ignore"):
        torn = ~((hi - lo) <= tol).all(axis=1)       # NaN (unsolved) corners count as torn
    return torn[loops].reshape(-1, 3).any(axis=1)


def _fail_torn(result, tri_loops):
    """``result`` with every certified island holding a torn loop failed (status, message)."""
    torn = torn_loops(result.corner_uv, tri_loops)
    ok = np.array([r.status == "certified" for r in result.islands], dtype=bool)
    torn &= ok[result.face_island]
    if not torn.any():
        return result
    hit = np.unique(result.face_island[torn])
    islands = list(result.islands)
    for i in hit:
        islands[i] = dataclasses.replace(
            islands[i], status="failed",
            message=f"island {int(i)} is cut through a face (along a diagonal of a quad or "
                    "n-gon), which a UV map cannot hold: mark seams on it and unwrap again",
            flags=tuple(islands[i].flags) + ("torn_polygon",))
    return dataclasses.replace(result, islands=islands)


def solve(V, F, *, tri_poly, tri_loops, seams=None, bound=5.0, stretch=2.0, face_groups=None,
          method="lscm", frames="auto", atlas_cuts=True, progress=None, cancel=None):
    """Unwrap with seams added where needed, every Blender polygon kept in one chart.

    Parameters
    ----------
    V : (n,3) float, F : (m,3) int, the batch (triangles of Blender polygons)
    tri_poly : (m,) int, polygon of each triangle, unique over the batch
    tri_loops : (m,3) int, Blender loop of each corner, unique over the batch
    seams : (s,2) int, the marked seams (all kept)
    bound : float, C (conformal distortion of every face, Lipman 2012 eq. 4.9)
    stretch : float, S (every chart's singular values within [1/S, S], section 6.3)
    face_groups : (m,) int, optional, material of each triangle: seams prefer their boundaries
    method, frames, progress, cancel : as for ``bd_uv.unwrap``
    atlas_cuts : bool, the search may cut a chart it made in two where it alone caps the
        atlas's coverage (``UnwrapOptions.atlas_cuts``; the first pass, whose charts the second
        keeps)

    Returns
    -------
    AutoSeams
    """
    V = np.asarray(V, np.float64)
    tri_poly = np.asarray(tri_poly, np.int64)
    F = np.asarray(F, np.int64)
    seams = np.zeros((0, 2), np.int64) if seams is None else np.asarray(seams, np.int64)
    E = edge_table(V, F)
    marked = _edge_mask(E, seams, len(V))
    # A marked seam inside a polygon cannot exist in Blender (no such edge); drop any anyway.
    seams = E.ends[marked & ~_diagonals(E, tri_poly)]
    options = dict(bound=float(bound), stretch=float(stretch), face_groups=face_groups,
                   polygons=tri_poly, method=method, frames=frames, progress=progress,
                   cancel=cancel)
    # The seams are searched on quads triangulated the same way in every session (the same
    # seams every run), then the charts they make are certified on Blender's own triangles
    # (those its UV map is drawn and checked on): seams are polygon edges, the same on both.
    # That second pass adds a seam only where a chart fails on Blender's triangles.
    Fc, order, poly = canonical_triangles(V, F, tri_poly, np.asarray(tri_loops, np.int64))
    search = dict(options, polygons=poly,
                  face_groups=None if face_groups is None else np.asarray(face_groups)[order])
    _, found, info = unwrap_auto(V, Fc, seams=seams, atlas_cuts=atlas_cuts, **search)
    keep = np.concatenate([seams, found]) if len(found) else seams
    result, added, _ = unwrap_auto(V, F, seams=keep, atlas_cuts=False, **options)
    added = np.concatenate([found, added]) if len(added) else found
    # The marked seams are exactly where the UVs are cut: the seams added (also those inside a
    # chart, e.g. a handle's cut) and the real edges between charts.
    inner = E.faces[:, 1] >= 0
    island = result.face_island
    cut = _edge_mask(E, added, len(V))
    cut[inner] |= island[E.faces[inner, 0]] != island[E.faces[inner, 1]]
    added = E.ends[cut & ~_diagonals(E, tri_poly) & ~marked]
    result = _fail_torn(result, np.asarray(tri_loops, np.int64))
    return AutoSeams(result, np.asarray(added, np.int64).reshape(-1, 2), len(result.islands),
                     atlas_cuts=atlas_cuts_of(info))


def canonical_triangles(V, F, tri_poly, tri_loops):
    """The batch's triangles in an order and numbering fixed by the vertices alone.

    Blender numbers the polygons (and loops, and triangles) of the same mesh differently from
    one session to the next (a new UV sphere, say): quads split by :func:`canonical_quads`,
    each triangle rotated to start at its smallest vertex id (orientation kept), triangles
    sorted by their vertex ids, polygons numbered in that order.

    Returns
    -------
    Fc : (m,3) int64, the triangles in canonical order
    order : (m,) int64, ``Fc[i]`` is (the canonical split of) triangle ``order[i]``
    poly : (m,) int64, polygon of each canonical triangle, numbered from 0 in order
    """
    Fc, _ = canonical_quads(V, F, tri_poly, tri_loops)
    r = np.argmin(Fc, axis=1)
    Fc = np.take_along_axis(Fc, (r[:, None] + np.arange(3)) % 3, axis=1)
    order = np.lexsort((Fc[:, 2], Fc[:, 1], Fc[:, 0]))
    _, first, inv = np.unique(tri_poly[order], return_index=True, return_inverse=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first)] = np.arange(len(first))
    return Fc[order], order, rank[inv.ravel()]


def canonical_quads(V, F, tri_poly, tri_loops):
    """Every quad split along the same diagonal whatever Blender chose: the shorter one (to
    1e-9 of the quad's size), on a tie the one through the quad's smallest vertex id, the other
    where that one would fold the quad (a concave quad). Blender picks the diagonal of a
    symmetric quad by rounding noise, differently from one session to the next.

    Parameters
    ----------
    V : (n,3) float64; F : (m,3) int64; tri_poly : (m,) int64; tri_loops : (m,3) int64, the
        Blender loop of each corner (a polygon's loops are consecutive, in polygon order)

    Returns
    -------
    F, tri_loops : (m,3) int64, the same triangles except in quads (two triangles per polygon)
    """
    order = np.argsort(tri_poly, kind="stable")
    count = np.bincount(tri_poly)
    pair = (count[tri_poly[order]] == 2)
    first = order[pair][0::2]
    second = order[pair][1::2]
    if len(first) == 0:
        return F, tri_loops
    loops = np.concatenate([tri_loops[first], tri_loops[second]], axis=1)
    verts = np.concatenate([F[first], F[second]], axis=1)
    srt = np.argsort(loops, axis=1, kind="stable")
    ls = np.take_along_axis(loops, srt, axis=1)
    vs = np.take_along_axis(verts, srt, axis=1)
    # Two triangles of a quad share two corners: 4 distinct loops, in polygon order.
    uniq = np.concatenate([np.ones((len(ls), 1), bool), ls[:, 1:] != ls[:, :-1]], axis=1)
    quad = uniq.sum(axis=1) == 4
    ql = ls[quad][uniq[quad]].reshape(-1, 4)
    qv = vs[quad][uniq[quad]].reshape(-1, 4)
    P = V[qv]
    d02 = np.linalg.norm(P[:, 2] - P[:, 0], axis=1)
    d13 = np.linalg.norm(P[:, 3] - P[:, 1], axis=1)
    size = np.maximum(d02, d13)
    tie = np.abs(d13 - d02) <= 1e-9 * size
    low = np.argmin(qv, axis=1) % 2 == 1            # the smallest vertex on diagonal 1-3
    use13 = np.where(tie, low, d13 < d02)

    def folds(a, b, c, d):            # triangles (a,b,c) and (a,c,d) facing apart
        n1 = np.cross(P[:, b] - P[:, a], P[:, c] - P[:, a])
        n2 = np.cross(P[:, c] - P[:, a], P[:, d] - P[:, a])
        return np.einsum("ij,ij->i", n1, n2) <= 0
    use13 = np.where(folds(0, 1, 2, 3), True, np.where(folds(1, 2, 3, 0), False, use13))
    c0 = np.where(use13[:, None], [1, 2, 3], [0, 1, 2])
    c1 = np.where(use13[:, None], [1, 3, 0], [0, 2, 3])
    F, tri_loops = F.copy(), tri_loops.copy()
    fa, fb = first[quad], second[quad]
    F[fa] = np.take_along_axis(qv, c0, axis=1)
    F[fb] = np.take_along_axis(qv, c1, axis=1)
    tri_loops[fa] = np.take_along_axis(ql, c0, axis=1)
    tri_loops[fb] = np.take_along_axis(ql, c1, axis=1)
    return F, tri_loops


def _edge_mask(E, pairs, n):
    """(e,) bool: the edges of ``E`` among the (k,2) vertex ``pairs``."""
    mask = np.zeros(len(E.ends), dtype=bool)
    if pairs is not None and len(pairs):
        k = E.keys(pairs, n)
        mask[k[k >= 0]] = True
    return mask


def _diagonals(E, tri_poly):
    """(e,) bool: edges inside one polygon (diagonals of quads and n-gons), never seams."""
    inner = E.faces[:, 1] >= 0
    diagonal = np.zeros(len(E.ends), dtype=bool)
    diagonal[inner] = tri_poly[E.faces[inner, 0]] == tri_poly[E.faces[inner, 1]]
    return diagonal


def _repair(V, F, E, tri_poly, result, cut, marked, resolve):
    """Give every polygon a solve split (or cut along a diagonal) to one island, and solve again.

    Each round relabels the triangles (:func:`whole_polygon_labels`), cuts along the real edges
    between the new labels plus the real edges of ``cut``, and calls ``resolve(seams (s,2))``;
    at most ``REPAIR_ROUNDS`` rounds (certifying may cut an overlapping island again).

    Returns
    -------
    result, cut (e,) bool (the edges cut for it), repaired (polygons moved)
    """
    inner = E.faces[:, 1] >= 0
    diagonal = _diagonals(E, tri_poly)
    repaired = np.zeros(int(tri_poly.max(initial=-1)) + 1, dtype=bool)
    P = V[F]
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    for round_ in range(REPAIR_ROUNDS):
        split = split_polygons(result.face_island, tri_poly)
        if not len(split) and not (cut & diagonal).any():
            break
        repaired[split] = True
        repaired[tri_poly[E.faces[cut & diagonal, 0]]] = True
        # First round: the island holding most of the polygon; later rounds (the same polygon
        # split again, by an overlap cut): the smallest island, so the cut moves off it.
        size = np.bincount(result.face_island, minlength=len(result.islands))
        weight = area if not round_ else 1.0 / size[result.face_island] * area.sum()
        labels = whole_polygon_labels(result.face_island, tri_poly, weight)
        across = np.zeros(len(E.ends), dtype=bool)
        across[inner] = labels[E.faces[inner, 0]] != labels[E.faces[inner, 1]]
        cut = (cut & ~diagonal) | across | marked
        result = resolve(E.ends[cut])
    return result, cut, int(repaired.sum())


def whole_polygons(solve, V, F, *, tri_poly, tri_loops, seams=None, **kwargs):
    """``solve(V, F, seams=seams, **kwargs)`` (``bd_uv.unwrap``, Seams "Marked") with every
    Blender polygon kept in one island.

    The core's overlap cut split islands through quads (Suzanne with Smart UV Project seams:
    one triangle of a quad became an island of its own) until ``unwrap(face_groups=)`` kept
    polygons whole; this stays as the guard of what a UV map can hold. Polygons split anyway go
    to one island and the islands are solved again with the real edges between them as seams
    (not marked on the mesh); islands still giving a loop two UVs are failed.

    Returns
    -------
    UnwrapResult
    """
    V = np.asarray(V, np.float64)
    F = np.asarray(F, np.int64)
    tri_poly = np.asarray(tri_poly, np.int64)
    result = solve(V, F, seams=seams, **kwargs)
    if len(split_polygons(result.face_island, tri_poly)):
        E = edge_table(V, F)
        marked = _edge_mask(E, seams, len(V))
        result, _, _ = _repair(V, F, E, tri_poly, result, marked.copy(), marked,
                               lambda pairs: solve(V, F, seams=pairs, **kwargs))
    return _fail_torn(result, np.asarray(tri_loops, np.int64))
