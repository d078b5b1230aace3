"""Every Blender polygon kept in one island (Seams "Marked" and the search's certification): a UV
map cannot hold a cut along a quad's or n-gon's diagonal, so polygons a solve split go to one
island and the islands are solved again (``whole_polygons``, ``_repair``); islands still giving a
Blender loop two UVs are failed, never written (``torn_loops``, ``_fail_torn``).

No ``bpy``: numpy and ``bd_uv`` only (tested without Blender; runs in the background job).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ..bd_uv.seams import edge_table

# Rounds of giving split polygons to one chart and certifying the charts again.
REPAIR_ROUNDS = 3


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
