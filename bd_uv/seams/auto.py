"""``seams="auto"``: cut every island that cannot be certified as it is into certified charts.

Top-down: a chart that is not a disk is opened by its handle cuts (``cut_graph``), a closed
sphere and a disk whose conformal map breaks a bound are split along their cheapest neck
(``fiedler_split``), until every chart's conformal map (LSCM) is flip-free with stretch within S
and a boundary that does not cross itself. Then bottom-up: neighbouring charts are merged while
the union still passes. ``bd_uv.unwrap`` finally certifies every chart at C (bending the few
whose conformal map exceeds C), and any chart the certified map leaves beyond S or crossing
itself is split again.
"""
import dataclasses
import time

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..errors import ClosedIslandError, InfeasibleError, SolverError, TopologyError
from ..geometry import face_areas
from ..metrics import face_jacobians
from ..mesh import check_arrays, islands
from ..unwrapping.results import UnwrapResult
from ..unwrapping.unwrap import unwrap
from .charts import boundary_crossings, chart_maps
from .cut_graph import cut_graph
from .edges import edge_table
from .split import fiedler_split

MAX_ROUNDS = 60
# Charts are accepted a little inside S: bending a map into C moves its stretch slightly.
MARGIN = 0.98
# Passes that split charts the certified map leaves beyond S.
FINISH_ROUNDS = 4
# Rounds of pairwise merging (each merges a matching of neighbouring charts).
MERGE_ROUNDS = 40


