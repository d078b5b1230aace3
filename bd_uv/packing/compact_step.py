"""One step of the compaction (:mod:`.compact`): its linear program (Li and Milenkovic's
compaction, 1995) over every chart's move and turn, the rows of the vertex and segment pairs
within reach and of the square's edges, and the pairs close after a move (rows for them too).
Split from :mod:`.compact` (the sequence of steps, its checks and stops)."""
import numpy as np

from .highs_lp import solve_lp

__all__ = ["TURN_MAX", "close", "step_lp"]

TURN_MAX = 0.1    # largest turn of a chart in one step, radians
# edge rows only for charts this many steps from an edge: a point moves at most
# (sqrt 2 + 1) steps a program and the side shrinks by at most about twice that (the charts
# at the edges move by as much), so a chart farther away cannot reach the edge; the exact
# check of every step holds anyway
EDGE_REACH = 8.0
REACH = 2.0      # rows for vertex and segment pairs within the separation plus REACH steps
# SHOVE: each program minimises the side less SHOVE times every chart's move up and right. With
# the side alone the optimum holds many moves, and HiGHS' dual simplex on the program left the
# charts that do not hold the side at their upper bounds (85 % of the moves at +step on the
# tiny-charts test's programs): a shove the compaction relied on, stated nowhere. Its programs
# are now solved as their dual first (highs_lp: 2.5-3x less CPU), whose optimum is lazy (96 % of
# the moves zero) and jammed that test's compaction (0.5 % in 20 programs, main 2.1 %); with the
# shove stated and the program itself solved again where a move fails the exact check (as main
# solved every one), 2.2 %. Measured on the compaction alone (21 dumped inputs of 8 meshes, each
# twice at the same CPU budget; issue18-pack27-2026-11-29.md): the area shrink's geometric mean
# 1.0900 (main) -> 1.0945 (dino +1.0 %, suzanne +1.3 %, rocker-arm -0.2 %); without the shove
# 1.0960, within the runs' spread of it; 1e-3 as 1e-4 (the dual alone)
SHOVE = 1e-4
# HOLD: a chart smaller than step / TURN_MAX turns by up to TURN_MAX, and its rows keep room for
# its turn's error terms (2 (sqrt 2 + 1) step TURN_MAX: 2.5 texels at the first step). Small charts
# close together (the shader ball's bolts: ~150 charts a few texels across) have narrower gaps: all
# programs were infeasible (0 steps in 2.9 s, 2 seeds of 3). After the first infeasible program
# such charts in a pair too tight for those terms only move (shader ball: 4-7 steps). Holding all
# charts of such pairs cost cow, dino, homer, spot 0.6-2.3 % coverage; these only: within noise.


def close(Q, owner, nxt, reach):
    """Vertex and segment indices of two charts closer than ``reach`` (at most ``reach`` apart).

    A point within ``reach`` of a segment lies within half its length plus ``reach`` of its
    midpoint: the candidates are the point and midpoint pairs within the longest half plus
    ``reach`` (k-d trees, in C), then each kept at its exact distance. The same pairs as
    shapely's STRtree ``dwithin`` query of every point against every segment, 2-4x faster
    (rocker-arm, cow, camel, the shader ball: 1.3-5 ms against 2.2-17 ms a program)."""
    from scipy.spatial import cKDTree
    A, B = Q, Q[nxt]
    half = 0.5 * np.linalg.norm(B - A, axis=1)
    grown = reach * (1 + 1e-9)
    near = cKDTree(0.5 * (A + B)).sparse_distance_matrix(
        cKDTree(Q), float(half.max()) + grown, output_type="ndarray")
    si, vi = near["i"].astype(np.int64), near["j"].astype(np.int64)
    keep = (owner[vi] != owner[si]) & (near["v"] <= half[si] + grown)
    vi, si = vi[keep], si[keep]
    a, ab = A[si], B[si] - A[si]
    t = np.clip(np.einsum("ij,ij->i", Q[vi] - a, ab)
                / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300), 0.0, 1.0)
    keep = np.linalg.norm(Q[vi] - (a + t[:, None] * ab), axis=1) <= reach
    order = np.lexsort((si[keep], vi[keep]))
    return vi[keep][order], si[keep][order]


def _near_pairs(Q, owner, nxt, reach, extra=None):
    """Vertex / segment pairs of two charts closer than ``reach``, and the ``extra`` pairs
    (vertex and segment indices): vertex index, the nearest point c of the segment, unit
    u = (v - c) / |v - c| and the distance (one row per vertex and segment end where the
    nearest point is an end)."""
    A, B = Q, Q[nxt]
    vi, si = close(Q, owner, nxt, reach)
    if extra is not None:
        vi, si = np.concatenate([vi, extra[0]]), np.concatenate([si, extra[1]])
    a, ab, v = A[si], B[si] - A[si], Q[vi]
    t = np.clip(np.einsum("ij,ij->i", v - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab),
                                                             1e-300), 0.0, 1.0)
    key = np.where(t <= 0, si, np.where(t >= 1, nxt[si], len(Q) + si))
    _, first = np.unique(vi.astype(np.int64) * (2 * len(Q) + 1) + key, return_index=True)
    vi, si, t = vi[first], si[first], t[first]
    c = A[si] + t[:, None] * (B[si] - A[si])
    d = np.linalg.norm(Q[vi] - c, axis=1)
    return vi, si, c, (Q[vi] - c) / d[:, None], d


