"""``seams="auto"``: cut every island that cannot be certified as it is into certified charts.

Top-down, round after round (``rounds.refine``): a chart that is not a disk is opened by its handle
cuts (``cut_graph``), a closed sphere and a disk whose conformal map breaks a bound are split along
their cheapest neck (``fiedler_split``), until every chart's conformal map (LSCM) is flip-free with
stretch within S, an area-weighted mean conformal distortion within ``mean_cap(C)`` and a boundary
that does not cross itself. Then bottom-up (``merge.merge_charts``): neighbouring charts are merged
while the union still passes. ``bd_uv.unwrap`` finally certifies every chart at C (bending the few
whose conformal map exceeds C), and any chart the certified map leaves beyond S, crossing itself or
overlapping (``measure.measure_charts``) is split again (its pieces may merge with their
neighbours).

Each round splits all its charts in one batch (``fiedler_split_many``), a chart far beyond S
several levels at once (``bisect.split_deep``). With ``polygons`` the charts are unions of whole
polygons. Every decision on floats is made on rounded values with ties broken by index, so the
same input gives the same charts in every run and process.
"""
import dataclasses
import time

import numpy as np

from ..errors import (CancelledError, ClosedIslandError, InfeasibleError, OverlapError,
                      SolverError, TopologyError)
from ..geometry import face_areas
from ..mesh import Island, check_arrays, islands
from ..options import UnwrapOptions
from ..unwrapping.unwrap import pin_arrays, unwrap, unwrap_islands
from .charts import face_geometry, mean_cap
from .copies import find_copies
from .edges import edge_table
from .measure import measure_charts, splice
from .merge import merge_charts
from .orders import Orders
from .pack_shape import split_for_packing
from .bisect import FaceCentroids, bisect, polygon_edges
from .rounds import angle_defects, refine
from .cut_vertices import cut_mesh
from .topology import charts
from .valid import valid_everywhere
from ..trim import CHUNK, maps_large_blocks, release_memory

MAX_ROUNDS = 60
# The charts of the given seams (the first round's) pass with a mean up to this share of
# (mean_cap - 1) more: 1.0875 at C = 2.
GIVEN_SLACK = 0.25
# Passes that split charts the certified map leaves beyond S.
FINISH_ROUNDS = 4
# Meshes of at most this many faces hold their face geometry (``charts.FaceGeometry``, ~64
# bytes a face: 3 MB here) through the search, merging and the atlas's splits rather than
# forming each batch's: the faces mapped add up to ~8x the mesh's, 4-5 % of the CPU of a
# 1k-20k-face mesh. Larger meshes form each batch's (on a 500k-face mesh the held geometry
# was 30 MB at the search's memory peaks). The same per-face arithmetic, the same bits.
GEOM_FACES = 50_000


