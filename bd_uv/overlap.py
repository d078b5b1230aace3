"""Is a flip-free map one-to-one? Its UV boundary decides (Lipman 2012, Theorems 5.1 and 5.2).

For a map with no flipped face the number of preimages of a UV point ``p`` (off the boundary image)
is the winding number of the UV boundary curves around ``p``. So an island is a bijection onto its
image exactly when its boundary curves are simple and pairwise disjoint, the outer one runs
counter-clockwise and the holes clockwise inside it, none inside another: then the winding number is
0 or 1 everywhere. This module checks the UV boundary found from the corners as stored:

1. (:mod:`.uv_boundary`) a half-edge is interior when a face of the same island holds the reverse half-edge with the same
   UVs at both ends; every other half-edge is a boundary segment (seams and slits included);
2. any two boundary segments that meet, other than consecutive segments at their shared end, are a
   crossing (GEOS's robust predicates through ``shapely.STRtree``); so is a UV point the boundary
   passes through more than once, and two consecutive segments that fold back onto each other;
3. with no crossing, each boundary loop's winding side is checked: the faces' side of every loop
   must have winding number 1 (even-odd containment of one point per loop in the other loops).
"""
from dataclasses import dataclass

import numpy as np

from .geometry import cycle_labels
from .segments import cross, group_pairs_touching, touching_pairs
from .uv_boundary import Boundary, exact_bits, row_ids, uv_boundary

__all__ = ["Boundary", "uv_boundary", "crossing_pairs", "IslandOverlap", "island_overlaps",
           "layout_overlaps"]


def crossing_pairs(bd, pairs):
    """Which touching pairs of one island's segments are crossings.

    Consecutive segments (sharing one UV point) only cross when they fold back onto each other
    (collinear, same direction away from the shared point); every other meeting is a crossing.

    Returns
    -------
    (k,) bool
    """
    i, j = pairs[:, 0], pairs[:, 1]
    share_pp = bd.pid[i] == bd.pid[j]
    share_pq = bd.pid[i] == bd.qid[j]
    share_qp = bd.qid[i] == bd.pid[j]
    share_qq = bd.qid[i] == bd.qid[j]
    n_share = share_pp.astype(int) + share_pq + share_qp + share_qq
    # The shared point s, and the other ends a (of i) and c (of j).
    s = np.where((share_pp | share_pq)[:, None], bd.p[i], bd.q[i])
    a = np.where((share_pp | share_pq)[:, None], bd.q[i], bd.p[i])
    c = np.where((share_pp | share_qp)[:, None], bd.q[j], bd.p[j])
    da, dc = a - s, c - s
    fold = (cross(da, dc) == 0) & (np.einsum("ij,ij->i", da, dc) > 0)
    return (n_share == 0) | (n_share >= 2) | ((n_share == 1) & fold)


def _loops(bd):
    """Label the boundary loops: segments joined end to start at the same UV point.

    Every UV point must start exactly one segment and end exactly one (islands with no crossing
    and no pinch, as ``island_overlaps`` passes them), so segment i continues with the one
    segment that starts where i ends."""
    nb = len(bd.p)
    if nb == 0:
        return 0, np.zeros(0, dtype=np.int64)
    npts = int(max(bd.pid.max(), bd.qid.max())) + 1
    starting = np.full(npts, -1, dtype=np.int64)
    starting[bd.pid] = np.arange(nb)
    least, loop = cycle_labels(starting[bd.qid])
    return len(least), loop


