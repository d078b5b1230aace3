"""``seams="needed"`` (the default of the operator, the command line and the batch script): the
marked seams kept, and seams added only to the islands that cannot be certified as they are.

1. the mesh is repaired (``repair.repair_mesh``): bow-tie vertices split per fan, edges of three
   or more faces and edges between oppositely oriented parts cut, duplicate faces left out of
   the solve (they get their twin's UVs), zero-area faces left out (named, their UVs untouched);
2. the islands the marked seams make are unwrapped at C with C never raised (``unwrap``); with
   ``bound="auto"`` at their least C, where that is within AUTO_LIMIT (the default C), and the
   charts the search of step 3 cuts at AUTO_BOUND each at its own least C (``least_charts``);
3. only the islands that fail (closed, higher genus, no certified map within C, overlapping
   themselves, or certified with a texel density varying over 4096 times across the island,
   which no texture serves and float32 UVs seldom hold (``unwrapping.storage.beyond_headroom``),
   when it has over HEADROOM_SOLVE_FACES faces or no stretch limit of ``STRETCH_LADDER``
   certifies it) go to the seam search
   (``unwrap_auto``) at ``min(C, AUTO_BOUND)`` and stretch S, keeping the marked seams. A mesh whose marked seams already make certifiable disks gets no
   new seam.

Why C = 5 for the islands given and C = 2, S = 2 for the charts the search makes: an island the
artist cut keeps the bound the artist asked for (5, the operator's default, is the paper's usual
choice and certifies every disk primitive with its conformal map); a chart bd-uv cuts itself
should look like what an artist would cut, and ``unwrap_auto``'s measured criterion at C = 2 and
S = 2 (at most a factor 2 of texel density, a mean distortion within 1.07) gives 1 to 18 charts
on Blender's primitives and Suzanne, where C = 5 would only accept more stretched charts. Both are
below the default C, so every face written is certified at the bound the user sees.
"""
import dataclasses

import numpy as np

from ..errors import (ClosedIslandError, DegenerateFacesError, InfeasibleError, InvalidMeshError,
                      NonFiniteError, OverlapError, SolverError, TopologyError)
from ..mesh import TOO_LARGE, check_arrays
from ..options import unwrap_options
from ..repair import repair_mesh, twin_corners, zero_area_faces
from ..unwrapping import one_disk
from ..unwrapping.results import IslandResult, UnwrapResult
from ..unwrapping.storage import beyond_headroom, with_storage_headroom
from ..unwrapping.unwrap import unwrap
from .auto import unwrap_auto
from .pack_shape import atlas_cuts_of
from .measure import splice

# The bound of the charts the seam search makes (see the module docstring); their stretch limit
# is ``UnwrapOptions.seams_stretch`` (``options.AUTO_SEAMS_STRETCH`` = 2 unless asked).
AUTO_BOUND = 2.0
# With ``bound="auto"`` an island whose least C is over this (the entry points' default C) gets
# seams, as it would at the default C (Online3DViewer's cow.ply, repaired into a disk of 5,800
# faces: certified at C = 72 as it is; 47 charts at C <= 2 from the seam search, each minimised).
AUTO_LIMIT = 5.0
# An island certified with a texel density too uneven to store (``beyond_headroom``) is re-solved
# under a stretch limit up to this many faces (the teapot's finger of tests/core, 2,856 faces, is
# kept whole so); a larger one goes to the seam search at once: its re-solve ends in conic solves
# of the whole island (the 69,451-face Stanford bunny: over 90 s of CPU in them, where the seam
# search cuts it into charts at S = 2 in seconds).
HEADROOM_SOLVE_FACES = 5000
# Island errors that seams can fix.
NEEDS_SEAMS = (ClosedIslandError, TopologyError, InfeasibleError, SolverError, OverlapError)


def needs_seams(island, overlap="cut"):
    """Whether a failed ``IslandResult`` goes to the seam search: its error is one seams fix,
    and not an overlap the caller asked to keep (``overlap="fail"``: named, not cut)."""
    if overlap == "fail" and isinstance(island.error, OverlapError):
        return False
    return isinstance(island.error, NEEDS_SEAMS)


