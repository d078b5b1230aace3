"""Connected parts of a mesh that are copies of one another (a bolt placed 36 times): the seam
search (``auto.unwrap_auto``) runs on the first ``SEARCHED`` of them, and the seams of the one
with the fewest charts are copied onto the others, their maps with them.

A copy has the same faces as its original, vertex for vertex (each part's vertices numbered by
first appearance in its faces), the same given seams, materials and polygons, and positions that
a rotation, a uniform scale and a translation carry onto the original's within ``TOL`` of the
part's size. A mirror image is not a copy (its seam costs see its creases turned inside out).
The conformal maps, the charts' test and the certificate depend only on the triangles' shapes,
so the original's charts pass on the copy as they passed on the original, to rounding; the
final unwrap certifies every copy's charts all the same, on the copy's own positions, and the
finish rounds split any that fail there, as they do for every chart.
"""
import dataclasses
import hashlib

import numpy as np

from ..geometry import components
from .topology import charts

# Parts of fewer faces are searched where they are: their search costs no round of its own.
MIN_FACES = 16
# A copy's positions lie within this share of the part's RMS radius of the original's moved
# by the best similarity (Kabsch with a scale): the shader ball's 36 bolts, stored in an OBJ
# with 6 decimals, are copies within 6.4e-6. The copies' charts are certified on their own
# positions anyway: the tolerance decides only where the original's seams are reused.
TOL = 1e-4
# Originals a part is compared with among the parts of its faces and seams (beyond, it is an
# original itself).
MAX_ORIGINALS = 4
# Members of a class of copies searched: the one with the fewest charts (then the shortest
# seams) gives its seams to the others. The shader ball's 36 bolts, each searched, came out
# with 3, 4 or 5 charts (rounding differs with their placement; the first five with 5, the
# sixth with 3): 1 searched gave 188 charts in 190 ms of CPU, 6 gave 116 in 216 ms, all 36 (the
# search without copies: 162 charts in 418 ms) 116 in 415 ms. Each bolt searched costs ~5 ms.
SEARCHED = 6


@dataclasses.dataclass
class Copies:
    """Classes of parts that copy one another: per class, its members (part, vertices, faces),
    vertex for vertex and face for face (the faces ascending), the first ``SEARCHED`` of them
    searched; ``mask`` (m,) bool: the faces of the others (the search leaves them alone).
    ``part`` (n,) int64: the part of each vertex."""
    mask: np.ndarray
    classes: list
    part: np.ndarray

    def settle(self, F, E, cut, marks, given, known, chs, before=None):
        """After the search: in each class the searched member with the fewest charts (then
        the shortest seams, then the first) gives its seams to every other member, in place in
        ``cut`` and in every mask of ``marks`` ((e,) bool, e.g. the atlas's seams); the given
        seams (``given``) stay. ``chs``: the charts of ``cut`` (topology.Chart) or None.
        ``known``: the conformal maps by sorted faces' bytes; every member's charts get their
        source chart's.

        ``before``: the charts before the atlas's splits (``pack_shape``), optional: each of
        those splits adds one chart, so the members' counts give the splits copied.

        Returns
        -------
        (the charts of the new ``cut`` (None where ``chs`` is None), the atlas's splits added
        (copied onto members less those of searched members that lost; 0 without ``before``))
        """
        n = len(self.part)
        epart = self.part[E.ends[:, 0]]
        count = int(self.part.max()) + 1
        seam = np.bincount(epart[cut], E.length[cut], minlength=count)
        def per_part(cs):
            return np.bincount(self.part[F[[int(c.faces[0]) for c in cs], 0]], minlength=count)
        charts_of = per_part(chs) if chs is not None else np.zeros(count, dtype=np.int64)
        splits = charts_of - per_part(before) if chs is not None and before is not None else \
            np.zeros(count, dtype=np.int64)
        added = 0
        redo = np.zeros(len(F), dtype=bool)
        pairs = []
        for members in self.classes:
            searched = members[:SEARCHED]
            best = min(range(len(searched)), key=lambda j: (
                int(charts_of[searched[j][0]]), round(float(seam[searched[j][0]]), 9), j))
            src = members[best]
            for j, dst in enumerate(members):
                if j == best:
                    continue
                if j < SEARCHED:                # searched, not the source: its seams go
                    mine = epart == dst[0]
                    cut[mine] = given[mine]
                    for mk in marks:
                        mk[mine] = False
                redo[dst[2]] = True
                pairs.append((src, dst))
                added += int(splits[src[0]]) - (int(splits[dst[0]]) if j < SEARCHED else 0)
        where = np.full(n, -1, dtype=np.int64)
        for mk in [cut] + list(marks):
            on = np.flatnonzero(mk)
            src_part = epart[on]
            for (p, orig, _), (_, copy, _) in pairs:
                ends = E.ends[on[src_part == p]].astype(np.int64)
                if not len(ends):
                    continue
                where[orig] = np.arange(len(orig))
                k = E.keys(copy[where[ends]], n)
                mk[k[k >= 0]] = True
        if chs is None:
            return None, added
        for c in chs:                       # the maps of charts whose seams went
            if redo[c.faces[0]]:
                known.pop(c.faces.tobytes(), None)
        chs = sorted([c for c in chs if not redo[c.faces[0]]]
                     + charts(F, E, cut, np.flatnonzero(redo)), key=lambda c: int(c.faces[0]))
        first = {int(c.faces[0]): c for c in chs}
        starts = np.array(sorted(first), dtype=np.int64)
        for (_, _, of), (_, _, cf) in pairs:
            for f in of[np.isin(of, starts)].tolist():
                oc = first[f]
                u = known.get(oc.faces.tobytes())
                cc = first.get(int(cf[np.searchsorted(of, f)]))
                if u is None or cc is None or len(cc.faces) != len(oc.faces):
                    continue
                # The same triangle shapes: the map the final unwrap would solve, to rounding
                # (it certifies the copy from its own positions).
                w = np.empty(len(cc.vertices), dtype=u.dtype)
                w[cc.tris.ravel()] = u[oc.tris.ravel()]
                known[cc.faces.tobytes()] = w
        return chs, added


