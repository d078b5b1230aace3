"""A map within a numeric C of low mean distortion without a conic solve, for an island whose
conformal start flips and whose projection from it stalls (issue 21: default C = 5 within ABF's
time on every disk).

``from_harmonic``: the harmonic map (flip-free) lowered into C by the bound search, stopping at
its first map within C (``searched.search``, as ``over_bound``), then ``lowest_energy``: the
conformal (LSCM) energy minimised over F_C with that map's frames by ADMM (the cone product and the
least-squares step of ``solvers.bound_search``, the energy taken into the cone step; two anchors
hold the scale as ``IslandProblem.anchor_to``'s), and the map of least mean distortion within C
on the segment between the two (``along.least_mean_within``: F_C with fixed frames is convex, the
searched map is in it, the ADMM iterate is at most slightly outside).

Before, such an island (libigl decimated-knight's 976-face strip with a 6-edge hole at C = 5)
projected its harmonic map for up to 300 iterations, which failed (~0.09 s), then took one
Clarabel solve from the harmonic frames (~0.11 s): max 4.989, mean 2.171. Here: the search, 9 ms;
25 ADMM iterations, ~5 ms; mean ~2.15.
"""
import time

import numpy as np

from ..frames import _far_pair, frames_from_map
from ..solvers.face_operators import gradient_rows
from ..solvers.free_admm import sparse_product, transposed
from ..solvers.global_step import GlobalStep
from .along import least_mean_within
from .initial import start_map
from .margins import solve_bound
from .searched import FAR, MEAN_SEARCH, search

__all__ = ["from_harmonic", "lowered", "lowest_energy", "weighted_lowered"]

# ADMM iterations of ``lowest_energy`` and the energy's weight next to the splitting's penalty
# (the optimum does not depend on it, the iterations' path does). decimated-knight's strip at
# C = 5, from the searched map (mean 2.623): at 0.3, 20 iterations 2.151, 30 2.148, 60 2.173 (the
# iterate nearer the cone's boundary, the segment's best further back); at 0.1, 20 2.277, 40
# 2.154; at 1, 20-60 2.178-2.179. The conic solve reached 2.171 in 80 iterations (0.11 s).
ITERATIONS = 25
TAU = 0.3
# The searched and relaxed map's mean still over the angle start's (Linear ABF's map, whose mean
# is near Blender ABF's: 1.2910 against 1.2928 on the unseen homer-ball2200y-) by more than
# LOWER_RISE: lowered within its max (``weighted_lowered``, from ``disk_angle`` and
# ``strategies.minimise`` with ``one_to_one``). There the relax held 772 of 1,241 vertices
# (the disk's LSCM map, which the angle start replaced, exceeds the max round every face held):
# mean 1.3658, 1.0565x ABF's; lowered, 1.2688 (0.981x) at the same C 1.6867, ~12-15 ms of CPU
# on ~70 (ABF 0.18 s). The energy weighted by 1 / |alpha|^2 (the distortion's scale):
# unweighted (TAU 0.3, 25-100 iterations) 1.352-1.369, the better maps lying over themselves;
# 35 iterations 1.2519, 50 1.2498; LOWER_TAU 0.03: 1.29-1.30. Aimed at D itself the faces at
# the max may end a rounding over it, and then nothing is taken (cow.off's 406-face disk: at 35
# iterations; 1.1338 -> 1.1226 at 25); aimed at 0.99 of D's excess the iterate is within D at
# 25-50 iterations there and on homer's (1.2478 at 25), but the max falls with the mean (cow
# disk's C 1.4432 -> 1.4383), under the C of the command line's time budget, whose steps run
# from the searched map (test_angle_start's time budget test). With no gate (LOWER_RISE -1)
# 15 of 19 angle-start disks of the 90 unseen lower their means (by up to 0.3 % of ABF's but
# homer's), no C rises; at 3 % only homer-ball2200y- pays (``issue21-auto33-2026-11-29.md``)
LOWER = True
LOWER_RISE = 0.03
LOWER_ITERATIONS = 25
LOWER_TAU = 0.01
LOWER_AIM = 1.0
LOWER_BACK = 4     # the segment's maps tested for laying the island out, halving s
# The steps of a bound raised where C is out of reach (``bounded.RAISE_FACTOR``'s, which the
# conic raise takes; that module imports this one)
RAISE_STEP = 1.5


def lowered(prob, us, target):
    """The map of least mean distortion within ``target`` between the searched map us (within
    it) and ``lowest_energy``'s iterate from it."""
    t = time.perf_counter()
    ul = lowest_energy(prob, us, target)
    um = least_mean_within(prob, us, ul, target, MEAN_SEARCH)
    prob.timings["project"] = prob.timings.get("project", 0.0) + time.perf_counter() - t
    return um


