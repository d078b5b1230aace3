"""The conic programs of one island's problem (``problem.IslandProblem``) and their solves.

F_C's rows (Lipman 2012, eqs. 4.15-4.18) at ``margins.solve_bound(C)``, with section 6.3's stretch
rows and the scale row where the formulation sets them, and the island's energy for the given
frames; the anchors substituted; one Clarabel solve (``solvers.conic``), its outcome counted. And
the Dinkelbach step lowering a flip-free map's max distortion (``ratio_step``, eq. 4.21).
"""
import time

import numpy as np
import scipy.sparse as sp

from ..energies import stretch_l1_program
from ..errors import SolverError
from ..frames import frames_from_map
from ..solvers import conic
from ..spaces import (bounded_distortion_space, distortion_epigraph_space, mean_scale_row,
                      stretch_space)
from .margins import solve_bound

RATIO_MAX_ITER = 12  # a Dinkelbach step's map is certified whatever the solver's status: 12 Clarabel
# iterations gave lion-head 1.650 then 1.590 (80: 1.650, 1.600; 8 or 10: stalls at 1.64), and
# loose tolerances stop earlier with the same map (mushroom: 8 iterations instead of 12, C 1.10996
# instead of 1.10995).
RATIO_TOL_GAP = 1e-3
RATIO_TOL_FEAS = 1e-4


class Cancelled(Exception):
    """Raised inside the unwrap when its cancel event is set."""


