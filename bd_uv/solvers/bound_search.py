"""The smallest bound a map can be certified at, by splitting iterations with one factorisation.

``bound="auto"`` (issue 21): lower the max conformal distortion of a flip-free map without a conic
solve. With frames ``w`` from a map, F_C (Lipman 2012, eq. 4.15) is convex: every face's Jacobian
lies in the cone ``|beta| <= k Re(w alpha)``, ``k = (C - 1) / (C + 1)``. A map in it is found by
ADMM (Douglas-Rachford splitting) between the maps, lifted to their Jacobians by ``G``, and that
product of cones; the area-weighted least-squares step is the projection iterations' global step
(``global_step.GlobalStep``: one factorisation of ``L = G^T A G``, reused for every C):

    x   = argmin_x |G x - (z - lam)|_A^2    one back-solve, fixed vertices held
    z   = Proj_K(G x + lam)                 closed form per face (``framed_cone_projection``)
    lam = lam + G x - z

Kovalsky et al.'s projection onto the non-convex set of bounded-distortion Jacobians
(``projection.py``) stalls short of the optimum where many faces are near the max (hemisphere.obj,
4k faces: 1.0432 in 100 iterations, none of 400 iterations within 1.04; C* = 1.0347); these
iterations, aimed at the convex set, reach 1.0351 in 127 (the search below).

The search over C: from the best certified map D, aim at ``1 + (D - 1)(1 - step)`` (the cones at
``1 + MARGIN (C - 1)`` of it, so that iterates cross into the bound), frames from that map and the
multipliers from zero; every iterate whose max distortion is below D becomes the best
(flip-free, certified at its own max); a run that reaches its target widens the step, one that
stops bettering the best for STALL iterations halves it, until the step is below TOLERANCE or two
targets in a row fell short while gaining less than SMALL of D - 1 (at STALL 20, hemisphere: 156
iterations against 176 for C 1.03506 against 1.03502; mushroom 72 against 92); a fruitless target
aimed at MAX_STEP (reached only by widening) just halves the step (OVERSHOT).
``bound="auto"`` on a small unpinned island with no time budget (``limit_effort``): within an
iteration budget growing with its faces, its first target waiting longer (``target_watch.effort``).

The iterations: up to ONE_PRODUCT_FACES faces on the free unknowns in every face's frame
(``free_admm``), above on the whole map by the gradient operator (``framed_cone``); each target's
stop (STALL, PROGRESS, FLIPPING, MAX_ITER) and ``enough`` are watched by ``target_watch``; the
lift of the maps and their max distortion are ``search_lift``'s.
"""
import functools
import time

import numpy as np

from ..frames import frames_from_map
from ..array_calls import quiet
from .framed_cone import framed_cone_projection, project_framed
from .free_admm import run_free
from .global_step import GlobalStep
from .search_lift import SearchLift
from . import target_watch
from .target_watch import Watch, ask as _ask

__all__ = ["BoundSearch", "framed_cone_projection"]