@maps_large_blocks
def unwrap_auto(V, F, seams=None, bound=2.0, stretch=2.0, face_groups=None, merge=True,
                method="lscm", frames="auto", cone="soc", progress=None, cancel=None,
                polygons=None, atlas_cuts=True):
    """Unwrap with seams added where needed: every chart a disk, certified at C, stretch <= S.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array
    seams : (s,2) int array, optional, vertex pairs of existing seams (all kept)
    bound : float, C: conformal distortion of every face at most C (Lipman 2012, eq. 4.9);
        every chart's conformal map also averages (area-weighted) at most ``mean_cap(C)``
        (1.07 at C = 2), so coarse meshes keep a low mean too
    stretch : float, S: every face's singular values within [1/S, S] with each chart scaled to
        its 3D area (section 6.3's bounds, ``max(sigma_1, 1/sigma_2) <= S``)
    face_groups : (m,) int array, optional, material per face: seams prefer group boundaries
    merge : bool, merge neighbouring charts while their union passes
    method, frames, cone, progress, cancel : as for ``bd_uv.unwrap``, which certifies the charts
        (with ``raise_bound=False``: a chart that cannot be certified at C is split further)
    polygons : (m,) int array, optional, the polygon (quad, n-gon) each triangle comes from:
        no seam is added inside a polygon (along a diagonal), so every chart is a union of whole
        polygons, as a UV map of the polygon mesh (Blender's) can hold it. Splits, cuts and
        merges work on whole polygons; ``unwrap`` gets them as its ``face_groups``. A marked
        seam along a diagonal is refused.
    atlas_cuts : bool, after merging, bisect a chart the search made (never an island the given
        seams alone bound) where it alone caps the atlas's coverage and both pieces pass
        (``pack_shape.split_for_packing``); False: only the seams the charts' test needs

    Raises
    ------
    ValueError for a bound or stretch below 1, a wrong ``polygons`` or a marked seam inside a
    polygon; CancelledError when cancelled

    Returns
    -------
    result : UnwrapResult, one island per chart
    added : (k,2) int64, vertex pairs of the seams added (smaller index first)
    info : dict, ``charts``, ``seam_length``, ``added_length``, ``edge_length`` (all edges),
        ``max_stretch`` (per chart, from the final UVs), ``crossings`` (per chart), ``rounds``,
        ``seconds``, ``atlas_cuts`` (bisections for the atlas), ``atlas_seams`` (k,2) int64 (the
        vertex pairs of their seams, among ``added``), ``atlas_length`` (their length)
    """
    t0 = time.perf_counter()
    V, F = check_arrays(V, F, share=True)     # held to the end: the caller's, not copies
    C, S = float(bound), float(stretch)
    if not (C >= 1.0 and S >= 1.0):
        raise ValueError(f"seams='auto' needs a bound C >= 1 and a stretch S >= 1, not {bound!r}, "
                         f"{stretch!r}")
    # How the charts are certified: at C, never raised (a chart that fails is cut further).
    chart_options = UnwrapOptions(method=method, bound=C, frames=frames, cone=cone,
                                  raise_bound=False)
    unwrap_options = dict(progress=progress, cancel=cancel)
    E = edge_table(V, F, face_groups)
    n, m = len(V), len(F)
    poly, diag = polygon_edges(polygons, E, m)
    if poly is not None:
        unwrap_options["face_groups"] = poly
    cut = np.zeros(len(E.ends), dtype=bool)
    if seams is not None and len(seams):
        k = E.keys(seams, n)
        cut[k[k >= 0]] = True
    cut[E.faces[:, 1] < 0] = False
    if (cut & diag).any():
        raise ValueError(f"{int((cut & diag).sum())} marked seam(s) run inside a polygon (between "
                         "two triangles of one polygon): a seam must be a polygon edge")
    original = cut.copy()
    # Seams merging keeps: the marked ones and, once cut, material boundaries.
    keep = original.copy()
    if face_groups is not None:
        g = np.asarray(face_groups)
        inner = E.faces[:, 1] >= 0
        keep[inner] |= g[E.faces[inner, 0]] != g[E.faces[inner, 1]]
    # Above ``GEOM_FACES`` faces only the face areas (``face_geometry``'s own arithmetic): the
    # mesh's face geometry (beta's coefficients, 30 MB on a 500k-face mesh) is not held through
    # the search; ``chart_maps`` forms each batch's (the same per-face numbers, the same bits).
    geom = face_geometry(V, F) if m <= GEOM_FACES else None
    A = geom.area if geom is not None else np.concatenate(
        [face_areas(V, F[i:i + CHUNK]) for i in range(0, m, CHUNK)] or [np.zeros(0)])
    # Face centroids formed for the faces split, held (with the dual edges' lengths) only
    # where the face geometry is
    cen = FaceCentroids(V, F, hold=geom is not None)
    # Islands the seams cannot fix (non-manifold, degenerate, ...) are left to ``unwrap`` to
    # report; the rest of the search works on charts of the validated mesh.
    frozen = np.zeros(m, dtype=bool)
    if not valid_everywhere(V, F, E, A):
        for i in islands(V, F, E.ends[cut]):
            if i.error is not None and not isinstance(i.error, (ClosedIslandError,
                                                                TopologyError)):
                frozen[i.faces] = True
    invalid = frozen.copy()
    # Parts that copy another part (``copies``: a bolt repeated) are left out of the search and
    # of merging and the atlas's splits, then get their original's seams.
    found = find_copies(V, F, E, cut, face_groups, poly, invalid)
    hold = invalid
    if found is not None:
        frozen |= found.mask
        hold = invalid | found.mask
    if E.fans is not None:                  # the corner table served the checks above only
        E = dataclasses.replace(E, corners=None)
    known = {}                              # conformal maps of charts that passed, by faces
    orders = Orders.of(n, m)                # the LSCM and Fiedler systems' orders
    failed = {}                             # max stretch of disks whose map failed, by chart
    defect = angle_defects(V, F, E, A)      # charts curved beyond ``rounds.CURVED``: no map
    release_memory(m)                       # the set-up's temporaries
    rounds = 0
    for rounds in range(1, MAX_ROUNDS + 1):
        if cancel is not None and cancel.is_set():
            raise CancelledError("cancelled while placing seams")
        if progress is not None:
            progress(0.0, f"seams: round {rounds}, {int(frozen.sum())}/{m} faces in charts")
        # The charts the given seams make (round 1) keep a looser mean: a chart found by a
        # search on other triangles of the same polygons (the Blender operator's second pass)
        # must not be cut again for triangulation noise in its mean.
        changed = refine(V, F, E, cut, frozen, A, cen, C, S, n, poly, diag,
                         cap=mean_cap(C) + GIVEN_SLACK * (mean_cap(C) - 1.0)
                         if rounds == 1 else mean_cap(C), known=known, geom=geom,
                         failed=failed, orders=orders, defect=defect)
        if not changed:
            break
    atlas = np.zeros(len(E.ends), dtype=bool)   # the seams added for the atlas
    kept = []
    before = None                           # the charts before the atlas's splits
    chs = None                              # the charts of ``cut``, where known
    if merge:
        chs = merge_charts(V, F, E, cut, keep, hold, S, C, known=known, geom=geom,
                           failed=failed, orders=orders)
    if atlas_cuts:
        # A chart that alone caps the atlas's coverage is bisected where that pays.
        atlas[:] = cut
        before = chs
        kept, chs = split_for_packing(V, F, E, cut, original, A, cen, S, mean_cap(C), poly, geom,
                                      known, hold, chs)
        atlas = cut & ~atlas
    if found is not None:
        chs, copied = found.settle(F, E, cut, [atlas], original, known, chs, before)
        kept = list(kept) + [None] * copied  # the atlas's splits the copies took
        found = None
    before = None
    release_memory(m)
    # A chart whose certified map overlaps itself fails (rather than being cut by ``unwrap``
    # along whatever edges separate the overlap) and is split like the others; only the last
    # round lets ``unwrap`` cut what still overlaps. Merging and the atlas's splits found the
    # charts of ``cut`` already (the same ``topology.charts`` finds).
    chs = None if invalid.any() else charts(F, E, cut) if chs is None else chs
    # The final unwrap and the measures after it read the edges' ends and lengths only: the
    # fans, faces, face edges and costs (~38 MB on a 500k-face mesh) are dropped, and the table
    # is built again (the same arrays) only if a finish round or a cut needs it.
    slim = E.fans is not None and chs is not None
    if slim:
        E = dataclasses.replace(E, faces=None, cost=None, face_edges=None, fans=None)

    def whole(E):
        """The whole edge table again where it was slimmed."""
        if E.fans is None and slim:
            E = dataclasses.replace(edge_table(V, F, face_groups), corners=None)
        return E
    result, chs = _unwrap_charts(V, F, E, cut, known, chs,
                                 chart_options.replace(overlap="cut" if FINISH_ROUNDS == 0
                                                       else "fail"), unwrap_options)
    known = None                            # the maps of charts merged since: no longer needed
    measured = None                         # (st, cr) of ``result`` on the current cut
    for finish in range(FINISH_ROUNDS):
        # Charts the certified map leaves beyond S or crossing itself are split again and only
        # their faces unwrapped anew.
        release_memory(m)                   # the unwrap's freed heap, before measuring
        st, cr = measured = measure_charts(V, F, E, cut, result, chs)
        chs = None                          # the charts of this cut, not of the next
        bad = [r for r, s, c in zip(result.islands, st, cr)
               if len(r.faces) > 1 and ((r.status == "certified" and (s > S * (1 + 1e-9) or c))
                                        or isinstance(r.error, (InfeasibleError, SolverError,
                                                                OverlapError)))]
        if not bad:
            break
        measured = None
        E = whole(E)
        frozen[:] = True
        group = np.full(m, -1, dtype=np.int64)
        for g, r in enumerate(bad):
            frozen[r.faces] = False
            group[r.faces] = g
        bisect([np.sort(r.faces) for r in bad], E, cut, A, cen, poly, orders)
        for _ in range(MAX_ROUNDS):
            if not refine(V, F, E, cut, frozen, A, cen, C, S, n, poly, diag, geom=geom,
                          failed=failed, orders=orders, defect=defect):
                break
        if merge:
            # The pieces may now merge with their neighbours (never with each other).
            merge_charts(V, F, E, cut, keep, invalid, S, C, group=group, geom=geom,
                         failed=failed, orders=orders)
        # Unwrap anew every chart holding a piece (with the neighbours it took in).
        redo = np.zeros(m, dtype=bool)
        for c in charts(F, E, cut):
            if (group[c.faces] >= 0).any():
                redo[c.faces] = True
        sub = np.flatnonzero(redo)
        Fc, voc = cut_mesh(F, E, cut, sub)
        last = finish == FINISH_ROUNDS - 1
        part = unwrap(V[voc], Fc[sub], options=chart_options.replace(
            overlap="cut" if last else "fail"), **unwrap_options)
        result = splice(result, part, sub, voc, m)
    # Edges ``unwrap`` cut (overlaps left after the last round) are seams too.
    for r in result.islands:
        if r.cut_edges is not None and len(r.cut_edges):
            k = E.keys(r.cut_edges, n)
            cut[k[k >= 0]] = True
            measured = chs = None
    if measured is None and chs is None:
        E = whole(E)
    st, cr = measured if measured is not None else measure_charts(V, F, E, cut, result, chs)
    result = dataclasses.replace(result, seconds=time.perf_counter() - t0)
    added = E.ends[cut & ~original].astype(np.int64)
    info = {"charts": len(result.islands),
            "seam_length": float(E.length[cut].sum()),
            "added_length": float(E.length[cut & ~original].sum()),
            "edge_length": float(E.length.sum()),
            "max_stretch": st, "crossings": cr, "rounds": rounds,
            "seconds": result.seconds, "atlas_cuts": len(kept),
            "atlas_seams": E.ends[atlas & cut].astype(np.int64),
            "atlas_length": float(E.length[atlas & cut].sum())}
    return result, added, info


