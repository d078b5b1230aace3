"""``seams="auto"``: cut every island that cannot be certified as it is into certified charts.

Top-down: a chart that is not a disk is opened by its handle cuts (``cut_graph``), a closed
sphere and a disk whose conformal map breaks a bound are split along their cheapest neck
(``fiedler_split``), until every chart's conformal map (LSCM) is flip-free with stretch within S
and a boundary that does not cross itself. Then bottom-up: neighbouring charts are merged while
the union still passes. ``bd_uv.unwrap`` finally certifies every chart at C (bending the few
whose conformal map exceeds C), and any chart the certified map leaves beyond S or crossing
itself is split again.
"""
import time

import numpy as np

from ..errors import ClosedIslandError, TopologyError
from ..geometry import face_areas
from ..metrics import face_jacobians
from ..mesh import check_arrays, islands
from ..unwrapping.unwrap import unwrap
from .charts import boundary_crossings, chart_maps
from .cut_graph import cut_graph
from .edges import edge_table
from .split import fiedler_split

MAX_ROUNDS = 60


def unwrap_auto(V, F, seams=None, bound=2.0, stretch=2.0, face_groups=None, merge=True,
                **unwrap_options):
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
    **unwrap_options : passed to ``bd_uv.unwrap`` (method, cone, progress, cancel, ...)

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
    result = None
    for _ in range(8):
        result = unwrap(V, F, seams=E.ends[cut], bound=C, raise_bound=False, **unwrap_options)
        st, cr = _measure(V, F, result, E.ends[cut])
        bad = [r for r, s, c in zip(result.islands, st, cr)
               if r.status == "certified" and (s > S * (1 + 1e-9) or c > 0)]
        bad += [r for r in result.islands if r.status != "certified"
                and isinstance(r.error, type(None)) is False and len(r.faces) > 1
                and not isinstance(r.error, (ClosedIslandError, TopologyError))
                and type(r.error).__name__ in ("InfeasibleError", "SolverError")]
        if not bad:
            break
        frozen[:] = True
        for r in bad:
            frozen[r.faces] = False
            _split_faces(r.faces, E, cut, A, cen)
        for _ in range(MAX_ROUNDS):
            if not _refine(V, F, E, cut, frozen, A, cen, C, S, n):
                break
    st, cr = _measure(V, F, result, E.ends[cut])
    added = E.ends[cut & ~original]
    info = {"charts": len(result.islands),
            "seam_length": float(E.length[cut].sum()),
            "added_length": float(E.length[cut & ~original].sum()),
            "edge_length": float(E.length.sum()),
            "max_stretch": st, "crossings": cr, "rounds": rounds,
            "seconds": time.perf_counter() - t0}
    return result, added, info


def _refine(V, F, E, cut, frozen, A, cen, C, S, n):
    """One top-down round over the charts not yet accepted; True when a seam was added."""
    isl = islands(V, F, E.ends[cut])
    open_, disks = [], []
    for i in isl:
        if frozen[i.faces[0]]:
            continue
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
            ok = (np.isfinite(cm.max_distortion[j]) and cm.max_stretch[j] <= S
                  and cm.crossings[j] == 0)
            if ok or len(i.faces) < 2:
                frozen[i.faces] = True
            elif _split_faces(i.faces, E, cut, A, cen):
                changed = True
            else:
                frozen[i.faces] = True
    return changed


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


def _merge(V, F, E, cut, original, C, S, n, rounds=6):
    """Merge neighbouring charts pairwise while the union's conformal map still passes."""
    for _ in range(rounds):
        isl = islands(V, F, E.ends[cut])
        label = np.empty(len(F), dtype=np.int64)
        for i in isl:
            label[i.faces] = i.index
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
        # Greedy matching: longest shared boundary first, each chart in at most one pair.
        order = np.argsort(-shared)
        used = np.zeros(len(isl), dtype=bool)
        chosen = []
        for p in order:
            x, y = divmod(int(uk[p]), len(isl))
            if not used[x] and not used[y]:
                used[x] = used[y] = True
                chosen.append(p)
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
            return
        cm = chart_maps(V, disks)
        ok = np.isfinite(cm.max_distortion) & (cm.max_stretch <= S) & (cm.crossings == 0)
        merged = 0
        for j, c in enumerate(disks):
            if not ok[j]:
                continue
            fe = np.unique(E.face_edges[c.faces].ravel())
            both = (E.faces[fe, 1] >= 0)
            f0, f1 = E.faces[fe, 0], E.faces[fe, 1]
            inside = both & (tlabel[f0] == c.index) & (tlabel[np.where(both, f1, 0)] == c.index)
            kill = fe[inside & cut[fe] & ~trial[fe]]
            cut[kill] = False
            merged += 1
        if merged == 0:
            return


def _measure(V, F, result, seams):
    """Per island of a result: max stretch and boundary self-crossings from its final UVs."""
    st, cr = [], []
    isl = islands(V, F, seams)
    for r in result.islands:
        if r.uv is None or r.status != "certified":
            st.append(float("nan"))
            cr.append(0)
            continue
        uv = r.uv[:, 0] + 1j * r.uv[:, 1]
        P = V[r.vertices]
        corner = r.uv[r.tris]
        alpha, beta = face_jacobians(P, r.tris, corner)
        a, b = np.abs(alpha), np.abs(beta)
        s = np.sqrt(face_areas(P, r.tris).sum() / max(_uv_area(corner), 1e-300))
        with np.errstate(divide="ignore", invalid="ignore"):
            st.append(float(np.max(np.maximum(s * (a + b), 1.0 / (s * (a - b))))))
        cr.append(int(boundary_crossings(uv, list(isl[r.index].loops)).sum()))
    return st, cr


def _uv_area(corner):
    e1 = corner[:, 1] - corner[:, 0]
    e2 = corner[:, 2] - corner[:, 0]
    return float(0.5 * np.sum(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]))