def _winding_ok(bd, loop, n_loops):
    """Per loop: does the faces' side of it have winding number 1? (k,) bool, k = n_loops."""
    if n_loops == 0:
        return np.zeros(0, dtype=bool)
    area2 = np.bincount(loop, weights=cross(bd.p, bd.q), minlength=n_loops)  # twice signed area
    positive = area2 > 0
    lisl = np.zeros(n_loops, dtype=np.int64)
    lisl[loop] = bd.island
    first = np.full(n_loops, -1, dtype=np.int64)
    first[loop[::-1]] = np.arange(len(loop))[::-1]
    sample = bd.p[first]
    lo = np.full((n_loops, 2), np.inf)
    hi = np.full((n_loops, 2), -np.inf)
    np.minimum.at(lo, loop, np.minimum(bd.p, bd.q))
    np.maximum.at(hi, loop, np.maximum(bd.p, bd.q))
    # Candidate (point of loop i, loop j): same island, i != j, point inside j's bounding box.
    order = np.argsort(lisl, kind="stable")
    counts = np.bincount(lisl, minlength=int(lisl.max()) + 1)
    starts = np.concatenate([[0], np.cumsum(counts)])
    sizes = counts[lisl]
    ii = np.repeat(np.arange(n_loops), sizes)
    offs = np.arange(len(ii)) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    jj = order[starts[lisl[ii]] + offs]
    pt = sample[ii]
    cand = (ii != jj) & np.all((pt >= lo[jj]) & (pt <= hi[jj]), axis=1)
    ii, jj = ii[cand], jj[cand]
    inside = np.zeros(len(ii), dtype=bool)
    if len(ii):
        # Even-odd rule: crossings of the rightward ray from the point with loop j's segments.
        seg_order = np.argsort(loop, kind="stable")
        seg_count = np.bincount(loop, minlength=n_loops)
        seg_start = np.concatenate([[0], np.cumsum(seg_count)])
        n_seg = seg_count[jj]
        pair = np.repeat(np.arange(len(ii)), n_seg)
        offs = np.arange(len(pair)) - np.repeat(np.cumsum(n_seg) - n_seg, n_seg)
        seg = seg_order[seg_start[jj[pair]] + offs]
        px, py = pt[cand][pair, 0], pt[cand][pair, 1]
        (x1, y1), (x2, y2) = bd.p[seg].T, bd.q[seg].T
        straddle = (y1 > py) != (y2 > py)
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = x1 + (py - y1) * (x2 - x1) / (y2 - y1)
        hit = straddle & (xc > px)
        inside = np.bincount(pair, weights=hit, minlength=len(ii)) % 2 == 1
    sign = np.where(positive, 1, -1)
    around = np.bincount(ii[inside], weights=sign[jj[inside]], minlength=n_loops)
    return np.where(positive, around == 0, around == 1)


@dataclass(frozen=True)
class IslandOverlap:
    """Overlap figures per island.

    Attributes
    ----------
    overlap_free : (k,) bool (False for an island with a face of non-finite UVs)
    crossings : (k,) int64, crossing pairs of boundary segments (plus extra passes through a point)
    bad_loops : (k,) int64, boundary loops on the wrong winding side (a hole outside the outer
        boundary, a second outer boundary around the first, ...)
    boundary : Boundary
    pairs : (c,2) int64, the crossing segment pairs (indices into ``boundary``)
    """
    overlap_free: np.ndarray
    crossings: np.ndarray
    bad_loops: np.ndarray
    boundary: Boundary
    pairs: np.ndarray


def island_overlaps(F, corner_uv, face_island, n_islands=None):
    """Check each island of a layout for self-overlap (Lipman 2012, Theorems 5.1 and 5.2).

    The result is meaningful for islands with no flipped face; a flipped face overlaps its
    neighbours without any boundary crossing.

    Parameters
    ----------
    F : (m,3) int array
    corner_uv : (m,3,2) float array, UVs as stored (float32 allowed)
    face_island : (m,) int array, island per face (-1: no island)
    n_islands : int, optional (default: max label + 1)

    Returns
    -------
    IslandOverlap (an island with a face of non-finite UVs is not overlap-free)
    """
    lab = np.asarray(face_island, dtype=np.int64).reshape(-1)
    k = int(lab.max()) + 1 if n_islands is None and len(lab) else int(n_islands or 0)
    bd = uv_boundary(F, corner_uv, lab)
    # A face with a non-finite UV has no place in UV: nothing proves its island one-to-one (its
    # boundary is not all there), so such an island is never overlap-free.
    finite = np.isfinite(np.asarray(corner_uv, dtype=np.float64).reshape(-1, 3, 2)).all(axis=(1, 2))
    unplaced = np.bincount(lab[(lab >= 0) & (lab < k) & ~finite], minlength=k)
    pairs = touching_pairs(bd.p, bd.q, bd.island)
    pairs = pairs[bd.island[pairs[:, 0]] == bd.island[pairs[:, 1]]]
    pairs = pairs[crossing_pairs(bd, pairs)]
    crossings = np.bincount(bd.island[pairs[:, 0]], minlength=k).astype(np.int64)
    # A UV point the boundary passes through more than once is a pinch: the curve is not simple.
    npts = int(max(bd.pid.max(), bd.qid.max())) + 1 if len(bd.p) else 0
    passes = np.bincount(bd.pid, minlength=npts)
    ends = np.bincount(bd.qid, minlength=npts)
    pt_isl = np.zeros(npts, dtype=np.int64)
    pt_isl[bd.pid] = bd.island
    pt_isl[bd.qid] = bd.island
    extra = np.maximum(passes, ends) - 1 + (passes != ends)
    crossings += np.bincount(pt_isl, weights=np.maximum(extra, 0), minlength=k).astype(np.int64)
    bad = np.zeros(k, dtype=np.int64)
    clean = crossings == 0
    sel = clean[bd.island]
    # Only islands with boundary segments have loops to wind: an island with no faces in the
    # layout (a failed island, left out with -1 or non-finite UVs) is clean but has nothing here.
    if sel.any():
        sub = Boundary(bd.p[sel], bd.q[sel], bd.island[sel], bd.face[sel], bd.edge[sel],
                       bd.pid[sel], bd.qid[sel], bd.interior)
        n_loops, loop = _loops(sub)
        ok = _winding_ok(sub, loop, n_loops)
        lisl = np.zeros(n_loops, dtype=np.int64)
        lisl[loop] = sub.island
        bad = np.bincount(lisl[~ok], minlength=k).astype(np.int64)
    return IslandOverlap(clean & (bad == 0) & (unplaced == 0), crossings, bad, bd, pairs)


