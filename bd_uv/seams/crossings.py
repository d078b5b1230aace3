"""Where a chart's UV boundary crosses itself: pairs of non-adjacent boundary edges that meet.

A flip-free map of a disk is one-to-one exactly when its boundary loop does not cross itself, so
the seam search counts these crossings on every candidate chart's conformal map.
"""
import numpy as np

# ``boundary_crossings`` tests every pair of a loop's edges when the loops have at most this many
# pairs in all (else candidate pairs come from a grid).
ALL_PAIRS = 20000


def boundary_crossings(uv, loops):
    """Count pairs of non-adjacent boundary edges that cross, per loop (polygon self-crossings).

    Candidate pairs come from a uniform grid (cell = the loop's mean edge length), so the work
    is about linear in the number of boundary edges.

    Parameters
    ----------
    uv : (nv,) complex, vertex positions
    loops : list of (b,) int arrays, one closed vertex loop per chart

    Returns
    -------
    (k,) int64, crossing pairs per loop
    """
    k = len(loops)
    lens = np.array([len(lp) for lp in loops], dtype=np.int64)
    if k == 0 or lens.sum() == 0:
        return np.zeros(k, np.int64)
    if (lens == 0).any():                   # empty loops: none of their edges cross
        out = np.zeros(k, np.int64)
        some = (lens > 0).ravel().nonzero()[0]
        out[some] = boundary_crossings(uv, [loops[j] for j in some])
        return out
    owner = np.repeat(np.arange(k), lens)
    a_idx = np.concatenate(loops)
    start = np.concatenate([[0], lens.cumsum()[:-1]])
    nxt = np.arange(len(a_idx)) + 1
    nxt[start + lens - 1] = start
    p, q = uv[a_idx], uv[a_idx[nxt]]
    if int((lens * lens).sum()) <= ALL_PAIRS:
        # Short loops: every pair of each loop's edges (fewer steps than the grid below; two
        # edges that cross share a grid cell, so the count is the same).
        # Each edge with every later edge of its loop (i < j).
        later = (start + lens)[owner] - 1 - np.arange(len(p))
        i = np.repeat(np.arange(len(p)), later)
        j = i + 1 + np.arange(len(i)) - np.repeat(later.cumsum() - later, later)
        keep = (nxt[i] != j) & (nxt[j] != i)
        # Only edges whose boxes meet (touching included) can cross: a few comparisons per
        # pair before the orientation tests, on the few pairs left.
        keep &= _boxes_meet(p, q, i, j)
        i, j = i[keep], j[keep]
        hit = _segments_cross(p[i], q[i], p[j], q[j])
        return np.bincount(owner[i[hit]], minlength=k).astype(np.int64)
    seg = np.abs(q - p)
    # Cell size: the mean edge, or a quarter of the longest, so no edge spans more than 5 cells.
    longest = np.zeros(k)
    np.maximum.at(longest, owner, seg)
    h = np.maximum(np.maximum(np.bincount(owner, seg) / lens, longest / 4), 1e-300)[owner]
    lo = np.minimum(p.real, q.real), np.minimum(p.imag, q.imag)
    hi = np.maximum(p.real, q.real), np.maximum(p.imag, q.imag)
    x0, y0 = np.floor(lo[0] / h).astype(np.int64), np.floor(lo[1] / h).astype(np.int64)
    x1, y1 = np.floor(hi[0] / h).astype(np.int64), np.floor(hi[1] / h).astype(np.int64)
    span = int(max((x1 - x0).max(), (y1 - y0).max())) + 1
    dx, dy = np.meshgrid(np.arange(span), np.arange(span), indexing="ij")
    dx, dy = dx.ravel(), dy.ravel()
    cx = x0[:, None] + dx[None]
    cy = y0[:, None] + dy[None]
    inside = (cx <= x1[:, None]) & (cy <= y1[:, None])
    sid = np.broadcast_to(np.arange(len(p))[:, None], cx.shape)[inside]
    cx, cy = cx[inside], cy[inside]
    # One int64 key per (loop, cell): cells per loop are at most about its edge count squared.
    cx, cy = cx - cx.min(), cy - cy.min()
    ny = int(cy.max()) + 1
    cell_id = (owner[sid] * (int(cx.max()) + 1) + cx) * ny + cy
    order = cell_id.argsort(kind="stable")
    cell_id, sid = cell_id[order], sid[order]
    bounds = np.diff(cell_id).ravel().nonzero()[0] + 1
    starts = np.concatenate([[0], bounds])
    sizes = np.diff(np.concatenate([starts, [len(cell_id)]]))
    # All pairs within each cell.
    reps = sizes ** 2
    grp = np.repeat(np.arange(len(starts)), reps)
    r = np.arange(reps.sum()) - np.repeat(reps.cumsum() - reps, reps)
    i = sid[starts[grp] + r // sizes[grp]]
    j = sid[starts[grp] + r % sizes[grp]]
    keep = i < j
    i, j = i[keep], j[keep]
    nseg = len(p)
    pair = np.unique(i * nseg + j)
    if len(pair) == 0:
        return np.zeros(k, np.int64)
    i, j = pair // nseg, pair % nseg
    keep = (nxt[i] != j) & (nxt[j] != i)
    keep &= _boxes_meet(p, q, i, j)
    i, j = i[keep], j[keep]
    hit = _segments_cross(p[i], q[i], p[j], q[j])
    return np.bincount(owner[i[hit]], minlength=k).astype(np.int64)


def _boxes_meet(p, q, i, j):
    """Whether the bounding boxes of edges ``i`` and ``j`` (``p -> q``) meet, touching included:
    edges that cross do, so the orientation tests run only on these pairs."""
    x0, x1 = np.minimum(p.real, q.real), np.maximum(p.real, q.real)
    y0, y1 = np.minimum(p.imag, q.imag), np.maximum(p.imag, q.imag)
    return (x0[i] <= x1[j]) & (x0[j] <= x1[i]) & (y0[i] <= y1[j]) & (y0[j] <= y1[i])


def _segments_cross(p1, q1, p2, q2):
    """Whether segments p1q1 and p2q2 intersect (touching counts), vectorised over rows."""
    def orient(a, b, c):
        return ((b - a).conj() * (c - a)).imag
    d1, d2 = orient(p2, q2, p1), orient(p2, q2, q1)
    d3, d4 = orient(p1, q1, p2), orient(p1, q1, q2)
    return (np.sign(d1) * np.sign(d2) <= 0) & (np.sign(d3) * np.sign(d4) <= 0) & \
        ~((d1 == 0) & (d2 == 0) & (d3 == 0) & (d4 == 0) & ~_collinear_overlap(p1, q1, p2, q2))


def _collinear_overlap(p1, q1, p2, q2):
    """For collinear segments: whether their extents overlap."""
    lo1 = np.minimum(p1.real, q1.real), np.minimum(p1.imag, q1.imag)
    hi1 = np.maximum(p1.real, q1.real), np.maximum(p1.imag, q1.imag)
    lo2 = np.minimum(p2.real, q2.real), np.minimum(p2.imag, q2.imag)
    hi2 = np.maximum(p2.real, q2.real), np.maximum(p2.imag, q2.imag)
    return ((lo1[0] <= hi2[0]) & (lo2[0] <= hi1[0]) & (lo1[1] <= hi2[1]) & (lo2[1] <= hi1[1]))
