"""One island's bounded-distortion problem: normalised geometry, operators, pins, one conic solve.

The variables are the island's vertex UVs ``u`` (complex, ``x = [Re u; Im u]``). A solve minimises
an energy over F_C (Lipman 2012, eqs. 4.15-4.18) for given frames ``w``, with some vertices held
fixed ("anchors"): the user's pins, or the two far boundary vertices of a start map kept where that
map has them (see ``anchor_to``), so that the scale of the result is the start's and no global floor
on the scale is needed.
"""
import dataclasses
import time

import numpy as np
import scipy.sparse as sp

from ..energies import energy, jacobian_operators, stretch_l1_program
from ..errors import InfeasibleError, SolverError
from ..frames import _far_pair, frames_from_map, lscm_map
from ..geometry import face_areas, local_coordinates
from ..solvers import conic
from ..spaces import (bounded_distortion_space, distortion_epigraph_space, mean_scale_row,
                      stretch_space)

SOLVE_MARGIN = 2e-3      # solve at a C slightly below the bound so certification has headroom
# Relative headroom a certified bound keeps above the map's float64 distortion, so that the UVs
# still pass when stored as float32 (Blender) or packed into the unit square.
STORE_HEADROOM = 2e-4
RATIO_MAX_ITER = 12  # a Dinkelbach step's map is certified whatever the solver's status: 12 Clarabel
# iterations gave lion-head 1.650 then 1.590 (80: 1.650, 1.600; 8 or 10: stalls at 1.64), and
# loose tolerances stop earlier with the same map (mushroom: 8 iterations instead of 12, C 1.10996
# instead of 1.10995).
RATIO_TOL_GAP = 1e-3
RATIO_TOL_FEAS = 1e-4


def solve_bound(C):
    """The C a solve uses for a requested bound C: a little below it (SOLVE_MARGIN on C - 1, and
    STORE_HEADROOM relative), never below 1."""
    return max(1.0, min(1.0 + (C - 1.0) * (1.0 - SOLVE_MARGIN), C / (1.0 + STORE_HEADROOM)))


# With stretch bounds (section 6.3) a conic solve bounds the singular values by [m/S, S/m] at the
# held scale, first with this m (``stretch.stretch_solve`` grows it when the result misses).
STRETCH_MARGIN_SOLVE = 1.005


def normalised(Vi, area3d):
    """An island's vertices Vi (nv,3) centred and scaled to unit total area (area3d its area):
    huge or tiny coordinates solve alike."""
    return (Vi - Vi.mean(axis=0)) / np.sqrt(area3d)


class Cancelled(Exception):
    """Raised inside the unwrap when its cancel event is set."""