def unwrap_auto(V, F, seams=None, bound=2.0, stretch=2.0, face_groups=None, merge=True,
                method="lscm", frames="auto", cone="soc", progress=None, cancel=None):
    """Unwrap with seams added where needed: every chart a disk, certified at C, stretch <= S.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array
    seams : (s,2) int array, optional, vertex pairs of existing seams (all kept)
    bound : float, C: conformal distortion of every face at most C (Lipman 2012, eq. 4.9)
    stretch : float, S: every face's singular values within [1/S, S] with each chart scaled to
        its 3D area (section 6.3's bounds, ``max(sigma_1, 1/sigma_2) <= S``)
    face_groups : (m,) int array, optional, material per face: seams prefer group boundaries
    merge : bool, merge neighbouring charts while their union passes
    method, frames, cone, progress, cancel : as for ``bd_uv.unwrap``, which certifies the charts
        (with ``raise_bound=False``: a chart that cannot be certified at C is split further)

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
    cut = np.zeros(len(E.ends), dtype=bool)
    if seams is not None and len(seams):
        k = E.keys(seams, n)
        cut[k[k >= 0]] = True
    cut[E.faces[:, 1] < 0] = False
    original = cut.copy()
    A = face_areas(V, F)
    cen = V[F].mean(axis=1)
    frozen = np.zeros(m, dtype=bool)
    rounds = 0
    for rounds in range(1, MAX_ROUNDS + 1):
        changed = _refine(V, F, E, cut, frozen, A, cen, C, S, n)
        if not changed:
            break
    if merge:
        _merge(V, F, E, cut, original, C, S, n)
    result = unwrap(V, F, seams=E.ends[cut], bound=C, raise_bound=False, **unwrap_options)
    for _ in range(FINISH_ROUNDS):
        # Charts the certified map leaves beyond S or crossing itself are split again and only
        # their faces unwrapped anew.
        st, cr = _measure(V, F, result, E.ends[cut])
        bad = [r for r, s, c in zip(result.islands, st, cr)
               if len(r.faces) > 1 and ((r.status == "certified" and (s > S * (1 + 1e-9) or c))
                                        or isinstance(r.error, (InfeasibleError, SolverError)))]
        if not bad:
            break
        frozen[:] = True
        for r in bad:
            frozen[r.faces] = False
            _split_faces(r.faces, E, cut, A, cen)
        sub = np.flatnonzero(~frozen)
        for _ in range(MAX_ROUNDS):
            if not _refine(V, F, E, cut, frozen, A, cen, C, S, n):
                break
        Fc, voc = cut_mesh(F, E, cut)
        part = unwrap(V[voc], Fc[sub], bound=C, raise_bound=False, **unwrap_options)
        result = _splice(result, part, sub, voc, m)
    st, cr = _measure(V, F, result, E.ends[cut])
    result = dataclasses.replace(result, seconds=time.perf_counter() - t0)
    added = E.ends[cut & ~original]
    info = {"charts": len(result.islands),
            "seam_length": float(E.length[cut].sum()),
            "added_length": float(E.length[cut & ~original].sum()),
            "edge_length": float(E.length.sum()),
            "max_stretch": st, "crossings": cr, "rounds": rounds,
            "seconds": result.seconds}
    return result, added, info


def _refine(V, F, E, cut, frozen, A, cen, C, S, n):
    """One top-down round over the charts not yet accepted; True when a seam was added."""
    # Only the faces not yet accepted: accepted charts are cut off from them by seams.
    sub = np.flatnonzero(~frozen)
    if len(sub) == 0:
        return False
    Fc, voc = cut_mesh(F, E, cut)
    isl = [_Chart(i, sub[i.faces], voc) for i in islands(V[voc], Fc[sub])]
    open_, disks = [], []
    for i in isl:
        if isinstance(i.error, (ClosedIslandError, TopologyError)) or (
                i.error is None and len(i.loops) > 1):
            open_.append(i)
        elif i.error is None:
            disks.append(i)
        else:                              # degenerate, non-manifold, ...: not ours to fix
            frozen[i.faces] = True
    changed = False
    for i in open_:
        w = lambda pairs, _v=i.vertices: _edge_weight(E, _v[pairs], n)
        c = cut_graph(i.tris, len(i.vertices), w)
        k = E.keys(i.vertices[c], n) if len(c) else np.zeros(0, np.int64)
        k = k[k >= 0]
        if len(k) and not cut[k].all():
            cut[k] = True
            changed = True
        elif _split_faces(i.faces, E, cut, A, cen):   # a sphere: split along its neck
            changed = True
        else:
            frozen[i.faces] = True
    if disks:
        cm = chart_maps(V, disks)
        for j, i in enumerate(disks):
            ok = (np.isfinite(cm.max_distortion[j]) and cm.max_stretch[j] <= S * MARGIN
                  and cm.crossings[j] == 0)
            if ok or len(i.faces) < 2:
                frozen[i.faces] = True
            elif _split_faces(i.faces, E, cut, A, cen):
                changed = True
            else:
                frozen[i.faces] = True
    return changed


class _Chart:
    """An island of a face subset, with its faces as input face ids."""

    def __init__(self, island, faces, voc):
        self.faces = faces
        self.vertices, self.tris, self.loops = voc[island.vertices], island.tris, island.loops
        self.error = island.error


def _edge_weight(E, pairs, n):
    k = E.keys(pairs, n)
    return np.where(k >= 0, E.length[k] * E.cost[k], np.inf)


def _split_faces(faces, E, cut, A, cen):
    """Split a chart (global face ids) by ``fiedler_split``; mark the new seams. True if split."""
    m = len(E.face_edges)
    local = np.full(m, -1, dtype=np.int64)
    local[faces] = np.arange(len(faces))
    fe = np.unique(E.face_edges[faces].ravel())
    fe = fe[(E.faces[fe, 1] >= 0) & ~cut[fe]]
    la, lb = local[E.faces[fe, 0]], local[E.faces[fe, 1]]
    inside = (la >= 0) & (lb >= 0)
    fe, pairs = fe[inside], np.stack([la[inside], lb[inside]], axis=1)
    side = fiedler_split(A[faces], cen[faces], pairs, E.length[fe], E.cost[fe])
    if side is None:
        return False
    new = fe[side[pairs[:, 0]] != side[pairs[:, 1]]]
    cut[new] = True
    return len(new) > 0


def _merge(V, F, E, cut, original, C, S, n, rounds=MERGE_ROUNDS):
    """Merge neighbouring charts pairwise while the union's conformal map still passes.

    Each round tests a matching of neighbouring pairs (longest shared seam first) in one
    batched solve; pairs that fail are not tried again while both charts stay as they are.
    """
    tried = set()
    for _ in range(rounds):
        isl = islands(V, F, E.ends[cut])
        label = np.empty(len(F), dtype=np.int64)
        for i in isl:
            label[i.faces] = i.index
        ident = [(int(i.faces[0]), len(i.faces)) for i in isl]
        good = np.array([i.error is None and len(i.loops) == 1 for i in isl])
        inner = (E.faces[:, 1] >= 0) & cut & ~original
        la, lb = label[E.faces[inner, 0]], label[E.faces[inner, 1]]
        diff = (la != lb) & good[la] & good[lb]
        if not diff.any():
            return
        ei = np.flatnonzero(inner)[diff]
        la, lb = np.minimum(la[diff], lb[diff]), np.maximum(la[diff], lb[diff])
        key = la * len(isl) + lb
        uk, inv = np.unique(key, return_inverse=True)
        shared = np.bincount(inv.ravel(), E.length[ei])
        # Greedy matching: longest shared seam first, each chart in at most one pair.
        order = np.argsort(-shared)
        used = np.zeros(len(isl), dtype=bool)
        chosen = []
        for p in order:
            x, y = divmod(int(uk[p]), len(isl))
            if not used[x] and not used[y] and (ident[x], ident[y]) not in tried:
                used[x] = used[y] = True
                chosen.append(p)
                tried.add((ident[x], ident[y]))
        if not chosen:
            return
        trial = cut.copy()
        pick = np.isin(inv.ravel(), chosen)
        trial[ei[pick]] = False
        tis = islands(V, F, E.ends[trial])
        tlabel = np.empty(len(F), dtype=np.int64)
        for i in tis:
            tlabel[i.faces] = i.index
        cand = [tis[tlabel[i.faces[0]]] for i in isl if used[i.index]]
        cand = list({c.index: c for c in cand}.values())
        disks = [c for c in cand if c.error is None and len(c.loops) == 1]
        if not disks:
            continue
        cm = chart_maps(V, disks)
        ok = np.isfinite(cm.max_distortion) & (cm.max_stretch <= S * MARGIN) & (cm.crossings == 0)
        for j, c in enumerate(disks):
            if not ok[j]:
                continue
            fe = np.unique(E.face_edges[c.faces].ravel())
            both = (E.faces[fe, 1] >= 0)
            f0, f1 = E.faces[fe, 0], E.faces[fe, 1]
            inside = both & (tlabel[f0] == c.index) & (tlabel[np.where(both, f1, 0)] == c.index)
            cut[fe[inside & cut[fe] & ~trial[fe]]] = False


def _measure(V, F, result, seams):
    """Per island of a result: max stretch and boundary self-crossings from its final UVs."""
    isl = islands(V, F, seams)
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
    cr[idx] = boundary_crossings(z, [isl[r.index].loops[0] + voff[j] for j, r in enumerate(rs)])
    return st.tolist(), cr.tolist()


def _splice(result, part, sub, voc, m):
    """``result`` with the islands on faces ``sub`` replaced by ``part`` (unwrapped on F[sub])."""
    redo = np.zeros(m, dtype=bool)
    redo[sub] = True
    keep = [r for r in result.islands if not redo[r.faces[0]]]
    new = [dataclasses.replace(r, faces=sub[r.faces], vertices=voc[r.vertices])
           for r in part.islands]
    isl = sorted(keep + new, key=lambda r: int(r.faces.min()))
    isl = [dataclasses.replace(r, index=j) for j, r in enumerate(isl)]
    corner_uv = result.corner_uv.copy()
    corner_uv[sub] = part.corner_uv
    face_island = np.empty(m, dtype=np.int64)
    for r in isl:
        face_island[r.faces] = r.index
    return UnwrapResult(corner_uv, face_island, isl, result.seconds + part.seconds, result.method)


def cut_mesh(F, E, cut):
    """The mesh cut open along the seams: a face subset of it keeps the charts' own topology.

    Parameters
    ----------
    F : (m,3) int64
    E : EdgeTable
    cut : (e,) bool, the seams

    Returns
    -------
    Fc : (m,3) int64, faces in cut vertex ids (corners glued across uncut interior edges only)
    voc : (nc,) int64, the input vertex of each cut vertex
    """
    m = len(F)
    join = (E.faces[:, 1] >= 0) & ~cut
    f0, f1 = E.faces[join, 0], E.faces[join, 1]
    rows, cols = [], []
    for end in (0, 1):
        v = E.ends[join, end]
        c0 = f0 * 3 + np.argmax(F[f0] == v[:, None], axis=1)
        c1 = f1 * 3 + np.argmax(F[f1] == v[:, None], axis=1)
        rows.append(c0)
        cols.append(c1)
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    g = sp.coo_array((np.ones(len(rows)), (rows, cols)), shape=(3 * m, 3 * m))
    _, corner = connected_components(g, directed=False)
    voc = np.empty(corner.max() + 1, dtype=np.int64)
    voc[corner] = F.ravel()
    return corner.reshape(m, 3).astype(np.int64), voc