def weighted_lowered(prob, v, u, D, lays_out):
    """The map u (nv,) complex of ``prob`` (max distortion D, laying the island out) with its
    mean lowered within D, where it is over the (angle) start v's by more than LOWER_RISE of it:
    ``lowest_energy`` with every face's energy weighted by LOWER_TAU x mean(|alpha|^2) /
    |alpha|^2 of u (the distortion's scale, not the face's), aimed at LOWER_AIM of D's excess,
    LOWER_ITERATIONS
    iterations, then the furthest map within D on the segment from u to that iterate (the
    iterate itself, or by MEAN_SEARCH bisections), or where that one does not ``lays_out``,
    the first that does of its segment's points nearer u, halving the way, LOWER_BACK tests
    at most. Returns (map, its max distortion) or None where
    none is lower."""
    area = prob.ops.area / float(np.add.reduce(prob.ops.area))
    mean_u = float(area @ prob.face_distortion(u))
    if not mean_u > (1.0 + LOWER_RISE) * float(area @ prob.face_distortion(v)):
        return None
    a2 = np.abs(prob.alpha(u)) ** 2
    d = lowest_energy(prob, u, 1.0 + LOWER_AIM * (D - 1.0), LOWER_ITERATIONS,
                      LOWER_TAU * float(area @ a2) / a2) - u

    def mean(s):
        Dy = prob.face_distortion(u + s * d)
        return float(area @ Dy) if Dy.max() <= D else np.inf
    # the furthest map within D on the segment (its whole length, where the iterate is)
    s, m = 1.0, mean(1.0)
    if not np.isfinite(m):
        lo, m, hi = 0.0, mean_u, 1.0
        for _ in range(MEAN_SEARCH):
            mid = 0.5 * (lo + hi)
            mm = mean(mid)
            if np.isfinite(mm):
                lo, m = mid, mm
            else:
                hi = mid
        s = lo
    for _ in range(LOWER_BACK):     # the least mean's map lying over itself: nearer u
        if not m < mean_u:
            return None
        y = u + s * d
        if lays_out(y):
            return y, float(prob.face_distortion(y).max())
        s *= 0.5
        m = mean(s)
    return None