def unwrap_needed(V, F, seams=None, polygons=None, options=None, marked_stretch=None,
                  repair=True, progress=None, cancel=None, precision=None):
    """Unwrap with the given (marked) seams, adding seams only to islands that cannot be
    certified as they are.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array
    seams : (s,2) int array, optional, vertex pairs of the marked seams (all kept)
    polygons : (m,) int array, optional, the polygon of each triangle (kept in one chart)
    options : UnwrapOptions, optional (its ``seams_mode`` is not read): ``bound`` C for the
        islands the marked seams make (never raised: an island with no certified map within C
        gets seams instead), ``min(C, AUTO_BOUND)`` for the charts the search cuts, ``stretch``
        (``seams_stretch``) S for those charts and ``atlas_cuts`` for the search; ``method``,
        ``frames``, ``cone`` for all;
        ``overlap`` for the marked islands (with "fail" an island overlapping itself is named,
        not given seams)
    marked_stretch : float, optional, S for the islands the marked seams make too (``unwrap``'s
        ``stretch``: the operator's Limit Stretch), at least sqrt(C)
    repair : bool, repair the mesh first (``repair.repair_mesh``); without, a messy island
        fails as it does with ``seams_mode="marked"``
    progress, cancel : as for ``bd_uv.unwrap``
    precision : the float type the positions were stored in, optional (``np.float32``: glTF,
        USD, Blender): faces it cannot tell from a line are zero-area faces too
        (``repair.zero_area_faces``)

    Returns
    -------
    UnwrapResult over the input faces, with ``seams_added`` (k,2) int64 (input vertex pairs of
    the seams the search added, smaller index first), ``atlas_cuts`` (those added for the
    atlas) and ``repair`` (what was repaired);
    ``duplicate_of`` names each duplicate face's twin (its corner UVs are the twin's);
    zero-area faces form one failed island (``DegenerateFacesError``) with NaN UVs
    """
    opts = unwrap_options(options)
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F)
    disk = clean_disk(V, F, precision) if repair else None
    rep = repair_mesh(V, F, precision) if repair and not disk else None
    V2, F2 = (rep.V, rep.F) if rep is not None else (V, np.asarray(F, np.int64))
    faces = rep.faces if rep is not None else np.arange(len(F2))
    seams2 = rep.seams(seams) if rep is not None else seams
    poly = None if polygons is None else np.asarray(polygons, np.int64)[faces]
    # An island whose map lies over itself (and that no lower C unfolds) fails here rather than
    # being cut by ``overlap_certificate`` along whatever edges separate the overlap (beetle's
    # 1.8k-face island: 22 pieces, four of one face): with ``overlap="cut"`` it goes to the seam
    # search, whose charts are cut as an artist would; with "fail" it is named
    marked = opts.replace(seams_mode="marked", raise_bound=False, stretch=marked_stretch,
                          atlas_cuts=True, overlap="fail")
    if opts.bound == "auto":    # the least C of each island whose least C is within the
        marked = marked.replace(bound_limit=min(opts.bound_limit, AUTO_LIMIT))   # default C
    added = np.zeros((0, 2), dtype=np.int64)
    atlas = atlas_cuts_of({"atlas_cuts": 0, "atlas_length": 0.0, "atlas_seams": added})
    if len(F2):
        res = unwrap(V2, F2, seams2, face_groups=poly, progress=progress, cancel=cancel,
                     options=marked, disk=disk or None)
        bad = [r for r in res.islands
               if r.status != "certified" and needs_seams(r, opts.overlap)]
        # certified, but with texel densities too uneven to texture or to store in float32:
        # re-solved under a stretch limit where one certifies, given seams where none does (the
        # milder cases float32 may still break are re-solved after, ``with_predicted_headroom``)
        flagged = beyond_headroom(V2, F2, res)
        small = [i for i in flagged if len(res.islands[i].faces) <= HEADROOM_SOLVE_FACES]
        if small:
            res, done = with_storage_headroom(V2, F2, res, small)
        else:
            done = {}
        bad += [res.islands[i] for i in flagged if i not in done]
        if bad:
            sub, voc, Fl = island_submesh(F2, bad)
            least = opts.bound == "auto"
            part, found, info = unwrap_auto(
                V2[voc], Fl,
                bound=AUTO_BOUND if least else min(float(opts.bound), AUTO_BOUND),
                stretch=opts.seams_stretch,
                method=opts.method, frames=opts.frames, cone=opts.cone, progress=progress,
                cancel=cancel, polygons=None if poly is None else poly[sub],
                atlas_cuts=opts.atlas_cuts)
            if least:
                part = least_charts(V2[voc], Fl, part, marked, progress, cancel)
            res = splice(res, part, sub, voc, len(F2))
            added = voc[found]
            atlas = atlas_cuts_of(info, voc)
    else:
        res = UnwrapResult(np.zeros((0, 3, 2)), np.zeros(0, np.int64), [], 0.0, opts.method)
    result = (result_on_input(res, rep, np.asarray(F, np.int64), opts.method)
              if rep is not None else res)
    if rep is not None and len(added):
        added = rep.vertex_source[added]
        atlas["seams"] = np.sort(rep.vertex_source[atlas["seams"]], axis=1)
    added = np.unique(np.sort(added, axis=1), axis=0) if len(added) else added.reshape(0, 2)
    return dataclasses.replace(result, seams_added=added.astype(np.int64),
                               repair=tuple(rep.notes()) if rep is not None else (),
                               atlas_cuts=atlas)


