"""``uv.bd_unwrap`` with Seams "Add Where Needed": ``bd_uv.seams.unwrap_auto`` for Blender meshes.

The core works on the triangles Blender hands it (``mesh.loop_triangles``). A Blender UV map
cannot hold a cut along the diagonal of a quad or n-gon: the polygon's triangles share the loops
at the diagonal's ends, one UV each, and a diagonal is no edge that could be marked as a seam.
:func:`solve` therefore passes the polygon of every triangle to the core
(``unwrap_auto(polygons=)``), whose charts are then unions of whole polygons, certified as
returned on these very triangles. The seams are searched on quads triangulated one fixed way
(:func:`canonical_quads`, ``canonical_triangles.py``), so a mesh gets the same seams in every
session. Any chart that would still give one Blender loop two UVs is failed, never written
(``whole_polygons.py``).

No ``bpy``: numpy and ``bd_uv`` only (tested without Blender; runs in the background job).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..bd_uv.seams import edge_table, unwrap_auto
from ..bd_uv.seams.pack_shape import atlas_cuts_of
from .canonical_triangles import canonical_quads, canonical_triangles
from .whole_polygons import (_diagonals, _edge_mask, _fail_torn, split_polygons, torn_loops,
                             whole_polygon_labels, whole_polygons)

# (whole_polygons.py's and canonical_triangles.py's names, as they were here)
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