def lowest_energy(prob, us, C, iterations=ITERATIONS, tau=TAU):
    """ADMM towards the least conformal energy ``sum_j A_j |beta_j|^2`` over F_C with the frames
    of the flip-free map us (nv,) complex whose max distortion is within C: from us, the island's
    two far boundary vertices held where us has them (its scale); ``tau`` a float or (k,) per
    face (``disk_angle._lowered``: 1 / |alpha|^2 weights). Returns the last iterate
    (nv,) complex, near F_C but not certainly in it (``from_harmonic`` takes the best map
    between it and us).

    The lift ``G`` (2k, nv: every face's d/dx, then d/dy) and the right-hand side's operator
    (``G^T`` times the faces' areas, its free vertices' rows) are bare compressed rows, from
    each face's gradient coefficients (``face_operators.gradient_rows``), in the entries' order
    of the scipy products they stand for, multiplied by the compiled products straight
    (``free_admm.sparse_product``) into buffers made once: the same sums in the same order, so
    the same bits, without scipy's matrices and dispatch (decimated-knight's 984-face strip:
    set-up 2.7 -> 2.2 ms, 25 iterations 4.7 -> 3.6 ms)."""
    ops, nv = prob.ops, prob.nv
    k = len(ops.area)
    idx, _ = _far_pair(prob.Z, prob.island.tris, nv, prob.island.loops[0])
    gs = GlobalStep(ops, nv, idx, prob.island.tris, connected=True, ranks=prob.ranks)
    solve = gs.factorize()
    free, fixed = gs.free, gs.fixed
    nf = len(free)
    gptr, gind, gdat = gradient_rows(*gs.face_gradients(), gs.tris)
    lift_op = sparse_product("csr", (2 * k, nv), gptr, gind)
    # G^T A (nv, 2k): scipy's product of the transpose (sorted rows) with the diagonal leaves
    # each row's entries in reverse order; only the free vertices' rows, in ``free``'s order
    tptr, tind, perm = transposed((2 * k, nv), gptr, gind)
    counts = tptr[free + 1] - tptr[free]
    rptr = np.zeros(nf + 1, np.int64)
    np.cumsum(counts, out=rptr[1:])
    pos = np.repeat(tptr[free + 1] - 1 + rptr[:-1], counts) - np.arange(rptr[-1])
    rind = tind.take(pos)
    area2 = np.concatenate([gs.area, gs.area])
    rdat = gdat.take(perm.take(pos)) * area2.take(rind)
    rhs_op = sparse_product("csr", (nf, 2 * k), rptr, rind)
    Uu, Uv = np.ascontiguousarray(us.real), np.ascontiguousarray(us.imag)
    share = gs.fixed_share(np.stack([Uu.take(fixed), Uv.take(fixed)], axis=1))
    su, sv = np.ascontiguousarray(share[:, 0]), np.ascontiguousarray(share[:, 1])
    w = frames_from_map(prob.alpha(us))
    wr, wi = w.real, w.imag
    kappa = (C - 1.0) / (C + 1.0)
    # the cone step with the energy: min tau |beta|^2 + |z - q|^2 over |beta| <= kappa Re(w
    # alpha) is the projection of (alpha_q, beta_q / s) onto the cone of kappa s, s =
    # sqrt(1 + tau), its beta then divided by s
    s = np.sqrt(1.0 + tau)
    ks = kappa * s
    lam = np.zeros((4, k))
    Pu, Pv = np.empty(2 * k), np.empty(2 * k)
    gu, gv = np.empty(2 * k), np.empty(2 * k)
    ru, rv = np.empty(nf), np.empty(nf)

    def lift():                                 # alpha, beta of the map (Uu, Uv), (4, k)
        gu.fill(0.0)
        gv.fill(0.0)
        lift_op(gdat, Uu, gu)
        lift_op(gdat, Uv, gv)
        ux, uy, vx, vy = gu[:k], gu[k:], gv[:k], gv[k:]
        return np.array([0.5 * (ux + vy), 0.5 * (vx - uy), 0.5 * (ux - vy), 0.5 * (vx + uy)])
    J = lift()
    for _ in range(iterations):
        q = J + lam
        X = wr * q[0] - wi * q[1]               # Re(w alpha)
        Y = wr * q[1] + wi * q[0]               # Im(w alpha)
        br, bi = q[2] / s, q[3] / s
        nb = np.hypot(br, bi)
        t = np.maximum(X + ks * nb, 0.0) / (1.0 + ks * ks)     # the cone's boundary ray's point
        f = np.minimum(ks * t / np.maximum(nb, 1e-300), 1.0) / s
        X = np.where(nb <= ks * X, X, t)        # inside the cone: as it is
        z = np.array([wr * X + wi * Y, wr * Y - wi * X, f * br, f * bi])
        z -= lam
        # the least-squares step: the map whose (u_x, u_y, v_x, v_y) are nearest z's
        np.add(z[0], z[2], out=Pu[:k])
        np.subtract(z[3], z[1], out=Pu[k:])
        np.add(z[1], z[3], out=Pv[:k])
        np.subtract(z[0], z[2], out=Pv[k:])
        ru.fill(0.0)
        rv.fill(0.0)
        rhs_op(rdat, Pu, ru)
        rhs_op(rdat, Pv, rv)
        ru -= su
        rv -= sv
        Uu[free] = solve(ru)
        Uv[free] = solve(rv)
        J = lift()
        lam = J - z         # lam + G x - (the cone step), z holding the cone step less lam
    return Uu + 1j * Uv


def from_harmonic(prob, C, report):
    """A map within C of an unpinned BD-LSCM island from its harmonic map (see the module's
    docstring) that lays the island out without overlapping itself, or None where the search
    from it does not reach C or its maps overlap (a 288-face teapot piece with a hole: the
    projection of its harmonic map and a conic solve then, as before). Returns (u, its start)
    or None, and where the search ended far above C (``searched.FAR``, as ``over_bound``
    judges C out of reach: the projection of the harmonic map into C is not tried then;
    decimated-knight's strip at C = 3, its search ending at 4.305: 114 iterations for nothing)
    its map and max distortion (u, D) and start, for the bound raised to it (else False).
    """
    harmonic = start_map(prob, "harmonic", None, report)
    if not np.isfinite(harmonic.D):
        return None, False
    target = solve_bound(C)
    us, D = search(prob, harmonic.u, report, None, [], time.perf_counter(),
                   enough=lambda x: prob.distortion(x) <= target)
    if not D <= target:
        D = prob.distortion(us)
        if not D - 1.0 > FAR * (C - 1.0):
            return None, False
        # out of reach: the bound raised as the conic raise steps it (C x RAISE_STEP^k, the
        # first at or above D) and the energy lowered within it as below, else within D, else
        # the searched map, the first that lays the island out
        raised = C
        while raised < D:
            raised *= RAISE_STEP
        u = us
        for bound in (solve_bound(raised), D):
            um = lowered(prob, us, bound)
            if prob.lays_out(um):
                u = um
                break
        return None, ((u, prob.distortion(u)), harmonic)
    um = lowered(prob, us, target)
    for u in (um, us):
        if prob.check(u, C)[0] and prob.lays_out(u):
            return (u, harmonic), False
    return None, False