def least_charts(V, F, part, options, progress=None, cancel=None):
    """``bound="auto"``: the charts the seam search cut at AUTO_BOUND (``part``, an UnwrapResult
    on F), each unwrapped again at its least C (``options``, the marked islands' with
    ``bound="auto"``), on its own cut vertices (``island_submesh``). A chart's least map is
    taken where it certifies as the whole chart (else the chart stays as cut, certified at
    AUTO_BOUND)."""
    charts = [r for r in part.islands if r.status == "certified"]
    if not charts:
        return part
    sub, voc, Fl = island_submesh(F, charts)
    again = unwrap(V[voc], Fl, progress=progress, cancel=cancel, options=options)
    size = np.bincount(part.face_island[sub], minlength=len(part.islands))
    ok = [r for r in again.islands if r.status == "certified"
          and len(r.faces) == size[part.face_island[sub[r.faces[0]]]]]
    if not ok:
        return part
    local = np.sort(np.concatenate([r.faces for r in ok]))
    pos = np.full(len(sub), -1, dtype=np.int64)
    pos[local] = np.arange(len(local))
    kept = UnwrapResult(again.corner_uv[local], np.zeros(len(local), np.int64),
                        [dataclasses.replace(r, faces=pos[r.faces]) for r in ok],
                        again.seconds, again.method)
    return splice(part, kept, sub[local], voc, len(F))


def clean_disk(V, F, precision=None):
    """The mesh's ``unwrapping.one_disk.Disk`` when it is one clean disk with no face
    ``precision`` cannot tell from a line (``repair.zero_area_faces``), else None. Then
    ``repair.repair_mesh`` would give it back unchanged (nothing to split, cut or leave out), so
    it is not called: on a small disk it cost ~2 ms, more than the unwrap (issue 21 item 2); the
    unwrap takes the disk as found (not found twice: ~0.35 ms on a 223-face disk)."""
    try:
        V, F = check_arrays(V, F)
    except InvalidMeshError:
        return None
    disk = one_disk.find(V, F)
    if disk is None or (precision is not None and np.dtype(precision) != np.float64
                        and zero_area_faces(V, F, precision).any()):
        return None
    return disk


