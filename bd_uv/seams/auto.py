"""``seams="auto"``: cut every island that cannot be certified as it is into certified charts.

Top-down: a chart that is not a disk is opened by its handle cuts (``cut_graph``), a closed
sphere and a disk whose conformal map breaks a bound are split along their cheapest neck
(``fiedler_split``), until every chart's conformal map (LSCM) is flip-free with stretch within S,
an area-weighted mean conformal distortion within ``mean_cap(C)`` and a boundary that does not cross
itself. Then bottom-up: neighbouring charts are merged while
the union still passes. ``bd_uv.unwrap`` finally certifies every chart at C (bending the few
whose conformal map exceeds C), and any chart the certified map leaves beyond S, crossing
itself or overlapping is split again (its pieces may merge with their neighbours).

Each round splits all its charts in one batch (``fiedler_split_many``), a chart far beyond S
several levels at once (``_split_deep``). With ``polygons`` the charts are unions of whole
polygons. Every decision on floats is made on rounded values with ties broken by index, so the
same input gives the same charts in every run and process.
"""
import dataclasses
import time

import numpy as np

from ..errors import (CancelledError, ClosedIslandError, InfeasibleError, OverlapError,
                      SolverError, TopologyError)
from ..geometry import face_areas
from ..metrics import face_jacobians
from ..mesh import DEGENERATE_RATIO, check_arrays, islands
from ..unwrapping.results import UnwrapResult
from ..unwrapping.unwrap import unwrap
from .charts import boundary_crossings, chart_maps, piece_stretch
from .cut_graph import cut_graph
from .edges import edge_table
from .split import _quantize, fiedler_split_many
from .topology import charts, cut_mesh

MAX_ROUNDS = 60
# Charts are accepted a little inside S: bending a map into C moves its stretch slightly.
MARGIN = 0.98
# Area-weighted mean conformal distortion a chart's conformal map may have (the result's mean
# is the area-weighted mean of its charts'): on coarse curved meshes a map within C and S can
# still average far above 1 (each vertex's angle defect is flattened into a few large faces:
# an 80-face icosphere in two charts averaged 1.23, a 16-sided cylinder 1.32). ``mean_cap``:
# 1 + MEAN_SLOPE for C <= 2, growing with a looser bound. 0.07 keeps the coarse test meshes'
# results at <= 1.065 with seams within xatlas's; 0.05 cost them more seam.
MEAN_SLOPE = 0.07
# The charts of the given seams (the first round's) pass with a mean up to this share of
# (mean_cap - 1) more: 1.0875 at C = 2.
GIVEN_SLACK = 0.25
# Passes that split charts the certified map leaves beyond S.
FINISH_ROUNDS = 4
# Levels a failing chart is split at once while its restricted map still breaks S.
SPLIT_DEPTH = 4
# ... while the restricted map's stretch exceeds S by this factor (a piece's own map is better
# than the restriction of its chart's map: nearer S it is left to its own map).
DEEPER = 4.0
# Rounds of pairwise merging (each merges a matching of neighbouring charts).
MERGE_ROUNDS = 15
# A union whose conformal map stretches beyond this many S: the charts around its two are not
# tried together again.
HOPELESS = 1.5
# Matchings of neighbouring chart pairs tested together in one merging round.
MERGE_LAYERS = 1


def mean_cap(C):
    """The largest area-weighted mean conformal distortion a chart's map may have at bound C:
    ``1 + MEAN_SLOPE * max(C - 1, 1)`` (1.07 at C = 2; a looser C relaxes it in proportion)."""
    return 1.0 + MEAN_SLOPE * max(float(C) - 1.0, 1.0)