STEP = 0.3          # first step, as a share of D - 1
MAX_STEP = 0.5
# Stop once a failed target halved the step below TOLERANCE of D - 1. 0.02 -> 0.03 drops the
# last target of the usual halving chain (0.45, 0.225, ... 0.028): nefertiti 80 -> 68 iterations,
# C 1.2653 -> 1.2672; face-patch200 110 -> 98, 1.03373 -> 1.03402; hemisphere, mushroom,
# lion-head, mannequin-devil unchanged, face.obj 1.1478 -> 1.1482 (the peers' least max:
# 1.405, 1.055, 1.037, 1.123, 2.54, 114, 1.216). At 0.06 mannequin-devil:700 rose 3.477 -> 3.628.
TOLERANCE = 0.03
SMALL = 0.01        # ... or two targets in a row fell short gaining less than this share of D - 1
# Within an effort budget (``limit_effort``) a target that gains nothing counts as small too:
# two fruitless targets in a row end the search rather than halving the step down to TOLERANCE
# (igl elephant's 2,004-face patch: 104 -> 38 iterations, C 1.1258 -> 1.1424, the peers' least
# max 1.205; mannequin-devil's 1,112-face strip 62 -> 48, 1.2688 -> 1.2718, 1.374; igl bunny's
# 1,595-face patch 77 -> 61, 1.2124 -> 1.2175, 1.273; no change on the 12 standing disks under
# 5k faces). Not without a budget: cow's 1,240-face disk searched from its angle start (3,666)
# ended at 2.0535 over the 2.045 its cut reached (lion-head 1.590 -> 1.609, face.obj 1.1482 ->
# 1.1487 in 26-28 % less CPU there)
ZERO_SMALL = True
# ... and a fruitless target right after one that fell short ends it (AFTER_SHORT; the step
# already halved once for nothing): mannequin-devil's strip 48 -> 36 iterations, igl bunny's
# patch 61 -> 49 (C 1.2175 -> 1.2176); of auto15's 16 disks four change: armadillo:1500 96 -> 88
# (C 1.0816 -> 1.0844), fandisk:1500 57 -> 30 (1.0632 -> 1.0640), horse:2000 and :4000 47 -> 35
# (1.0695 -> 1.0696, 1.0695), screwdriver:1800 102 -> 68 (1.1023 -> 1.1105); none of the small
# standing disks
AFTER_SHORT = True
# Both also end a least-C search whose start was over ``target_watch.EFFORT_START`` (no budget)
# once its map is within it, as they end one that started there (LATE_BUDGETED: homer's
# 1,982-face strip from its angle start, 2.51: 76 -> 49 iterations, C 1.3456 -> 1.3647, the
# peers' least max 1.585; ChineseDragon's 1,577-face patch 85 -> 42, 1.5114 -> 1.5496, 2.103;
# knight-ball3000top 152 -> 93, 1.6629 -> 1.6841, 2.59, its mean the same; DamagedHelmet's
# 741-face piece 102 -> 39, 1.7875 -> 1.8946, 3.206; no other of 54 disks changes C. Not over
# it: cow's 1,240-face disk ends at 2.03, where its cut reached 2.045)
LATE_BUDGETED = True
# A search given a ``check`` (``strategies.least_one_to_one``: does the map lay the island out?)
# also asks it of the first new best of a target after one that found nothing (aimed too deep):
# True (the map lies over itself) ends the search there, as at a checked new best within a
# target. The targets after a map lying over itself start from it, and their maps lay the island
# out no more (homer's 3,521-face patch: its first target's best, 1.3711, is the least
# one-to-one map; its second target finds nothing, and from the third's first best on, 46
# iterations of 63, every best lies over itself: now 17 iterations, the same map). Of 20 disks
# searched from their angle start, 3 pay one test more (~0.4 ms on 2k faces), the others none
# (the least one-to-one map is tested after the search anyway: the test is kept)
CHECK_AFTER_FRUITLESS = True
# Neither counts a fruitless target aimed at MAX_STEP (OVERSHOT): the step only gets there by
# widening after targets reached, so such a target says that the widened step overshot, not that
# the search is near its floor; the step is halved and the search goes on as if it had not run.
# unseen igl elephant's 600-face patch (R R F F ended it at 59 of its 78 iterations, C 1.1235 over
# Blender ABF's one-to-one 1.11588): 78 iterations, 1.1131. Of 87 unseen disks 5 change, none
# for the worse: camel-strip700x 66 -> 79 iterations (C 1.105 -> 1.103), camel-patch600 65 -> 78
# (1.2028 -> 1.1973), ChineseDragon-ball2200y- 34 -> 78 (1.9485 -> 1.8682), igl-bunny-ball2200y-
# 38 -> 50 (the same C); 6,080 -> 6,181 iterations in all (+1.7 %; issue21-auto33-2026-11-29.md)
OVERSHOT = True
MARGIN = 0.98       # the cones are aimed at 1 + MARGIN (C - 1)
# A map this close to an isometry is not searched further: the bound ``auto`` reports keeps
# STORE_HEADROOM (2e-4) above its max and rounds C - 1 up to 4 significant digits (1.0002001), so
# no lower max can move it by more than one unit of that rounding. A flat mesh's conformal map is
# an isometry up to round-off (alligator.obj, 6k faces: D - 1 = 1e-11), and five targets of 33
# iterations each sought to lower that noise: 0.126 s against 0.014 s at C = 5. Not for a search
# with an ``enough`` (the unfold of a flat island lying over itself seeks a one-to-one map, not
# a lower max: the USD sedan's 99-face body panel, unfolded at max 1.000, was cut with it)
FLAT = 1e-7
ALPHA = 1.5         # ADMM over-relaxation (hemisphere: 196 iterations against 240 at 1.0)
# A search asked to aim deep (``deep``: the unfold of a map lying over itself, which ends at its
# first map ``enough`` accepts) aims deeper and steps further: the least C is not sought.
# Iterations to the first one-to-one map, 7 overlapping disks (three_peaks:554,
# ChineseDragon:913, armadillo:533, camel:328, lion-head:330, :156, three_peaks:536) at C = 5:
# 85 at (0.98, 1.5), 78 at (0.9, 1.5), 73 at (0.9, 1.7), 72 at (0.9, 1.9) (three_peaks:554 21,
# 16, 15, 14); means within 0.4 % (0.8 % at (0.9, 1.5) for lion-head:156), below the least C's.
# On 5 other such disks (the same meshes, other seeds) 55 -> 48 iterations, means within 0.4 %
UNFOLD_MARGIN, UNFOLD_ALPHA = 0.9, 1.7
# Up to this many faces the lift and the right-hand side are one product each with the (4k, 2nv)
# operator (fewer calls: small islands pay per call); above, two products each with the (2k, nv)
# gradient operator (half the multiply-adds: lion-head, 16.7k faces, 1.9 -> 0.95 ms an iteration).
ONE_PRODUCT_FACES = 1000