class ConicSolves:
    """The solves of ``problem.IslandProblem``, which inherits them: they read its operators
    (``ops``, ``nv``, ``alpha``, ``beta``), its formulation (the anchors ``free``, ``fixed`` and
    ``xfix``, ``sigma``, ``scale``, ``stretch``, ``fix_scale``, ``cone``, ``method``, ``_energy``)
    and ``cancel``, and count into its ``solves``, ``iterations``, ``outcomes``, ``last_status``
    and ``timings``.
    """

    def solver_failure(self):
        """A SolverError when no solve ever gave an answer (no certificate either way)."""
        if self.outcomes and not ({"solved", "infeasible"} & set(self.outcomes)):
            return SolverError(f"island {self.island.index}: the solver failed on every attempt "
                               f"(last status: {self.last_status}); try other frames or the "
                               "L-infinity space, or report the mesh", self.island.index)
        return None

    def solve(self, w, C, **settings):
        """Minimise the energy over F_C with frames w (eqs. 4.15-4.18), with the stretch rows of
        section 6.3 (eqs. 6.3-6.4, ``spaces.stretch_space``) when ``self.stretch`` is set and the
        scale row when ``self.fix_scale``; the L1 stretch energy ("stretch-l1") as a cone
        program (``energies.stretch_l1_program``). ``settings``: ``conic.solve_conic``'s
        ``max_iter``, ``tol_gap``, ``tol_feas`` (its defaults without). Returns (u or None,
        outcome)."""
        if self.cancel is not None and self.cancel.is_set():
            raise Cancelled
        t = time.perf_counter()
        if len(self.free) == 0:
            return self._pinned_map(), "solved"
        P, q, _ = self._energy(w)
        A, b, cones = self._space(w, C)
        extra = 0
        if self.method == "stretch-l1":  # epigraph unknowns after the 2nv vertex coordinates
            _, q, A, b, cones = stretch_l1_program(self.ops, A, b, cones)
            extra = A.shape[1] - 2 * self.nv
            P = sp.csc_array((A.shape[1], A.shape[1]))
            q = q / float(self.ops.area.sum())
        x, outcome = self._solve_reduced(P * self.scale, q * self.scale, A, b, cones, t, extra,
                                         **settings)
        if x is None:
            return None, outcome
        return x[:self.nv] + 1j * x[self.nv:2 * self.nv], outcome

    def _space(self, w, C):
        """F_C's rows (eqs. 4.15-4.18) at ``solve_bound(C)``, with the stretch rows (section
        6.3) and the scale row when set. Returns (A, b, cones)."""
        Cs = solve_bound(C)
        A, b, cones = bounded_distortion_space(self.ops, w, Cs, self.sigma, self.cone)
        if self.stretch is not None:
            As, bs, cs = stretch_space(self.ops, w, Cs, *self.stretch)
            A, b, cones = sp.vstack([A, As]).tocsc(), np.concatenate([b, bs]), cones + cs
        if self.fix_scale:
            Az, bz, cz = mean_scale_row(self.ops, w)
            A, b, cones = sp.vstack([Az, A]).tocsc(), np.concatenate([bz, b]), cz + cones
        return A, b, cones

    def ratio_step(self, u, eps):
        """One Dinkelbach step lowering the max conformal distortion of a flip-free map ``u``.

        Minimises ``t + eps k E(u')`` over maps u' with ``|beta_j| <= k Re(w_j alpha_j) + g_j t``,
        ``-k <= t <= 0`` (``spaces.distortion_epigraph_space``): frames w and scales
        ``g = |alpha|`` from ``u`` (eq. 4.21: ``Re(w alpha) = |alpha|`` there), k its max ratio
        ``|beta| / |alpha|`` (eqs. 4.9, 4.15; with ``cone="linf"`` the ratio of eq. 4.22's
        ``sqrt(2) max(|Re beta|, |Im beta|)``), E the island's energy scaled to 1 at the anchor
        map, anchors as ``anchor_to`` set them. ``u`` with ``t = 0`` is feasible, so the program
        is never empty; the energy term keeps faces away from the max near the energy's optimum
        (a low mean distortion).

        Returns (u' or None, outcome, C_model): C_model is the max distortion the program promises
        with u's scales, ``(1 + k + t) / (1 - k - t)``; certify u' from its UVs (its actual max
        is C_model when no face's scale changed, above it as far as the scales grew).
        """
        if self.cancel is not None and self.cancel.is_set():
            raise Cancelled
        t = time.perf_counter()
        if len(self.free) == 0:
            return self._pinned_map(), "solved", np.nan
        a, b = self.alpha(u), self.beta(u)
        g = np.abs(a)
        # the measure the rows bound (eq. 4.15, or 4.22's sqrt(2) max(|Re|, |Im|) >= |beta|), so
        # that u with t = 0 is feasible
        size = (np.abs(b) if self.cone != "linf"
                else np.sqrt(2.0) * np.maximum(np.abs(b.real), np.abs(b.imag)))
        k = float(np.max(size / g))
        w = frames_from_map(a)
        A, b, cones = distortion_epigraph_space(self.ops, w, k, g, self.cone)
        P, q, _ = self._energy(w)
        n = 2 * self.nv
        P = sp.block_diag([P * (self.scale * eps * k), sp.csc_array((1, 1))], format="csc")
        q = np.concatenate([q * (self.scale * eps * k), [1.0]])  # + t
        x, outcome = self._solve_reduced(P, q, A, b, cones, t, extra=1, max_iter=RATIO_MAX_ITER,
                                         tol_gap=RATIO_TOL_GAP, tol_feas=RATIO_TOL_FEAS)
        if x is None:
            return None, outcome, np.nan
        kt = k + x[n]
        return x[:self.nv] + 1j * x[self.nv:n], outcome, (1.0 + kt) / (1.0 - kt)

    def _pinned_map(self):
        x = np.zeros(2 * self.nv)
        x[self.fixed] = self.xfix
        return x[:self.nv] + 1j * x[self.nv:]

    def _solve_reduced(self, P, q, A, b, cones, t, extra=0, **settings):
        """Solve the conic program with the anchors substituted; ``extra`` trailing unknowns (after
        the 2nv vertex coordinates) stay free. Counts the solve. Returns (x or None, outcome)."""
        n = 2 * self.nv
        fr = np.concatenate([self.free, np.arange(n, n + extra)])
        fx = self.fixed
        P = sp.csc_array(P)
        A = sp.csc_array(A)
        Pff = P[:, fr][fr]
        qf = q[fr] + P[fr][:, fx] @ self.xfix
        Af = A[:, fr]
        bf = b - A[:, fx] @ self.xfix
        self.timings["setup"] += time.perf_counter() - t
        sol = conic.solve_conic(Pff, qf, Af, bf, cones, cancel=self.cancel, **settings)
        self.timings["solve"] += sol.seconds
        self.solves += 1
        self.iterations += sol.iterations
        self.outcomes.append(sol.outcome)
        self.last_status = sol.status
        if sol.outcome == "cancelled" and self.cancel is not None and self.cancel.is_set():
            raise Cancelled
        if sol.x is None:
            return None, sol.outcome
        x = np.zeros(n + extra)
        x[fx] = self.xfix
        x[fr] = sol.x
        return x, sol.outcome