def island_submesh(F, islands):
    """The faces of ``islands`` (IslandResults on F) as one mesh for the seam search, on the
    islands' own cut vertices (``mesh.islands``: corners of a vertex share one only when joined
    around it without crossing a seam): the marked seams inside them are open already, and no
    vertex joins two islands, or two sides of one, that meet only there (where a certified island
    lay between them): a bow-tie of the joined faces would fail the search's whole mesh (usd-wg's
    chess pawn, once its overlapping islands came here too). A vertex with one cut vertex keeps
    its place in the order of the mesh's vertex ids (one island without seams: the faces as they
    are).

    Returns
    -------
    sub : (k,) int64, the faces, sorted; voc : (q,) int64, the vertex of F of each sub-mesh
    vertex; Fl : (k,3) int64, the faces in sub-mesh vertices
    """
    faces = np.concatenate([r.faces for r in islands])
    j = np.repeat(np.arange(len(islands)), [len(r.vertices) for r in islands])
    verts = np.concatenate([r.vertices for r in islands]).astype(np.int64)
    local = np.concatenate([np.arange(len(r.vertices)) for r in islands])
    rank = np.empty(len(verts), dtype=np.int64)
    rank[np.lexsort((local, verts, j))] = np.arange(len(verts))
    first = np.cumsum([0] + [len(r.vertices) for r in islands[:-1]])
    tris = np.concatenate([r.tris + o for r, o in zip(islands, first)]).astype(np.int64)
    order = np.argsort(faces, kind="stable")
    voc = np.empty(len(verts), dtype=np.int64)
    voc[rank] = verts
    return faces[order], voc, rank[tris[order]]


def result_on_input(res, rep, F, method):
    """``res`` (an UnwrapResult on ``rep``, a ``repair.Repair``) as a result over the input
    faces ``F`` (m,3) and vertices: duplicates given their twin's island and corner UVs
    (``duplicate_of``), zero-area faces one failed island (``DegenerateFacesError``)."""
    m = len(F)
    src = rep.vertex_source
    islands = [dataclasses.replace(
        r, faces=rep.faces[r.faces], vertices=src[r.vertices],
        cut_edges=None if r.cut_edges is None
        else src[np.asarray(r.cut_edges, np.int64).reshape(-1, 2)]) for r in res.islands]
    corner_uv = np.full((m, 3, 2), np.nan)
    face_island = np.full(m, -1, dtype=np.int64)
    corner_uv[rep.faces] = res.corner_uv
    face_island[rep.faces] = res.face_island
    dup = np.flatnonzero(rep.twin >= 0)
    if len(dup):
        tw = rep.twin[dup]
        corner = twin_corners(F, dup, tw)
        corner_uv[dup] = np.take_along_axis(corner_uv[tw], corner[:, :, None], axis=1)
        face_island[dup] = face_island[tw]
    for z, error, what, fix in (
            (rep.zero_area, DegenerateFacesError, "zero-area face(s)",
             "dissolve or merge them to unwrap them"),
            (rep.non_finite, NonFiniteError, "face(s) with NaN or infinite coordinates, or "
             f"{TOO_LARGE},",
             "fix their vertices to unwrap them")):
        if not len(z):
            continue
        face_island[z] = len(islands)
        err = error(f"island {len(islands)}: {len(z)} {what} cannot be unwrapped with any certified bound (faces "
                    f"{', '.join(str(int(i)) for i in z[:8])}{', ...' if len(z) > 8 else ''}): "
                    f"their UVs are left as they were; {fix}", island=len(islands), faces=z)
        # its vertices and triangles as any island's (vertices[tris] == F[faces])
        verts, tris = np.unique(F[z], return_inverse=True)
        islands.append(IslandResult(index=len(islands), faces=z, vertices=verts.astype(np.int64),
                                    tris=tris.reshape(-1, 3).astype(np.int64), status="failed",
                                    error=err, message=str(err)))
    twin = rep.twin if len(dup) else None
    return UnwrapResult(corner_uv, face_island, islands, res.seconds, method, duplicate_of=twin)
