"""Robust predicates on planar segments: which of many segments intersect or touch.

Orientation signs in float64 where each is clear of its rounding error bound (Shewchuk's
``ccwerrboundA``), GEOS's robust predicate (``shapely.intersects``) where one is not; candidate
pairs from a bounding-box table (few segments), a sweep along x, or ``shapely.STRtree``. Used by
the UV boundary's overlap certificate (``overlap.py``), the one-disk certificate and the live
certificate.
"""
import numpy as np


# Up to this many boundary segments every pair is tested (2016 pairs at 64) rather than the
# candidates of an STRtree, whose set-up costs more than the pairs below it.
ALL_PAIRS = 64
# Candidate pairs ``touching_pairs`` forms by its sweep along x, at most, per segment (beyond,
# an STRtree finds them).
SWEEP_PAIRS = 32
# ... and at most this many in all (~10 arrays of them at once, 20 MB): a large mesh's boundary
# goes to the tree, whose memory was measured on the 500k-face meshes.
SWEEP_MAX = 1 << 18
# Candidate pairs group_pairs_touching asks the tree for at a time (~100 MB of them).
CANDIDATES = 2_000_000


def cross(u, v):
    """z of the cross product of rows of (k,2) arrays."""
    return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]


def _orient(a, b, c):
    """Twice the signed area of (a, b, c) and a bound on its rounding error (Shewchuk's
    ``ccwerrboundA`` is 3.3e-16 times the same sum; 1e-15 leaves room)."""
    l = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1])
    r = (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    return l - r, 1e-15 * (np.abs(l) + np.abs(r))


def touching_pairs(p, q, group=None):
    """Pairs of segments that intersect or touch, each pair once (i < j).

    Bounding-box candidates come from a sweep along x (``_box_pairs``; every pair up to
    ``ALL_PAIRS`` segments, ``shapely.STRtree`` where the sweep would form more than
    ``SWEEP_PAIRS`` pairs a segment or ``SWEEP_MAX`` in all); each candidate is decided by the four
    orientation signs in float64 when all four are clear of their rounding error bound, and by
    GEOS's robust predicate otherwise (touching, collinear and near-degenerate pairs). Segments
    with an identical end touch.

    Parameters
    ----------
    p, q : (b,2) float arrays, segment ends
    group : (b,) int array, optional: only pairs within one group are wanted (the segments of
        each island). Many islands stacked at (0, 0) would otherwise make every pair of islands a
        candidate (1000 islands: 21 s); the candidates are then searched among the segments'
        boxes moved apart group by group, and decided on the segments themselves.

    Returns
    -------
    (k,2) int64
    """
    p = np.asarray(p, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    if len(p) < 2:
        return np.zeros((0, 2), dtype=np.int64)
    if len(p) <= ALL_PAIRS:
        # Few segments (a small island): every pair's boxes are compared at once, no tree to
        # build; the same candidates as the tree's, decided alike (segments whose boxes are
        # apart cannot meet).
        lo, hi = np.minimum(p, q), np.maximum(p, q)
        # boxes that meet (touching included), as the tree's candidates; then one island's:
        # the (b, b) table at once, its upper triangle read off (pairs i < j, by i then j)
        x0, y0, x1, y1 = lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1]
        keep = x0[:, None] <= x1[None, :]
        keep &= x0[None, :] <= x1[:, None]
        keep &= y0[:, None] <= y1[None, :]
        keep &= y0[None, :] <= y1[:, None]
        if group is not None:
            g = np.asarray(group)
            keep &= g[:, None] == g[None, :]
        i, j = np.nonzero(np.triu(keep, 1))
        meets = segments_meet(p, q, i, j)
        return np.stack([i[meets], j[meets]], axis=1).astype(np.int64)
    lo, hi = np.minimum(p, q), np.maximum(p, q)
    pairs = _box_pairs(lo, hi, group, min(SWEEP_PAIRS * len(p) + 4096, SWEEP_MAX))
    if pairs is not None:
        i, j = pairs
        meets = segments_meet(p, q, i, j)
        return np.stack([i[meets], j[meets]], axis=1)
    import shapely
    geoms = shapely.linestrings(np.stack([p, q], axis=1))
    if group is None:
        boxes = geoms
    else:  # boxes moved apart island by island: candidates only within one island
        span = float(np.max(hi) - np.min(lo)) + 1.0
        pad = 1e-9 * span                      # far above the rounding of the moved boxes
        off = np.asarray(group, dtype=np.float64) * (4.0 * span)
        boxes = shapely.box(lo[:, 0] - pad + off, lo[:, 1] - pad, hi[:, 0] + pad + off,
                            hi[:, 1] + pad)
    i, j = shapely.STRtree(boxes).query(boxes)
    keep = i < j
    i, j = i[keep].astype(np.int64), j[keep].astype(np.int64)
    meets = segments_meet(p, q, i, j, geoms)
    return np.stack([i[meets], j[meets]], axis=1)


def _box_pairs(lo, hi, group, limit):
    """The pairs (i < j, by i then j) of segments whose bounding boxes ``lo``-``hi`` meet
    (touching included; within one ``group`` where given), by a sweep along x: the segments by
    group and least x, each against those starting from its own least x up to its largest (a
    search on the x ranks), then the y ranges compared. Only comparisons of the ends'
    coordinates, no arithmetic: every pair of segments that meet is among them, as among an
    STRtree's candidates. None where more than ``limit`` x-overlapping pairs would be formed
    (a boundary running back and forth along x): the tree takes those."""
    b = len(lo)
    g = np.zeros(b, dtype=np.int64) if group is None else np.asarray(group, dtype=np.int64)
    # Exact ranks of every least and largest x (ties equal), so the sweep's keys are integers.
    _, rank = np.unique(np.concatenate([lo[:, 0], hi[:, 0]]), return_inverse=True)
    rank = rank.ravel()
    width = int(rank.max()) + 1
    if len(g) and int(g.max()) - int(g.min()) >= b:    # any ids: numbered 0.. (no overflow)
        g = np.unique(g, return_inverse=True)[1].ravel()
    else:
        g = g - g.min(initial=0)
    k0 = g * width + rank[:b]
    k1 = g * width + rank[b:]
    order = k0.argsort(kind="stable")
    s0 = k0[order]
    end = s0.searchsorted(k1[order], side="right")
    count = end - np.arange(b) - 1          # the later segments starting within its x range
    total = int(count.sum())
    if total > limit:
        return None
    first = np.repeat(np.arange(b), count)
    second = np.arange(total) - np.repeat(np.cumsum(count) - count, count) + first + 1
    a, c = order[first], order[second]
    keep = (lo[c, 1] <= hi[a, 1]) & (lo[a, 1] <= hi[c, 1])
    i, j = np.minimum(a[keep], c[keep]), np.maximum(a[keep], c[keep])
    by = np.lexsort((j, i))
    return i[by].astype(np.int64), j[by].astype(np.int64)


def group_pairs_touching(p, q, group, chunk=CANDIDATES):
    """Pairs of groups (islands) with a segment of one meeting a segment of the other, each pair
    once (a < b), sorted: ``touching_pairs`` read off as groups, in bounded memory.

    The tree is asked for a few segments at a time (about ``chunk`` candidates), and a candidate
    of a pair of groups already found to meet is not decided again: islands left stacked where
    their unwraps put them (``--no-pack``) make nearly every pair of segments a candidate
    (trimesh's quadknot.obj, 1,438 islands: 1.6 GB for the segment pairs at once).

    Returns
    -------
    (k,2) int64
    """
    import shapely
    p = np.asarray(p, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    group = np.asarray(group, dtype=np.int64)
    if len(p) <= ALL_PAIRS:
        pairs = touching_pairs(p, q)
        ga, gb = group[pairs[:, 0]], group[pairs[:, 1]]
        out = np.stack([np.minimum(ga, gb), np.maximum(ga, gb)], axis=1)[ga != gb]
        return np.unique(out, axis=0) if len(out) else out.reshape(0, 2).astype(np.int64)
    n = int(group.max()) + 1
    geoms = shapely.linestrings(np.stack([p, q], axis=1))
    tree = shapely.STRtree(geoms)
    found = np.zeros(0, dtype=np.int64)
    lo, step = 0, 256
    while lo < len(p):
        rows = np.arange(lo, min(lo + step, len(p)))
        lo = rows[-1] + 1
        r, j = tree.query(geoms[rows])
        i = rows[r]
        # the next rows as many as keep about ``chunk`` candidates each (2M: ~100 MB)
        step = int(np.clip(chunk / max(len(r) / len(rows), 1.0), 64, 1 << 16))
        ga, gb = group[i], group[j]
        keep = (i < j) & (ga != gb)
        i, j = i[keep].astype(np.int64), j[keep].astype(np.int64)
        key = np.minimum(ga[keep], gb[keep]) * n + np.maximum(ga[keep], gb[keep])
        new = ~np.isin(key, found)
        meets = segments_meet(p, q, i[new], j[new], geoms)
        found = np.union1d(found, key[new][meets])
    return np.stack([found // n, found % n], axis=1).astype(np.int64)


def segments_meet(p, q, i, j, geoms=None):
    """Do segments ``i`` and ``j`` (each (k,) int) of ``p, q`` (b,2) intersect or touch? (k,) bool.

    Decided by the four orientation signs in float64 when all four are clear of their rounding
    error bound, by GEOS's robust predicate otherwise; segments with an identical end touch.
    ``geoms`` (b,) shapely linestrings of the segments, optional (made when needed)."""
    import shapely
    # (rows by ``take``: numpy's fancy index is ~4x dearer for rows)
    a, b, c, d = p.take(i, axis=0), q.take(i, axis=0), p.take(j, axis=0), q.take(j, axis=0)
    shared = np.zeros(len(i), dtype=bool)
    for x, y in ((a, c), (a, d), (b, c), (b, d)):
        shared |= np.all(x == y, axis=1)
    o1, e1 = _orient(a, b, c)
    o2, e2 = _orient(a, b, d)
    o3, e3 = _orient(c, d, a)
    o4, e4 = _orient(c, d, b)
    clear = (np.abs(o1) > e1) & (np.abs(o2) > e2) & (np.abs(o3) > e3) & (np.abs(o4) > e4)
    meets = shared | (clear & (np.sign(o1) != np.sign(o2)) & (np.sign(o3) != np.sign(o4)))
    unsure = ~shared & ~clear
    if unsure.any():
        if geoms is None:
            geoms = shapely.linestrings(np.stack([p, q], axis=1))
        meets[unsure] = shapely.intersects(geoms[i[unsure]], geoms[j[unsure]])
    return meets