def layout_overlaps(corner_uv, face_island, F=None):
    """Pairs of islands of a layout that overlap each other.

    Two islands overlap when their UV boundaries meet (touching counts: pack with a margin), or
    when one lies inside the other (a point of its boundary inside the other's outer boundary and
    outside its holes, even-odd rule).

    Parameters
    ----------
    corner_uv : (m,3,2) float array, UVs as stored
    face_island : (m,) int array, island per face (-1: no island)
    F : (m,3) int array, optional; without it every face corner is its own vertex, so the boundary
        is found from the UVs alone

    Returns
    -------
    (k,2) int64, island pairs (a < b), sorted, each once
    """
    uv = np.asarray(corner_uv, dtype=np.float64).reshape(-1, 3, 2)
    if F is None:
        F = _vertices_from_uv(uv)
    bd = uv_boundary(F, uv, face_island)
    if not len(bd.p):
        return np.zeros((0, 2), dtype=np.int64)
    out = [group_pairs_touching(bd.p, bd.q, bd.island)]
    # Containment: one boundary point of each island, tested against the other islands' boundary.
    n_isl = int(bd.island.max()) + 1
    first = np.full(n_isl, -1, dtype=np.int64)
    first[bd.island[::-1]] = np.arange(len(bd.island))[::-1]
    has = first >= 0
    isl_ids = np.flatnonzero(has)
    pts = bd.p[first[has]]
    import shapely
    segs = shapely.linestrings(np.stack([bd.p, bd.q], axis=1))
    tree = shapely.STRtree(segs)
    # Segments crossed by the rightward ray from each point decide the even-odd containment.
    far = max(float(np.max(np.abs(bd.p))), float(np.max(np.abs(bd.q))), 1.0) * 4 + 1
    rays = shapely.linestrings(np.stack([pts, np.stack([np.full(len(pts), far), pts[:, 1]], 1)],
                                        axis=1))
    r, s = tree.query(rays, predicate="intersects")
    other = bd.island[s] != isl_ids[r]
    r, s = r[other], s[other]
    y1, y2 = bd.p[s, 1], bd.q[s, 1]
    py = pts[r, 1]
    straddle = (y1 > py) != (y2 > py)
    key = r * n_isl + bd.island[s]
    uk, inv = np.unique(key, return_inverse=True)
    odd = np.bincount(inv, weights=straddle, minlength=len(uk)) % 2 == 1
    a, b = isl_ids[uk[odd] // n_isl], uk[odd] % n_isl
    out.append(np.stack([np.minimum(a, b), np.maximum(a, b)], axis=1))
    allp = np.concatenate(out).astype(np.int64)
    return np.unique(allp, axis=0) if len(allp) else allp.reshape(0, 2)


def _vertices_from_uv(uv):
    """Corner vertex ids shared by corners with identical UVs: (m,3) int64."""
    flat = uv.reshape(-1, 2)
    ids = row_ids(exact_bits(flat[:, 0]), exact_bits(flat[:, 1]))
    return ids.reshape(-1, 3)