def find_copies(V, F, E, cut, face_groups=None, polygons=None, invalid=None):
    """The parts of (V, F) that copy another part, or None when there are none.

    ``cut``: (e,) bool, the given seams (a copy has the same ones); ``face_groups``,
    ``polygons``: (m,) int arrays or None (a copy has the same materials and polygons);
    ``invalid``: (m,) bool or None, faces of islands left to ``unwrap`` to report: their parts
    are searched where they are (whether a face is degenerate may differ between copies).

    Returns
    -------
    Copies or None
    """
    n, m = len(V), len(F)
    if m < 2 * MIN_FACES:
        return None
    count, part = components(n, E.ends[:, 0], E.ends[:, 1])
    if count < 2:
        return None
    F = np.asarray(F, dtype=np.int64)
    fpart = part[F[:, 0]]
    nf = np.bincount(fpart, minlength=count)
    used = np.zeros(n, dtype=bool)
    used[F.ravel()] = True
    nv = np.bincount(part[used], minlength=count)
    size = nf * (n + 1) + nv
    _, inv, times = np.unique(size, return_inverse=True, return_counts=True)
    ok = (nf >= MIN_FACES) & (times[inv.ravel()] > 1)
    if invalid is not None and invalid.any():
        ok[fpart[invalid]] = False
    cand = np.flatnonzero(ok)
    if not len(cand):
        return None
    order = np.argsort(fpart, kind="stable")
    start = np.concatenate([[0], np.cumsum(nf)])
    seam = np.flatnonzero(cut)
    spart = fpart[E.faces[seam, 0]]
    groups = {}
    for p in cand.tolist():
        fc = order[start[p]:start[p + 1]]
        corners = F.take(fc, axis=0).ravel()
        uniq, first, inv = np.unique(corners, return_index=True, return_inverse=True)
        by_first = np.argsort(first, kind="stable")
        rank = np.empty(len(uniq), dtype=np.int64)
        rank[by_first] = np.arange(len(uniq))
        verts = uniq[by_first]
        h = hashlib.blake2b(rank[inv.ravel()].tobytes(), digest_size=16)
        if face_groups is not None:
            h.update(np.asarray(face_groups)[fc].astype(np.int64).tobytes())
        if polygons is not None:
            _, pf, pinv = np.unique(np.asarray(polygons)[fc], return_index=True,
                                    return_inverse=True)
            pr = np.empty(len(pf), dtype=np.int64)
            pr[np.argsort(pf, kind="stable")] = np.arange(len(pf))
            h.update(b"p" + pr[pinv.ravel()].tobytes())
        mine = E.ends[seam[spart == p]].astype(np.int64)
        if len(mine):
            loc = rank[np.searchsorted(uniq, mine)]
            loc = np.sort(loc, axis=1)
            loc = loc[np.lexsort((loc[:, 1], loc[:, 0]))]
            h.update(b"s" + loc.tobytes())
        groups.setdefault((int(size[p]), h.digest()), []).append((p, verts))
    mask = np.zeros(m, dtype=bool)
    classes = []
    for members in groups.values():
        found = []                          # classes of congruent members
        for p, verts in members:
            Y = V[verts]
            own = next((c for c in found[:MAX_ORIGINALS] if _congruent(V[c[0][1]], Y)), None)
            faces = order[start[p]:start[p + 1]]
            if own is None:
                found.append([(p, verts, faces)])
            else:
                if len(own) >= SEARCHED:
                    mask[faces] = True
                own.append((p, verts, faces))
        classes += [c for c in found if len(c) > 1]
    if not classes:
        return None
    return Copies(mask, classes, part)


def _congruent(X, Y):
    """Whether a rotation (no reflection), a uniform scale and a translation carry X onto Y
    within ``TOL`` of Y's RMS radius (row for row)."""
    xc = X - X.mean(axis=0)
    yc = Y - Y.mean(axis=0)
    sx, sy = float((xc * xc).sum()), float((yc * yc).sum())
    if not (sx > 0 and sy > 0):
        return False
    U, s, Wt = np.linalg.svd(xc.T @ yc)
    R = U @ Wt
    if np.linalg.det(R) <= 0:
        return False
    scale = float(s.sum()) / sx
    return float(np.abs(scale * (xc @ R) - yc).max()) <= TOL * np.sqrt(sy / len(Y))
