"""``uv.bd_unwrap`` with Seams "Add Where Needed" (the default): the marked seams kept, seams added
only to the islands that cannot be certified as they are, a messy mesh repaired first.

1. ``bd_uv.repair.repair_mesh``: bow-tie vertices split per fan, edges of three or more faces and
   edges between oppositely oriented parts cut (marked as seams afterwards, so the artist sees
   them), zero-area faces left out (named in the report, their UVs untouched), duplicate faces
   left out of the solve and written with their twin's UVs (``verify.verify_written`` checks
   them through their twin);
2. the islands of the marked seams are unwrapped as Seams "Marked" does
   (:func:`auto_seams.whole_polygons` of ``bd_uv.unwrap``) at C, C never raised;
3. the islands that fail (closed, handles, no map within C, overlapping themselves) go to
   :func:`auto_seams.solve` at ``min(C, AUTO_BOUND)`` and S, the marked seams kept.

No ``bpy``: numpy and ``bd_uv`` only (runs in the background job).
"""
from __future__ import annotations

import numpy as np

from ..bd_uv.repair import repair_mesh
from ..bd_uv.seams.measure import splice
from ..bd_uv.options import UnwrapOptions
from ..bd_uv.seams.needed import (AUTO_BOUND, AUTO_LIMIT, island_submesh, least_charts,
                                  needs_seams, result_on_input)
from ..bd_uv.seams.repaired import needs_repair
from . import auto_seams

__all__ = ["applies", "solve", "auto_repaired"]


def applies(minimise, frames, boundary, pinned):
    """Whether Seams "Add Where Needed" adds seams: not with From Current UVs
    (``frames == "input-uv"``), a fixed ``boundary`` or ``pinned`` UVs (seams added cannot keep
    those: the islands are then taken as marked, as with Seams "Marked"). With Minimise it does,
    each island and chart at its least C (``solve``'s ``bound="auto"``)."""
    return frames != "input-uv" and boundary == "free" and not pinned


def solve(V, F, *, unwrap, tri_poly, tri_loops, seams=None, bound=5.0, stretch=2.0,
          marked_stretch=None, face_groups=None, method="lscm", frames="auto", overlap="cut",
          precision=None, atlas_cuts=True, progress=None, cancel=None):
    """Unwrap with seams added only where an island cannot be certified.

    Parameters
    ----------
    V : (n,3) float, F : (m,3) int, the batch (triangles of Blender polygons)
    unwrap : callable, ``bd_uv.unwrap`` (the operator's ``SOLVE``)
    tri_poly : (m,) int, tri_loops : (m,3) int, as for :func:`auto_seams.solve`
    seams : (s,2) int, the marked seams (all kept)
    bound : float, C of the islands the marked seams make (not raised); or "auto" (Minimise):
        each island at its least C where that is within AUTO_LIMIT (the default C), the others
        given seams, and each chart the search cuts at AUTO_BOUND at its own least C
        (``bd_uv.seams.needed.least_charts``), as ``bd_uv.unwrap(seams="needed",
        bound="auto")``
    stretch : float, S of the charts the seams added make
    marked_stretch : float, optional, Limit Stretch of the islands the marked seams make
    face_groups : (m,) int, optional, material of each triangle (seams prefer its boundaries)
    overlap : "cut" | "fail", an island of the marked seams whose map lies over itself (and
        that no lower C unfolds): given seams by the search, as ``seams.needed`` does (the
        marked pass fails it rather than cutting it along whatever edges separate the overlap),
        or left as it was and named (Overlaps "Keep as One")
    precision : float type, optional, as for ``bd_uv.unwrap`` (``np.float32``: the faces it
        cannot tell from a line are left out as zero-area; ``gather.needed_arguments`` gives it
        when such faces lie side by side)
    method, frames, progress, cancel : as for ``bd_uv.unwrap``
    atlas_cuts : bool, as for :func:`auto_seams.solve` (the islands that get seams)

    Returns
    -------
    auto_seams.AutoSeams, its ``added`` also holding the edges the repair cut, ``notes`` what
    was repaired
    """
    V = np.asarray(V, np.float64)
    F = np.asarray(F, np.int64)
    tri_poly = np.asarray(tri_poly, np.int64)
    tri_loops = np.asarray(tri_loops, np.int64)
    rep = repair_mesh(V, F, precision)
    V2, F2, keep = rep.V, rep.F, rep.faces
    tp, tl = tri_poly[keep], tri_loops[keep]
    seams2 = rep.seams(seams)
    options = dict(method=method, frames=frames, progress=progress, cancel=cancel)
    added = np.zeros((0, 2), dtype=np.int64)
    atlas = {"cuts": 0, "length": 0.0, "seams": added}
    if not len(F2):
        from ..bd_uv.unwrapping.results import UnwrapResult
        res = UnwrapResult(np.zeros((0, 3, 2)), np.zeros(0, np.int64), [], 0.0, method)
    else:
        extra = {} if marked_stretch is None else {"stretch": float(marked_stretch)}
        least = bound == "auto"
        if least:
            extra.update(bound="auto", bound_limit=AUTO_LIMIT)
        else:
            extra["bound"] = float(bound)
        res = auto_seams.whole_polygons(unwrap, V2, F2, tri_poly=tp, tri_loops=tl, seams=seams2,
                                        raise_bound=False, overlap="fail",
                                        face_groups=tp, **extra, **options)
        bad = [r for r in res.islands if r.status != "certified" and needs_seams(r, overlap)]
        if bad:
            sub, voc, Fl = island_submesh(F2, bad)
            groups = None if face_groups is None else np.asarray(face_groups)[keep][sub]
            auto = auto_seams.solve(V2[voc], Fl, tri_poly=tp[sub],
                                    tri_loops=tl[sub],
                                    bound=AUTO_BOUND if least else min(float(bound), AUTO_BOUND),
                                    stretch=float(stretch),
                                    face_groups=groups, atlas_cuts=atlas_cuts, **options)
            part = auto.result
            if least:   # each chart at its least C, never cut (a map over itself fails)
                part = least_charts(V2[voc], Fl, part, UnwrapOptions(
                    bound="auto", bound_limit=AUTO_LIMIT, overlap="fail", method=method,
                    frames=frames), progress, cancel)
            res = splice(res, part, sub, voc, len(F2))
            added = voc[auto.added]
            atlas = dict(auto.atlas_cuts, seams=np.sort(
                rep.vertex_source[voc[auto.atlas_cuts["seams"]]], axis=1).reshape(-1, 2))
    result = result_on_input(res, rep, F, method)
    added = rep.vertex_source[added] if len(added) else added
    cuts = [p for p in (added, rep.nonmanifold_edges, rep.orientation_edges) if len(p)]
    added = (np.unique(np.sort(np.concatenate(cuts), axis=1), axis=0) if cuts
             else np.zeros((0, 2), dtype=np.int64))
    charts = sum(1 for r in result.islands if r.status == "certified")
    return auto_seams.AutoSeams(result, added, charts, tuple(rep.notes(
        indices=False, count=lambda tris: len(np.unique(tri_poly[tris])))), atlas_cuts=atlas)


