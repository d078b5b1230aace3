"""One island's bounded-distortion problem: normalised geometry, operators, pins, the measures of a
map and its formulation (anchors, scale floor, energy weights and scale).

The variables are the island's vertex UVs ``u`` (complex, ``x = [Re u; Im u]``). A solve minimises
an energy over F_C (Lipman 2012, eqs. 4.15-4.18) for given frames ``w``, with some vertices held
fixed ("anchors"): the user's pins, or the two far boundary vertices of a start map kept where that
map has them (see ``anchor_to``), so that the scale of the result is the start's and no global floor
on the scale is needed. The conic programs and their solves are ``conic_solves.ConicSolves``',
which ``IslandProblem`` inherits.
"""
import dataclasses
import time

import numpy as np
import scipy.sparse as sp

from ..energies import energy, jacobian_operators
from ..errors import InfeasibleError
from ..frames import _far_pair, frames_from_map, lscm_map
from ..geometry import face_areas, local_coordinates
from ..array_calls import quiet
from ..overlap import island_overlaps
from ..solvers.free_admm import sparse_product
from .conic_solves import ConicSolves
from .disk_certificate import simple_ccw_loop, turning
from .margins import STORE_HEADROOM


def normalised(Vi, area3d):
    """An island's vertices Vi (nv,3) centred and scaled to unit total area (area3d its area):
    huge or tiny coordinates solve alike."""
    # sum / n: mean()'s arithmetic (the same reduction, the same division) without its wrapper
    return (Vi - Vi.sum(axis=0) / len(Vi)) / np.sqrt(area3d)


# Maps whose per-face distortion an ``IslandProblem`` keeps (``face_distortion``)
MEASURED = 4


class IslandProblem(ConicSolves):
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
        # callable(u) -> bool or None: the bound search ends at the first best map it accepts
        # (``island_solve.unfolder``: a map that does not lie over itself), and the cheap test
        # it needs, asked first of every iterate that is the least yet (``BoundSearch.search``)
        self.enough = self.ready = None
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
    def _times(self, x, *which):
        """The products ``M @ x`` of the operators named (``ops``' csr "Are", "Aim", "Bre",
        "Bim") with x (2nv,) float64: the compiled product scipy's ``@`` calls, into zeros, the
        same bits without its dispatch (~10 us a product; a distortion takes four)."""
        prods = self.__dict__.get("_prods")
        if prods is None:
            prods = self._prods = {}
            for n in ("Are", "Aim", "Bre", "Bim"):
                M = getattr(self.ops, n)
                prods[n] = (M.data, sparse_product("csr", M.shape, M.indptr, M.indices))
        k = len(self.ops.area)
        out = []
        for n in which:
            data, product = prods[n]
            y = np.zeros(k)
            product(data, x, y)
            out.append(y)
        return out

    def alpha(self, u):
        x = np.concatenate([u.real, u.imag])
        ar, ai = self._times(x, "Are", "Aim")
        return ar + 1j * ai

    def beta(self, u):
        x = np.concatenate([u.real, u.imag])
        br, bi = self._times(x, "Bre", "Bim")
        return br + 1j * bi

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
        """Conformal distortion per face (eq. 4.9); inf where a face flips or collapses (a new
        array). A map equal to one of the last MEASURED measured is not measured again (the
        same function of the same numbers: its answer kept; ``strategies.least_one_to_one``
        measures each target's best, ``minimise`` the one it returns again, ``mean_relax`` its
        mean: 1-3 measures a call, ~0.15 ms each on a 1,595-face disk)."""
        kept = self.__dict__.get("_measured")
        if kept is None:
            kept = self._measured = []
        for v, D in kept:
            if v.shape == u.shape and np.logical_and.reduce(v == u):
                return D.copy()
        D = self._face_distortion(u)
        kept.append((np.array(u, dtype=np.complex128), D.copy()))
        del kept[:-MEASURED]
        return D

    def _face_distortion(self, u):
        """``face_distortion`` measured."""
        # one concatenation for both; np.abs of the complex numbers (np.hypot of their parts
        # differs from it in the last bits)
        ar, ai, br, bi = self._times(np.concatenate([u.real, u.imag]), "Are", "Aim", "Bre",
                                     "Bim")
        a, b = np.abs(ar + 1j * ai), np.abs(br + 1j * bi)
        with quiet("invalid", "divide"):
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

    def may_be_one_to_one(self, u):
        """A cheap test that ``one_to_one`` needs (the unfold asks it of every iterate that is
        the least yet): may every boundary loop of the map u be simple? Simple loops turn once
        each (``turning``), counter-clockwise for the outer one, clockwise for the holes."""
        loops = self.island.loops
        turns = [turning(u.take(loop)) for loop in loops]
        return None in turns or (all(abs(t) == 1 for t in turns)
                                 and sum(turns) == 2 - len(loops))

    def lays_out(self, u):
        """Does the flip-free map u (nv,) complex lay the island out without overlapping
        itself? A flip-free map of a disk is one to one where its boundary is a simple polygon
        wound counter-clockwise (Lipman 2012, Theorem 5.1): the loop's test alone
        (``disk_certificate.simple_ccw_loop``, ~0.17 ms on a 1,324-face disk), not the island's
        whole overlap test (``one_to_one``, ~2.2 ms there); a loop that does not turn once is
        refused at once (``may_be_one_to_one``). Islands with holes: ``one_to_one``."""
        if not self.may_be_one_to_one(u):
            return False
        loops = self.island.loops
        return bool(simple_ccw_loop(np.stack([u.real, u.imag], axis=1).take(loops[0], axis=0))
                    if len(loops) == 1 else self.one_to_one(u))

    def one_to_one(self, u):
        """Does the flip-free map u (nv,) complex lay the island out without overlapping itself
        (``overlap.island_overlaps``: no boundary crossing, every loop wound as it should)?"""
        tris = self.island.tris
        corner_uv = np.stack([u.real, u.imag], axis=1).take(tris, axis=0)
        return bool(island_overlaps(tris, corner_uv, np.zeros(len(tris), np.int64), 1)
                    .overlap_free[0])