def _unwrap_charts(V, F, E, cut, known, chs, options, run):
    """``unwrap`` of the mesh cut along ``cut`` with ``options`` (UnwrapOptions: C, not raised),
    the conformal maps in ``known`` (charts that passed) certified rather than solved again
    (``known`` is emptied before the unwrap: the maps of charts merged since are garbage);
    ``run``: progress, cancel and face_groups as ``unwrap`` takes them.

    ``chs``: the charts of ``cut`` (``topology.charts``) where the mesh is valid
    (``valid.valid_everywhere``, nothing frozen as invalid), else None. Where they are all
    disks, they are the islands ``mesh.islands`` would find (numbered alike), so they go to
    ``unwrap_islands`` as they are; otherwise ``unwrap`` finds and checks them (``E``: its
    ``ends`` only).

    Returns
    -------
    (UnwrapResult, the charts of ``cut`` (``topology.charts``) or None where not found)
    """
    if chs is None or any(c.kind != "disk" for c in chs):
        known.clear()
        return unwrap(V, F, seams=E.ends[cut], options=options, **run), (chs or None)
    isl = [Island(j, c.faces, c.vertices, c.tris, c.loops) for j, c in enumerate(chs)]
    conformal = {}
    for j, c in enumerate(chs):
        u = known.get(c.faces.tobytes())
        if u is not None:
            conformal[j] = u
    known.clear()                           # the maps are in ``conformal`` now
    return unwrap_islands(V, F, isl, pin_arrays(None, None, len(F)), options, conformal=conformal,
                          **run), chs