def unwrap_auto(V, F, seams=None, bound=2.0, stretch=2.0, face_groups=None, merge=True,
                method="lscm", frames="auto", cone="soc", progress=None, cancel=None,
                polygons=None):
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
        ``seconds``
    """
    t0 = time.perf_counter()
    V, F = check_arrays(V, F)
    C, S = float(bound), float(stretch)
    if not (C >= 1.0 and S >= 1.0):
        raise ValueError(f"seams='auto' needs a bound C >= 1 and a stretch S >= 1, not {bound!r}, "
                         f"{stretch!r}")
    unwrap_options = dict(method=method, frames=frames, cone=cone, progress=progress,
                          cancel=cancel)
    E = edge_table(V, F, face_groups)
    n, m = len(V), len(F)
    poly, diag = _polygons(polygons, E, m)
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
    A = face_areas(V, F)
    cen = V[F].mean(axis=1)
    # Islands the seams cannot fix (non-manifold, degenerate, ...) are left to ``unwrap`` to
    # report; the rest of the search works on charts of the validated mesh.
    frozen = np.zeros(m, dtype=bool)
    if not _valid_everywhere(V, F, E, A):
        for i in islands(V, F, E.ends[cut]):
            if i.error is not None and not isinstance(i.error, (ClosedIslandError,
                                                                TopologyError)):
                frozen[i.faces] = True
    invalid = frozen.copy()
    rounds = 0
    for rounds in range(1, MAX_ROUNDS + 1):
        if cancel is not None and cancel.is_set():
            raise CancelledError("cancelled while placing seams")
        if progress is not None:
            progress(0.0, f"seams: round {rounds}, {int(frozen.sum())}/{m} faces in charts")
        # The charts the given seams make (round 1) keep a looser mean: a chart found by a
        # search on other triangles of the same polygons (the Blender operator's second pass)
        # must not be cut again for triangulation noise in its mean.
        changed = _refine(V, F, E, cut, frozen, A, cen, C, S, n, poly, diag,
                          cap=mean_cap(C) + GIVEN_SLACK * (mean_cap(C) - 1.0)
                          if rounds == 1 else mean_cap(C))
        if not changed:
            break
    if merge:
        _merge(V, F, E, cut, keep, invalid, S, C)
    # A chart whose certified map overlaps itself fails (rather than being cut by ``unwrap``
    # along whatever edges separate the overlap) and is split like the others; only the last
    # round lets ``unwrap`` cut what still overlaps.
    result = unwrap(V, F, seams=E.ends[cut], bound=C, raise_bound=False,
                    overlap="cut" if FINISH_ROUNDS == 0 else "fail", **unwrap_options)
    measured = None                         # (st, cr) of ``result`` on the current cut
    for finish in range(FINISH_ROUNDS):
        # Charts the certified map leaves beyond S or crossing itself are split again and only
        # their faces unwrapped anew.
        st, cr = measured = _measure(V, F, E, cut, result)
        bad = [r for r, s, c in zip(result.islands, st, cr)
               if len(r.faces) > 1 and ((r.status == "certified" and (s > S * (1 + 1e-9) or c))
                                        or isinstance(r.error, (InfeasibleError, SolverError,
                                                                OverlapError)))]
        if not bad:
            break
        measured = None
        frozen[:] = True
        group = np.full(m, -1, dtype=np.int64)
        for g, r in enumerate(bad):
            frozen[r.faces] = False
            group[r.faces] = g
        _bisect([np.sort(r.faces) for r in bad], E, cut, A, cen, poly)
        for _ in range(MAX_ROUNDS):
            if not _refine(V, F, E, cut, frozen, A, cen, C, S, n, poly, diag):
                break
        if merge:
            # The pieces may now merge with their neighbours (never with each other).
            _merge(V, F, E, cut, keep, invalid, S, C, group=group)
        # Unwrap anew every chart holding a piece (with the neighbours it took in).
        redo = np.zeros(m, dtype=bool)
        for c in charts(F, E, cut):
            if (group[c.faces] >= 0).any():
                redo[c.faces] = True
        sub = np.flatnonzero(redo)
        Fc, voc = cut_mesh(F, E, cut, sub)
        part = unwrap(V[voc], Fc[sub], bound=C, raise_bound=False,
                      overlap="cut" if finish == FINISH_ROUNDS - 1 else "fail", **unwrap_options)
        result = _splice(result, part, sub, voc, m)
    # Edges ``unwrap`` cut (overlaps left after the last round) are seams too.
    for r in result.islands:
        if r.cut_edges is not None and len(r.cut_edges):
            k = E.keys(r.cut_edges, n)
            cut[k[k >= 0]] = True
            measured = None
    st, cr = measured if measured is not None else _measure(V, F, E, cut, result)
    result = dataclasses.replace(result, seconds=time.perf_counter() - t0)
    added = E.ends[cut & ~original]
    info = {"charts": len(result.islands),
            "seam_length": float(E.length[cut].sum()),
            "added_length": float(E.length[cut & ~original].sum()),
            "edge_length": float(E.length.sum()),
            "max_stretch": st, "crossings": cr, "rounds": rounds,
            "seconds": result.seconds}
    return result, added, info


def _valid_everywhere(V, F, E, A):
    """Whether no island can fail ``mesh.islands``' validation (whatever the seams), checked
    on the whole mesh at once, so the search can skip ``islands`` (a few per cent of its time).

    Conservative: every coordinate finite, no face of zero area by ``mesh.islands``' test, no
    edge of three or more faces, every interior edge's two faces oriented alike, no two faces on
    the same three vertices, every vertex a single fan of corners. Where any fails (even a
    vertex fan ``mesh.islands`` would accept, joining two islands), ``islands`` decides.

    Parameters
    ----------
    V : (n,3) float64, F : (m,3) int64, E : edges.EdgeTable, A : (m,) float64 face areas

    Returns
    -------
    bool
    """
    P = V[F]
    if not np.isfinite(P).all():
        return False
    lmax2 = np.max(np.sum((P - np.roll(P, -1, axis=1)) ** 2, axis=2), axis=1)
    with np.errstate(invalid="ignore"):
        if not np.all(2 * A > DEGENERATE_RATIO * lmax2):
            return False
    if (np.bincount(E.face_edges.ravel(), minlength=len(E.ends)) > 2).any():
        return False
    c = E.corners[E.faces[:, 1] >= 0]
    nxt = lambda h: h - h % 3 + (h % 3 + 1) % 3
    if np.any((nxt(c[:, 0, 0]) == c[:, 0, 1]) == (nxt(c[:, 1, 0]) == c[:, 1, 1])):
        return False
    # Two faces on the same vertices share all three edges: each edge leads to the other.
    ef = E.faces[E.face_edges]                          # (m,3,2)
    me = np.arange(len(F))[:, None]
    other = np.where(ef[:, :, 0] == me, ef[:, :, 1], ef[:, :, 0])
    if np.any((other[:, 0] >= 0) & (other[:, 0] == other[:, 1]) & (other[:, 1] == other[:, 2])):
        return False
    _, voc = cut_mesh(F, E, np.zeros(len(E.ends), dtype=bool))
    return len(voc) == len(np.unique(F))


def _refine(V, F, E, cut, frozen, A, cen, C, S, n, poly=None, diag=None, cap=None):
    """One top-down round over the charts not yet accepted; True when a seam was added.

    Handles are cut first; the charts to split (closed spheres, open charts no cut graph
    changes, disks whose map fails) are all split in one batch (``_split_deep``). A disk passes
    with a mean distortion up to ``cap`` (default ``mean_cap(C)``).
    """
    sub = np.flatnonzero(~frozen)
    if len(sub) == 0:
        return False
    chs = charts(F, E, cut, sub)
    changed = False
    todo = []                               # (faces, the map's sigma per face or None)
    for c in chs:
        if c.kind == "open":                # handles, or several boundary loops
            w = lambda pairs, _v=c.vertices: _edge_weight(E, _v[pairs], n, diag)
            g = cut_graph(c.tris, len(c.vertices), w)
            k = E.keys(c.vertices[g], n) if len(g) else np.zeros(0, np.int64)
            k = k[k >= 0]
            if diag is not None:            # never inside a polygon (the split below instead)
                k = k[~diag[k]]
            if len(k) and not cut[k].all():
                cut[k] = True
                changed = True
                continue
        if c.kind in ("open", "sphere"):    # a sphere: split along its neck
            todo.append((c.faces, None))
    disks = [c for c in chs if c.kind == "disk"]
    if disks:
        cm = chart_maps(V, disks)
        cap = mean_cap(C) if cap is None else cap
        for j, c in enumerate(disks):
            ok = (np.isfinite(cm.max_distortion[j]) and cm.max_stretch[j] <= S * MARGIN
                  and cm.crossings[j] == 0 and cm.mean_distortion[j] <= cap)
            if ok or len(c.faces) < 2:
                frozen[c.faces] = True
            else:
                todo.append((c.faces, cm.sigma[cm.foff[j]:cm.foff[j + 1]]))
    if todo:
        split = _split_deep(todo, E, cut, A, cen, S, poly)
        for (faces, _), done in zip(todo, split):
            if not done:
                frozen[faces] = True
        changed |= bool(split.any())
    return changed


def _split_deep(todo, E, cut, A, cen, S, poly=None):
    """Split charts, and split their pieces again while a chart's conformal map restricted to a
    piece (``piece_stretch``: no new solve) still breaks S by the factor ``DEEPER``.

    A piece whose restricted map is nearer S is left for the next round to map on its own; the
    restriction saves the rounds (and solves) a chart far beyond S would take one split at a
    time. Pieces on flipped faces of the chart's map are left to their own map too. Every
    level splits all its pieces in one batch (``_bisect``).

    Parameters
    ----------
    todo : list of (faces (k,) int64 sorted global face ids, sigma (k,2) float64 or None): the
        charts, with their map's singular values per face (``ChartMaps.sigma``); None: split
        once

    Returns
    -------
    (len(todo),) bool, whether each chart was split
    """
    split = np.zeros(len(todo), dtype=bool)
    stack = [(faces, j) for j, (faces, _) in enumerate(todo)]
    for _ in range(SPLIT_DEPTH):
        sides = _bisect([f for f, _ in stack], E, cut, A, cen, poly)
        nxt = []
        for (f, j), two in zip(stack, sides):
            if two is None:
                continue
            split[j] = True
            faces, sigma = todo[j]
            if sigma is None:
                continue
            for piece in two:
                st = piece_stretch(sigma[np.searchsorted(faces, piece)], A[piece],
                                   np.zeros(len(piece), np.int64), 1)[0]
                if np.isfinite(st) and st > DEEPER * S * MARGIN and len(piece) > 1:
                    nxt.append((piece, j))
        stack = nxt
        if not stack:
            break
    return split


def _edge_weight(E, pairs, n, diag=None):
    """Cost of cutting each vertex pair (length times crease discount; inside a polygon, a
    million times that, so cut graphs run along polygon edges)."""
    k = E.keys(pairs, n)
    w = np.where(k >= 0, E.length[k] * E.cost[k], np.inf)
    if diag is not None:
        w = np.where((k >= 0) & diag[np.maximum(k, 0)], 1e6 * w, w)
    return w


def _polygons(polygons, E, m):
    """Checked polygon ids (m,) int64 (None without) and the edges inside a polygon (e,) bool."""
    diag = np.zeros(len(E.ends), dtype=bool)
    if polygons is None:
        return None, diag
    poly = np.asarray(polygons)
    if poly.shape != (m,) or not np.issubdtype(poly.dtype, np.integer):
        raise ValueError(f"polygons must be ({m},) integers, one polygon id per triangle, got "
                         f"shape {poly.shape} of {poly.dtype}")
    poly = poly.astype(np.int64)
    inner = E.faces[:, 1] >= 0
    diag[inner] = poly[E.faces[inner, 0]] == poly[E.faces[inner, 1]]
    return poly, diag


def _bisect(pieces, E, cut, A, cen, poly=None):
    """Split charts by ``fiedler_split_many`` (all at once) and mark the new seams.

    With ``poly`` (polygon of each face) the split runs on the polygons (each one node of the
    dual graph, its area and area-weighted centroid), so no polygon is cut.

    Parameters
    ----------
    pieces : list of (k_i,) int64, sorted global face ids of disjoint charts

    Returns
    -------
    list of (faces_a, faces_b) sorted global face ids of the two sides, or None where a chart
    is not split
    """
    out = [None] * len(pieces)
    if not pieces:
        return out
    m = len(E.face_edges)
    sizes = np.array([len(f) for f in pieces], dtype=np.int64)
    fa = np.concatenate(pieces)
    owner = np.repeat(np.arange(len(pieces)), sizes)
    local = np.full(m, -1, dtype=np.int64)
    local[fa] = np.arange(len(fa))
    fe = np.unique(E.face_edges[fa].ravel())
    fe = fe[(E.faces[fe, 1] >= 0) & ~cut[fe]]
    la, lb = local[E.faces[fe, 0]], local[E.faces[fe, 1]]
    inside = (la >= 0) & (lb >= 0)
    inside[inside] = owner[la[inside]] == owner[lb[inside]]
    fe, la, lb = fe[inside], la[inside], lb[inside]
    # Nodes: the faces, or the polygons (grouped by chart either way).
    if poly is None:
        node = np.arange(len(fa))
        mass, pcen = A[fa], cen[fa]
    else:
        key = owner * (int(poly.max()) + 1) + poly[fa]
        _, node = np.unique(key, return_inverse=True)
        node = node.ravel()
        mass = np.bincount(node, A[fa])
        pcen = np.stack([np.bincount(node, A[fa] * cen[fa, d]) for d in range(3)], 1)
        pcen /= np.maximum(mass, 1e-300)[:, None]
    nowner = np.zeros(len(mass), dtype=np.int64)
    nowner[node] = owner
    offsets = np.searchsorted(nowner, np.arange(len(pieces) + 1))
    na, nb = node[la], node[lb]
    across = na != nb
    side, split = fiedler_split_many(mass, pcen, offsets, np.stack([na[across], nb[across]], 1),
                                     E.length[fe[across]], E.cost[fe[across]])
    fside = side[node]
    new = fe[fside[la] != fside[lb]]
    cut[new[split[owner[local[E.faces[new, 0]]]]]] = True
    for j in np.flatnonzero(split):
        f = pieces[j]
        sj = fside[local[f]]
        out[j] = (f[sj], f[~sj])
    return out


def _merge(V, F, E, cut, keep, invalid, S, C, rounds=None, group=None):
    """Merge neighbouring charts pairwise while the union's conformal map still passes.

    Each round tests a matching of neighbouring pairs (dearest shared seam first: length times
    cost, so seams along creases are the last to go) in one
    batched solve; a pair that fails is not tried again while both charts stay as they are.

    Parameters
    ----------
    keep : (e,) bool, seams never removed (marked seams, material boundaries)
    S, C : float, a union passes with stretch within ``MARGIN`` S, mean distortion within
        ``mean_cap(C)``, no flipped face and no boundary crossing
    group : (m,) int64, optional: only pairs with a chart in a group (>= 0) are tried, and
        never two charts of one group (the pieces of a chart split because its certified map
        failed: their union is that chart again)
    """
    tried = set()
    # A face of each of two charts whose union was far beyond S: charts holding them are not
    # tried together again (a union of larger charts around them fares no better).
    far_a, far_b = [], []
    chs = charts(F, E, cut)
    original = keep
    for _ in range(MERGE_ROUNDS if rounds is None else rounds):
        label = np.empty(len(F), dtype=np.int64)
        for j, c in enumerate(chs):
            label[c.faces] = j
        ident = [(int(c.faces[0]), len(c.faces)) for c in chs]
        good = np.array([c.kind == "disk" and not invalid[c.faces[0]] for c in chs])
        inner = (E.faces[:, 1] >= 0) & cut & ~original
        la, lb = label[E.faces[inner, 0]], label[E.faces[inner, 1]]
        diff = (la != lb) & good[la] & good[lb]
        if group is not None:
            ga, gb = group[E.faces[inner, 0]], group[E.faces[inner, 1]]
            diff &= ((ga >= 0) | (gb >= 0)) & (ga != gb)
        if not diff.any():
            return
        ei = np.flatnonzero(inner)[diff]
        la, lb = np.minimum(la[diff], lb[diff]), np.maximum(la[diff], lb[diff])
        uk, inv = np.unique(la * len(chs) + lb, return_inverse=True)
        inv = inv.ravel()
        shared = np.bincount(inv, E.length[ei] * E.cost[ei])
        fa, fb = label[np.array(far_a, np.int64)], label[np.array(far_b, np.int64)]
        hopeless = np.isin(uk, np.minimum(fa, fb) * len(chs) + np.maximum(fa, fb))
        # Matchings ("layers"): dearest shared seam first, each chart in at most one pair of a
        # layer; every layer's unions are tested in one batched solve.
        used = np.zeros((MERGE_LAYERS, len(chs)), dtype=bool)
        layers = [[] for _ in range(MERGE_LAYERS)]
        for p in np.lexsort((uk, -_quantize(shared))):
            x, y = divmod(int(uk[p]), len(chs))
            if (ident[x], ident[y]) in tried or hopeless[p]:
                continue
            free = np.flatnonzero(~used[:, x] & ~used[:, y])
            if len(free) == 0:
                continue
            used[free[0], [x, y]] = True
            layers[free[0]].append(p)
            tried.add((ident[x], ident[y]))
        disks = []
        for lay, chosen in enumerate(layers):
            if not chosen:
                continue
            trial = cut.copy()
            trial[ei[np.isin(inv, chosen)]] = False
            faces = np.flatnonzero(used[lay][label])
            disks += [(c, trial) for c in charts(F, E, trial, faces)
                      if c.kind == "disk" and len(np.unique(label[c.faces])) == 2]
        if not disks:
            if not any(layers):
                return
            continue
        cm = chart_maps(V, [c for c, _ in disks])
        ok = (np.isfinite(cm.max_distortion) & (cm.max_stretch <= S * MARGIN)
              & (cm.crossings == 0) & (cm.mean_distortion <= mean_cap(C)))
        for j in np.flatnonzero(~(cm.max_stretch <= HOPELESS * S)):
            x, y = np.unique(label[disks[j][0].faces])
            far_a.append(int(chs[x].faces[0]))
            far_b.append(int(chs[y].faces[0]))
        merged = np.zeros(len(chs), dtype=bool)
        # Accept passing unions, dearest removed seam first, each chart merged once per round.
        fes = [np.unique(E.face_edges[c.faces].ravel()) for c, _ in disks]
        gain = np.array([(E.length * E.cost)[fe[cut[fe] & ~t[fe]]].sum()
                         for fe, (_, t) in zip(fes, disks)])
        unions = []
        for j in np.lexsort((np.arange(len(gain)), -_quantize(gain))):
            c, trial = disks[j]
            two = np.unique(label[c.faces])
            if not ok[j] or merged[two].any():
                continue
            merged[two] = True
            fe = fes[j]
            cut[fe[cut[fe] & ~trial[fe]]] = False
            unions.append(c)
        # The charts after this round: the unions (as found on the trial cut, which agrees with
        # the new cut on their faces) and every chart not merged, as they were.
        chs = sorted([c for j, c in enumerate(chs) if not merged[j]] + unions,
                     key=lambda ch: int(ch.faces[0]))


def _measure(V, F, E, cut, result):
    """Per island of a result: max stretch and boundary self-crossings from its final UVs."""
    isl = {int(c.faces[0]): c for c in charts(F, E, cut)}
    rs = [r for r in result.islands if r.uv is not None and r.status == "certified"]
    st = np.full(len(result.islands), np.nan)
    cr = np.zeros(len(result.islands), dtype=np.int64)
    if not rs:
        return st.tolist(), cr.tolist()
    nvs = np.array([len(r.vertices) for r in rs])
    nfs = np.array([len(r.tris) for r in rs])
    voff = np.concatenate([[0], np.cumsum(nvs)])
    foff = np.concatenate([[0], np.cumsum(nfs)])
    fc = np.repeat(np.arange(len(rs)), nfs)
    P = V[np.concatenate([r.vertices for r in rs])]
    uv = np.concatenate([r.uv for r in rs])
    tris = np.concatenate([r.tris for r in rs]) + voff[fc][:, None]
    corner = uv[tris]
    alpha, beta = face_jacobians(P, tris, corner)
    a, b = np.abs(alpha), np.abs(beta)
    e1 = corner[:, 1] - corner[:, 0]
    e2 = corner[:, 2] - corner[:, 0]
    uv_area = np.bincount(fc, 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]), len(rs))
    s = np.sqrt(np.bincount(fc, face_areas(P, tris), len(rs)) / np.maximum(uv_area, 1e-300))[fc]
    with np.errstate(divide="ignore", invalid="ignore"):
        fs = np.where(a > b, np.maximum(s * (a + b), 1.0 / (s * (a - b))), np.inf)
    idx = np.array([r.index for r in rs])
    st[idx] = np.maximum.reduceat(fs, foff[:-1])
    z = uv[:, 0] + 1j * uv[:, 1]
    cr[idx] = boundary_crossings(z, [_loop(isl.get(int(r.faces.min())), r) + voff[j]
                                     for j, r in enumerate(rs)])
    return st.tolist(), cr.tolist()


def _splice(result, part, sub, voc, m):
    """``result`` with the islands on faces ``sub`` replaced by ``part`` (unwrapped on F[sub])."""
    redo = np.zeros(m, dtype=bool)
    redo[sub] = True
    keep = [r for r in result.islands if not redo[r.faces[0]]]
    new = [dataclasses.replace(r, faces=sub[r.faces], vertices=voc[r.vertices],
                               cut_edges=None if r.cut_edges is None
                               else voc[np.asarray(r.cut_edges, np.int64).reshape(-1, 2)])
           for r in part.islands]
    isl = sorted(keep + new, key=lambda r: int(r.faces.min()))
    isl = [dataclasses.replace(r, index=j) for j, r in enumerate(isl)]
    corner_uv = result.corner_uv.copy()
    corner_uv[sub] = part.corner_uv
    face_island = np.empty(m, dtype=np.int64)
    for r in isl:
        face_island[r.faces] = r.index
    return UnwrapResult(corner_uv, face_island, isl, result.seconds + part.seconds, result.method)



def _loop(chart, r):
    """The boundary loop of ``chart`` in the vertex ids of the unwrap result ``r`` (same chart)."""
    if chart is None or not chart.loops or len(chart.faces) != len(r.faces):
        return np.zeros(0, dtype=np.int64)
    # Same faces, vertices numbered differently: map chart vertex -> result vertex by corner.
    pos = np.searchsorted(chart.faces, r.faces)
    ids = np.full(len(chart.vertices), -1, dtype=np.int64)
    ids[chart.tris[pos].ravel()] = r.tris.ravel()
    return ids[chart.loops[0]]