def _cross(w, u):
    """u . J w for the quarter turn J (x, y) -> (-y, x): a point's velocity under a unit turn."""
    return w[:, 0] * u[:, 1] - w[:, 1] * u[:, 0]


def step_lp(Q, owner, nxt, centre, radius, S, pad, pm, tol, step, turn, seconds, extra=None,
             hold=False):
    """One linear program (at most ``seconds`` long): the moves (k,2), turns (k,) in radians and
    the side reached, or None; and whether the program was infeasible. ``hold``: the charts
    turning by TURN_MAX in a pair whose gap leaves no room for the turns' error terms do not
    turn (``HOLD``)."""
    from scipy.sparse import coo_array
    k = len(centre)
    nv = 3 * k + 1                    # per chart dx, dy, turn; then S
    sep = pm * S + 2 * tol
    # turns: at most ``step`` at the chart's farthest point and TURN_MAX radians; a point's exact
    # turn departs from the linear one by at most r (1 - cos phi) + r (phi - sin phi) < r phi^2
    lim = np.minimum(step / np.maximum(radius, 1e-300), TURN_MAX) if turn else np.zeros(k)
    err = radius * lim ** 2
    vi, si, c, u, d = _near_pairs(Q, owner, nxt, sep + REACH * step, extra)
    i, j = owner[vi], owner[si]
    m = len(vi)
    if hold and turn:
        tight = d - sep < err[i] + err[j] + 2 * (np.sqrt(2) + 1) * step * lim[j]
        held = np.concatenate([i[tight], j[tight]])
        lim[held[lim[held] >= TURN_MAX]] = 0.0
        err = radius * lim ** 2
    ri, rj = _cross(Q[vi] - centre[i], u), _cross(c - centre[j], u)
    # -u.Di - phi_i ri + u.Dj + phi_j rj + pm S <= d - 2 tol
    cols = [3 * i, 3 * i + 1, 3 * i + 2, 3 * j, 3 * j + 1, 3 * j + 2, np.full(m, 3 * k)]
    vals = [-u[:, 0], -u[:, 1], -ri, u[:, 0], u[:, 1], rj, np.full(m, pm)]
    rows = [np.tile(np.arange(m), 7)]
    # the segment's own turn tilts its line: |phi_j| times the points' relative slide (each
    # point moves at most (sqrt 2 + 1) step), second order again
    rhs = [d - 2 * tol - err[i] - err[j] - 2 * (np.sqrt(2) + 1) * step * lim[j]]
    n = m
    # edges: vertices near their chart's extremes, e <= q + D + phi J(q - centre) <= S - e,
    # for the charts within EDGE_REACH steps of that edge (the others cannot reach it)
    lo = np.full((k, 2), np.inf)
    hi = np.full((k, 2), -np.inf)
    np.minimum.at(lo, owner, Q)
    np.maximum.at(hi, owner, Q)
    e = 0.5 * pad * S + tol
    for a in range(2):  # per axis
        vel = (Q - centre[owner])[:, 1 - a] * (-1 if a == 0 else 1)   # (J (q - centre))_a
        for sgn, ext in ((-1.0, lo), (1.0, hi)):  # lower edge, upper edge
            gap = ext[:, a] - e if sgn < 0 else S - e - ext[:, a]
            sel = np.flatnonzero((sgn * (Q[:, a] - ext[owner, a]) > -6 * step)
                                 & (gap[owner] < EDGE_REACH * step))
            o = owner[sel]
            r = n + np.arange(len(sel))
            cols += [3 * o + a, 3 * o + 2, np.full(len(sel), 3 * k)]
            vals += [np.full(len(sel), sgn), sgn * vel[sel],
                     np.full(len(sel), 0.5 * pad if sgn < 0 else -(1 - 0.5 * pad))]
            rows += [np.tile(r, 3)]
            rhs.append(-sgn * Q[sel, a] - tol - err[o])
            n += len(sel)
    A = coo_array((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                  shape=(n, nv)).tocsr()
    cost = np.zeros(nv)
    cost[-1] = 1.0
    cost[:-1].reshape(k, 3)[:, :2] = -SHOVE
    bounds = np.zeros((nv, 2))
    bounds[:-1] = np.stack([np.tile([step, step, 0.0], k), np.tile([step, step, 0.0], k)], 1)
    bounds[2:-1:3, 0] = bounds[2:-1:3, 1] = lim
    bounds[:-1, 0] *= -1
    bounds[-1] = (0.0, S)
    # (dual simplex without presolve: measured 1.5x faster on these small, tall programs; their
    # dual first, the program itself once a move failed the exact check: SHOVE)
    sol, status = solve_lp(cost, A, np.concatenate(rhs), bounds[:, 0], bounds[:, 1],
                           max(float(seconds), 1e-3), dual=extra is None)
    if status != 0:
        return None, status == 2
    x = sol[:-1].reshape(k, 3)
    return (x[:, :2], x[:, 2], float(sol[-1])), False