def auto_repaired(V, F, *, tri_poly, tri_loops, seams=None, method="lscm", precision=None,
                  **search):
    """Seams "Add Automatically" (:func:`auto_seams.solve`) on a messy mesh: solved as it is,
    and only where an island failed for a defect the repair mends
    (``bd_uv.seams.repaired.needs_repair``: a bow-tie, an edge of three faces, parts wound
    against each other, a duplicate, zero-area or NaN face) repaired as step 1 above and solved
    again, the result on the input's triangles, the edges the repair cut marked with the seams
    added, ``notes`` what was repaired (a bow-tie was refused whole: "split the vertex (Mesh >
    Split)"). ``precision`` as for :func:`solve` (``gather.auto_arguments``: float32 where faces
    Blender's float32 positions cannot tell from a line lie side by side, else None): the mesh
    is repaired first, those faces left out as zero-area as "Add Where Needed" and
    ``bd_uv.seams.repaired`` leave them (kept, their chart failed as stored, CANCELLED).

    Returns
    -------
    auto_seams.AutoSeams
    """
    def as_it_is():
        return auto_seams.solve(V, F, tri_poly=tri_poly, tri_loops=tri_loops, seams=seams,
                                method=method, **search)
    if precision is None:    # (else faces float32 cannot tell from a line lie side by side)
        auto = as_it_is()
        if not needs_repair(auto.result):
            return auto
    V = np.asarray(V, np.float64)
    F = np.asarray(F, np.int64)
    tri_poly = np.asarray(tri_poly, np.int64)
    rep = repair_mesh(V, F, precision)
    if not rep.changed or not len(rep.F):
        return as_it_is() if precision is not None else auto
    keep = rep.faces
    groups = search.pop("face_groups", None)
    part = auto_seams.solve(rep.V, rep.F, tri_poly=tri_poly[keep],
                            tri_loops=np.asarray(tri_loops, np.int64)[keep],
                            seams=rep.seams(seams), method=method,
                            face_groups=None if groups is None else np.asarray(groups)[keep],
                            **search)
    result = result_on_input(part.result, rep, F, method)
    src = rep.vertex_source
    cuts = [p for p in (src[part.added] if len(part.added) else part.added,
                        rep.nonmanifold_edges, rep.orientation_edges) if len(p)]
    added = (np.unique(np.sort(np.concatenate(cuts), axis=1), axis=0) if cuts
             else np.zeros((0, 2), dtype=np.int64))
    atlas = part.atlas_cuts
    if atlas is not None and len(atlas["seams"]):
        atlas = dict(atlas, seams=np.sort(src[atlas["seams"]], axis=1).reshape(-1, 2))
    charts = sum(1 for r in result.islands if r.status == "certified")
    return auto_seams.AutoSeams(result, added, charts, tuple(rep.notes(
        indices=False, count=lambda tris: len(np.unique(tri_poly[tris])))), atlas_cuts=atlas)