def _complex(V):
    """The map (nv,) complex of a map's rows (2, nv)."""
    return V[0] + 1j * V[1]


class BoundSearch(SearchLift):
    """Lower a flip-free map's max conformal distortion by ADMM onto F_C with frames.

    Parameters
    ----------
    ops : energies.JacobianOperators of the island (or of several: any union of components)
    nv : int
    tris : (k,3) int
    fixed : (p,) int, vertices held where the map searched from has them (at least one per
        component)
    connected : bool, ``tris`` are one connected piece (one ``mesh.Island``): its components
        are not searched for (``GlobalStep``)
    ranks : (nv,) int64, optional, the vertices' elimination order (``GlobalStep``)
    free : bool, optional, iterate on the free unknowns in every face's frame (``free_admm``)
        whatever the size; by default up to ONE_PRODUCT_FACES faces (``disk_auto`` asks it up
        to its own gate: ``ops`` may then lack the (4k, 2nv) operators)
    """

    def __init__(self, ops, nv, tris, fixed, connected=False, ranks=None, free=None):
        solver = GlobalStep(ops, nv, fixed, tris=tris, connected=connected, ranks=ranks)
        super().__init__(solver, len(solver.area) <= ONE_PRODUCT_FACES if free is None
                         else bool(free))
        self.iterations = 0
        self.ended = self.pending = False   # the last run: ``enough`` stopped it; its best unasked
        # ``limit_effort``'s: bounded as auto's least C, its iteration budget, the first
        # target's STALL
        self.least, self.budget, self.first_stall = False, None, target_watch.STALL
        # asked of every CHECK_EVERY-th new best iterate of a target (``target_watch.Watch``)
        # and, where CHECK_AFTER_FRUITLESS, of the first of a target after one that found
        # nothing; True ends the search there (``strategies.least_one_to_one``: the map lies
        # over itself)
        self.check = None
        self._after_fruitless = False    # the target run follows one that found nothing

    def run(self, U, w, C, D_best, cancel=None, enough=None, ready=None, deep=False):
        """ADMM towards F_C with frames w (unit complex, (k,)), from U (2, nv): rows u and v;
        ``enough``, ``ready`` and ``deep`` as ``search``'s (``ended``: whether ``enough``
        stopped the run; ``pending``: whether its best was not asked).

        Returns (U of the least max distortion below D_best or None, that max, whether it is
        within C)."""
        self.ended = self.pending = False
        ask = None if enough is None or ready is None else functools.partial(_ask, enough, ready)
        s = self.solver
        margin, alpha = (UNFOLD_MARGIN, UNFOLD_ALPHA) if deep else (MARGIN, ALPHA)
        Cm = 1.0 + margin * (C - 1.0)
        kappa = (Cm - 1.0) / (Cm + 1.0)
        if self.on_free:
            return self._run_free(U, w, kappa, C, D_best, cancel, ask, alpha)
        solve = s.factorize()
        BtA = self._operators()[1]
        nf = len(s.free)
        if self._rhs_fixed is None or self._rhs_fixed[0] is not self.UF:
            # the fixed vertices' share of the right-hand side: the same for every target
            self._rhs_fixed = (self.UF, s.fixed_share(self.UF).T.ravel())
        rhs_fixed = self._rhs_fixed[1]
        w2 = np.array([w.real, -w.imag])       # np.stack's rows (its wrapper: ~4 us)
        U = U.copy()
        GU = self._lift(U)
        lam = np.zeros_like(GU)
        rhs = np.empty(2 * nf)
        with quiet("invalid", "divide"):
            best, D_best = self._iterate(U, GU, lam, rhs, w2, kappa, C, D_best, solve, BtA,
                                         rhs_fixed, cancel, ask, alpha)
        return best, D_best, best is not None and D_best <= C

    def _iterate(self, U, GU, lam, rhs, w2, kappa, C, D_best, solve, BtA, rhs_fixed, cancel,
                 ask=None, alpha=ALPHA):
        """``run``'s iterations, on its buffers (U, GU, lam, rhs updated in place)."""
        free, nf = self.solver.free, len(self.solver.free)

        def step():
            Z = project_framed(GU + lam, w2, kappa)
            if alpha != 1.0:  # over-relaxation
                Z *= alpha
                Z += (1.0 - alpha) * GU
            Z -= lam                            # z - lam: the least-squares target
            BtA(Z.ravel(), rhs)
            np.subtract(rhs, rhs_fixed, out=rhs)
            U[0, free] = solve(rhs[:nf])
            U[1, free] = solve(rhs[nf:])
            self._lift(U, GU)
            np.subtract(GU, Z, out=lam)         # lam + G x - z
            self.iterations += 1

        watch = self._watch(D_best, ask, _complex)
        watch.iterate(step, lambda: self._max_distortion(GU), U.copy, C, cancel)
        self.ended, self.pending = watch.ended, watch.pending
        return watch.kept, watch.best

    def _run_free(self, U, w, kappa, C, D_best, cancel, ask=None, alpha=ALPHA):
        """``run`` on the free path (``on_free``: by default up to ONE_PRODUCT_FACES faces):
        ``free_admm.run_free``, the iterations on the free unknowns in every face's frame."""
        s, nf = self.solver, len(self.solver.free)
        self._operators()
        x0 = np.concatenate([U[0, s.free], U[1, s.free]])

        def whole(x):           # the map (2, nv) of free unknowns x, the fixed vertices of U
            V = U.copy()
            V[0, s.free], V[1, s.free] = x[:nf], x[nf:]
            return V

        watch = self._watch(D_best, ask, lambda x: _complex(whole(x)))
        best, D = run_free(self._free_lift(), s.factorize(), x0, w, kappa, C, watch, alpha,
                           cancel, self._count)
        self.ended, self.pending = watch.ended, watch.pending
        if best is None:
            return None, D, False
        return whole(best), D, D <= C

    def limit_effort(self):
        """Bound the search as ``bound="auto"`` bounds it on an unpinned island with no time
        budget, up to ``target_watch.EFFORT_FACES`` faces: from a start within EFFORT_START its
        iterations are within a budget growing with the faces (``target_watch.effort``), no
        target starting with fewer than LEAST_RUN of them left; up to FIRST_STALL_FACES faces its
        first target waits FIRST_STALL iterations."""
        if self.k <= target_watch.EFFORT_FACES:
            self.least = True
        if self.k <= target_watch.FIRST_STALL_FACES:
            self.first_stall = target_watch.FIRST_STALL

    def _watch(self, D_best, ask, to_u):
        """A target's ``Watch``: its iterations within the search's budget where it has one, the
        first target's STALL ``first_stall``; ``ask`` and ``check`` (``search``'s) asked of the
        map (nv,) complex ``to_u(kept)`` of an iterate kept."""
        limit = target_watch.MAX_ITER
        if self.budget is not None:
            limit = min(limit, self.budget - self.iterations)
        check = self.check
        return Watch(D_best, None if ask is None else lambda kept: ask(to_u(kept)), limit,
                     self.first_stall if self.iterations == 0 else target_watch.STALL,
                     None if check is None else lambda kept: check(to_u(kept)),
                     CHECK_AFTER_FRUITLESS and self._after_fruitless)

    def _count(self, n):
        self.iterations += n

    def search(self, u, frames_of=None, report=None, deadline=None, cancel=None, enough=None,
               ready=None, deep=False):
        """The least max distortion reached from the flip-free map u (nv,) complex.

        Parameters
        ----------
        frames_of : callable(u) -> (k,) unit frames of a map (eq. 4.21), optional: by default
            from the map's own lift (``frames.frames_from_map`` of its doubled alpha: one sparse
            product, not the island problem's two)
        report : callable(message), optional, called before each target
        deadline : float (``time.perf_counter()``) or None: no new target after it
        enough : callable(u) -> bool, optional: asked of each target's best map (nv,) complex
            at its end; True ends the search there (a bound asked for whose conformal map lay
            over itself: the first map that does not is enough, the least C is not sought)
        ready : callable(u) -> bool, optional, a cheap test that ``enough`` needs (a boundary
            loop's turning number): where given, ``enough`` is also asked within each target of
            every iterate that is the least yet and that ``ready`` passes, as soon as it is
            reached, until it refuses one (then the target's best at its end, as without it);
            one that ``ready`` refuses is not asked
        deep : bool, aim the cones deeper and over-relax more (UNFOLD_MARGIN, UNFOLD_ALPHA): for
            a search that ends at its first one-to-one map (the unfold), not the least C

        Returns
        -------
        u : (nv,) complex128, the best map (u itself when nothing was better)
        D : float, its max distortion
        out_of_time : bool, the deadline stopped the search
        """
        U = np.array([u.real, u.imag])
        D = self.distortion_of(u)
        if self.least:
            self.budget = target_watch.effort(self.k, D)
        step, small, short, fruitless = STEP, 0, False, False
        out_of_time = False
        flat = FLAT if enough is None else 0.0
        while np.isfinite(D) and D - 1.0 > flat:
            if self.budget is not None and self.iterations > self.budget - target_watch.LEAST_RUN:
                break               # the budget spent, or too little of it left for a target
            if deadline is not None and time.perf_counter() > deadline and self.iterations:
                out_of_time = True
                break
            C = 1.0 + (D - 1.0) * (1.0 - step)
            if report is not None:
                report(D, C)
            w = (frames_from_map(self._alpha2(U)) if frames_of is None
                 else frames_of(U[0] + 1j * U[1]))
            self._after_fruitless = fruitless
            Ub, Db, reached = self.run(U, w, C, D, cancel, enough, ready, deep)
            if cancel is not None and cancel.is_set():
                break
            gain = (D - Db) / (D - 1.0) if Ub is not None else 0.0
            fruitless = Ub is None
            if Ub is not None:
                U, D = Ub, Db
                if self.ended or (enough is not None and (ready is None or self.pending)
                                  and _ask(enough, ready, U[0] + 1j * U[1])):
                    break
            if reached:
                step = min(MAX_STEP, 1.5 * step)
                small, short = 0, False
                continue
            # within an effort budget a fruitless target counts as a small one (ZERO_SMALL),
            # and in a search the budget was spared from its start once its map is within
            # EFFORT_START (LATE_BUDGETED)
            zero = ZERO_SMALL and (self.budget is not None or (
                LATE_BUDGETED and self.least and D <= target_watch.EFFORT_START))
            overshot = OVERSHOT and Ub is None and step >= MAX_STEP
            step *= 0.5
            if overshot:
                continue
            small = small + 1 if (gain < SMALL if zero else 0.0 < gain < SMALL) else 0
            if step < TOLERANCE or small >= 2 or (AFTER_SHORT and zero and short and gain <= 0.0):
                break
            short = True
        return U[0] + 1j * U[1], D, out_of_time