class IslandProblem:
    """One island's normalised geometry and operators; solves F_C for given frames.

    Parameters
    ----------
    island : mesh.Island
    V : (n,3) float64, the whole mesh's vertices
    pins : (corners (p,), uv (p,2)), the whole mesh's pinned corners
    method : "lscm" | "arap" | "dirichlet" | "biharmonic" | "stretch-l1"
    cone : "soc" | "linf"
    cancel : object with ``is_set()`` or None
    faces_3d : (G (k,2,3), A (k,)), optional, the faces' gradient operators and areas in the
        input geometry when known (``one_disk.Disk``: ``geometry.gradient_operators`` and
        ``face_areas``' bits): ``finish`` measures the final UVs with them

    ranks : (nv,) int64, optional, the island's vertices' elimination order when known
        (``one_disk.Disk.ranks``); the bound search finds it otherwise

    Attributes
    ----------
    faces_3d, ranks : as the parameters, or None
    """

    def __init__(self, island, V, pins, method, cone, cancel, faces_3d=None, ranks=None):
        self.island, self.ranks = island, ranks
        self.method, self.cone, self.cancel = method, cone, cancel
        self.faces_3d = faces_3d
        Vi = V[island.vertices]
        self.V = Vi
        self.area3d = float((face_areas(Vi, island.tris) if faces_3d is None
                             else faces_3d[1]).sum())
        self.Vn = normalised(Vi, self.area3d)
        self.nv = len(Vi)
        self.Z = local_coordinates(self.Vn, island.tris)
        self.ops = jacobian_operators(self.Z, island.tris, self.nv)
        self.pin_idx, self.pin_val = self._island_pins(pins)
        self.sigma = 1.0
        self.scale = 1.0
        self.weights = None
        # Section 6.3: (smin, smax) bounds on every face's singular values in the normalised
        # geometry, or None; with ``fix_scale`` the area-weighted mean of Re(w alpha) is held at 1
        # (``spaces.mean_scale_row``) instead of a second anchor fixing the scale.
        self.stretch = None
        self.fix_scale = False
        self.set_anchors(self.pin_idx if len(self.pin_idx) else np.array([0]),
                         self.pin_val if len(self.pin_idx) else np.array([0j]))
        self.solves = 0
        self.iterations = 0
        self.outcomes = []
        self.last_status = None
        self.timings = {"setup": 0.0, "solve": 0.0, "certify": 0.0}

    def _island_pins(self, pins):
        corners, uv = pins
        isl = self.island
        if not len(corners):
            return np.zeros(0, np.int64), np.zeros(0, np.complex128)
        face, k = corners // 3, corners % 3
        pos = np.full(isl.faces.max() + 1, -1, dtype=np.int64)
        pos[isl.faces] = np.arange(len(isl.faces))
        inside = face <= isl.faces.max()
        inside[inside] = pos[face[inside]] >= 0
        if not inside.any():
            return np.zeros(0, np.int64), np.zeros(0, np.complex128)
        vid = isl.tris[pos[face[inside]], k[inside]]
        val = uv[inside, 0] + 1j * uv[inside, 1]
        ids, first = np.unique(vid, return_index=True)
        clash = np.abs(val - val[first][np.searchsorted(ids, vid)]) > 0
        if clash.any():
            raise InfeasibleError(f"island {isl.index}: corners of one vertex are pinned to "
                                  "different UVs; unpin one of them or mark a seam there",
                                  isl.index)
        return ids, val[first]

    # -- the map's Jacobians -------------------------------------------------------------------
    def alpha(self, u):
        x = np.concatenate([u.real, u.imag])
        return self.ops.Are @ x + 1j * (self.ops.Aim @ x)

    def beta(self, u):
        x = np.concatenate([u.real, u.imag])
        return self.ops.Bre @ x + 1j * (self.ops.Bim @ x)

    def stretch_range(self, u):
        """(smallest sigma_2, largest sigma_1) of a map as the certificate measures them (Lipman
        2012, eqs. 4.7-4.8, 6.3-6.4): relative to the island's own scale (UV area = 3D area)
        when the map is scaled afterwards (fewer than two pins), else relative to the 3D geometry
        (the pins give the scale; ``alpha`` is taken on the unit-area copy of the island)."""
        a, b = np.abs(self.alpha(u)), np.abs(self.beta(u))
        area = self.ops.area
        if len(self.pin_idx) >= 2:
            s = np.sqrt(self.area3d)
        else:
            s = np.sqrt(max(float(np.sum(area * (a * a - b * b)) / np.sum(area)), 1e-300))
        return float(np.min(a - b)) / s, float(np.max(a + b)) / s

    def within(self, u, C, S=None):
        """Whether a map passes the certificate's tests here: no flip, distortion <= C, and (with
        S) singular values in [1/S, S] with room for storing the UVs (STORE_HEADROOM)."""
        if u is None or not self.check(u, C)[0]:
            return False
        if S is None:
            return True
        lo, hi = self.stretch_range(u)
        return lo >= (1 + STORE_HEADROOM) / S and hi * (1 + STORE_HEADROOM) <= S

    def face_distortion(self, u):
        """Conformal distortion per face (eq. 4.9); inf where a face flips or collapses."""
        a, b = np.abs(self.alpha(u)), np.abs(self.beta(u))
        with np.errstate(invalid="ignore", divide="ignore"):
            D = (a + b) / (a - b)
        D[~(a > b) | ~np.isfinite(D)] = np.inf
        return D

    def distortion(self, u):
        """Max distortion of a map (inf when any face flips)."""
        return float(np.max(self.face_distortion(u)))

    def mean_distortion(self, u):
        """Area-weighted mean distortion (inf when any face flips)."""
        D = self.face_distortion(u)
        return float(np.sum(self.ops.area * D) / np.sum(self.ops.area))

    def check(self, u, C):
        """Certify a map in the normalised geometry: (ok, max distortion)."""
        t = time.perf_counter()
        D = self.distortion(u) if u is not None else np.inf
        self.timings["certify"] += time.perf_counter() - t
        return D <= C * (1 + 1e-9), D

    def fallback_map(self):
        """The conformal map, for a formulation when the start gives frames only."""
        isl = self.island
        pins = (self.pin_idx, self.pin_val) if len(self.pin_idx) >= 2 else None
        return lscm_map(self.Z, isl.tris, self.nv, isl.loops, pins, ops=self.ops)

    # -- formulations --------------------------------------------------------------------------
    def set_anchors(self, idx, val):
        """Hold vertices ``idx`` at complex ``val`` in every solve."""
        nv = self.nv
        self.fixed = np.concatenate([idx, idx + nv])
        self.xfix = np.concatenate([np.real(val), np.imag(val)])
        free = np.ones(2 * nv, dtype=bool)
        free[self.fixed] = False
        self.free = np.flatnonzero(free)    # np.setdiff1d's answer without its sort

    def anchor_to(self, u_start):
        """Formulation that keeps a start map's scale: no global floor (issue 9).

        With fewer than two pins, the two boundary vertices about half the boundary apart stay
        where ``u_start`` has them; sigma (eq. 4.17) is tiny, so it only excludes collapsed faces,
        and ``u_start`` stays feasible (sigma below its smallest |alpha|). For BD-LSCM the energy
        of each face is weighted by ``1 / |alpha|`` of the start map: LSCM's absolute energy
        rewards shrinking distorted regions, which raises their share of the distortion; dividing
        by the local scale makes the energy closer to the mean conformal distortion (measured:
        three_peaks mean 1.346 against 1.378 unweighted, mannequin-devil 1.071 both, at C = 5).
        """
        a = np.abs(self.alpha(u_start))
        if len(self.pin_idx) >= 2:
            self.set_anchors(self.pin_idx, self.pin_val)
        else:
            isl = self.island
            idx, _ = _far_pair(self.Z, isl.tris, self.nv, isl.loops[0])
            if len(self.pin_idx) == 1:
                idx = np.unique(np.concatenate([self.pin_idx, idx]))
            self.set_anchors(idx, u_start[idx])
        typical = float(np.median(a))
        self.sigma = min(1e-3 * typical, 0.5 * float(a.min())) if typical > 0 else 1e-12
        if self.method == "lscm":
            self.weights = 1.0 / np.maximum(a, 1e-6 * typical)
        self._scale_objective(u_start, frames_from_map(self.alpha(u_start)))

    def floor_scale(self, u0, w0):
        """The first release's free-boundary formulation: sigma = 1 on the unit-area island with
        one anchor vertex. BD-Dirichlet needs it: its energy has no scale of its own, so without a
        floor its optimum collapses the map."""
        if len(self.pin_idx) >= 2:
            typical = np.median(np.abs(self.alpha(u0)))
            self.sigma = 1e-3 * typical if typical > 0 else 1e-8
            us = u0
        else:
            self.sigma = 1.0
            lo = np.real(w0 * self.alpha(u0)).min()
            us = u0 / lo if lo > 0 else u0
        self._scale_objective(us, w0)

    def _energy(self, w):
        if self.method == "stretch-l1":  # linear objective over epigraph variables: see solve
            return sp.csc_array((2 * self.nv, 2 * self.nv)), np.zeros(2 * self.nv), 0.0
        ops = self.ops if self.weights is None else dataclasses.replace(
            self.ops, area=self.ops.area * self.weights)
        return energy(self.method, ops, w)

    def _scale_objective(self, u, w):
        P, q, const = self._energy(w)
        x = np.concatenate([u.real, u.imag])
        e0 = 0.5 * x @ (P @ x) + q @ x + const
        self.scale = 1.0 / max(abs(e0), 1e-12) if self.method != "stretch-l1" else 1.0

    def energy_of(self, u, w):
        if self.method == "stretch-l1":
            return float(np.sum(self.ops.area * (np.abs(self.alpha(u)) + np.abs(self.beta(u)))))
        P, q, const = self._energy(w)
        x = np.concatenate([u.real, u.imag])
        return float(0.5 * x @ (P @ x) + q @ x + const)

    # -- solving -------------------------------------------------------------------------------
    def solver_failure(self):
        """A SolverError when no solve ever gave an answer (no certificate either way)."""
        if self.outcomes and not ({"solved", "infeasible"} & set(self.outcomes)):
            return SolverError(f"island {self.island.index}: the solver failed on every attempt "
                               f"(last status: {self.last_status}); try other frames or the "
                               "L-infinity space, or report the mesh", self.island.index)
        return None

    def hold_scale(self, u_start):
        """Formulation for stretch bounds and the L1 stretch energy on a free boundary: one anchor
        vertex (or the user's pins) and the island's scale held by ``spaces.mean_scale_row``
        (area-weighted mean of Re(w alpha) = 1 on the unit-area island: UV area close to 3D
        area, where the singular values are certified). Two anchors would fix the scale too, but
        at the start map's, which may be the wrong one for the bounds. With two or more pins the
        pins give the scale and nothing is added.
        """
        a = np.abs(self.alpha(u_start))
        typical = float(np.median(a))
        if len(self.pin_idx) >= 2:
            self.set_anchors(self.pin_idx, self.pin_val)
            self.fix_scale = False
        else:
            idx = self.pin_idx if len(self.pin_idx) else np.array([0])
            val = self.pin_val if len(self.pin_idx) else u_start[:1]
            self.set_anchors(idx, val)
            self.fix_scale = True
        self.sigma = min(1e-3 * typical, 0.5 * float(a.min())) if typical > 0 else 1e-12
        if self.method == "lscm":
            self.weights = 1.0 / np.maximum(a, 1e-6 * typical)
        self._scale_objective(u_start, frames_from_map(self.alpha(u_start)))

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
