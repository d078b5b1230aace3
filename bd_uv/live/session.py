"""``LiveSession``: interactive planar deformation of one island by its pins, every frame certified
(Lipman 2012, section 6.1, solved by projection iterations: Kovalsky, Galun and Lipman 2015).

Set up once per session: the rest shape, its per-face gradient operators and boundary loops (the
frame certificate, ``certificate``), and per pin set one factorisation of the global matrix shared
by the energy's local/global steps and the projection iterations (``steps``). A frame, for the
pins' new targets:

1. the last certified frame moved by the similarity that takes its pins nearest to the targets
   (exact for two pins), its pins then put on their targets;
2. from it, a few local/global steps of the energy; when that map is not certified, projection
   iterations until every face is within C (projecting onto 0.9 C);
3. the result is certified from its own coordinates. When it fails (or the iterations ran out),
   the frame is the certified map nearest to it found on the segment from step 1's map (which
   is certified whenever the last frame was: distortion and overlap do not change under a
   similarity; it is checked all the same), by bisection: the pins as close as it got,
   ``pin_error`` saying how close. The next call goes on projecting from where this one stopped,
   so a target held still keeps converging; no frame is ever uncertified, and none jumps back to
   the rest shape.
"""
import threading
import time

import numpy as np
from scipy.sparse.csgraph import connected_components
import scipy.sparse as sp

from ..errors import (CancelledError, DegenerateFacesError, InvalidMeshError, OptionError,
                      OverlapError)
from .certificate import FrameCertificate
from .frame import LiveFrame, SessionClosedError
from .rest import conformal_rest
from .steps import LIVE_METHODS, _PinSet, apply_similarity, pin_similarity, project_frame

__all__ = ["LiveFrame", "LiveSession", "SessionClosedError"]

BISECTIONS = 6          # steps of the search for the certified map nearest an uncertified one


class LiveSession:
    """Drag pins of one island and get a certified bounded-distortion map each frame.

    Parameters
    ----------
    V : (n,3) or (n,2) float, the island's vertices
    F : (k,3) int, its triangles (one connected disk, possibly with holes)
    pins : (p,) int, pinned vertices (distinct, at least one, at least one vertex free)
    bound : float C > 1, the conformal distortion bound against the rest shape (eq. 4.9)
    method : "arap" | "lscm" | "dirichlet" (see ``steps``)
    rest_uv : (n,2) float, the rest shape (every face counter-clockwise, overlap-free); default:
        the island's conformal map (LSCM) scaled to its 3D area, or ``V`` itself when 2D
    energy_steps : int, local/global steps of the energy per frame
    max_iterations : int, projection iterations per frame at most
    backend : factorisation backend (``solvers.factor.factor_spd``)
    storage : None or a float dtype (``numpy.float32`` for Blender's UVs): every frame is rounded
        to it before it is certified, so the frame is certified as it will be stored; targets
        are rounded likewise (``pin_error`` is measured to the rounded targets)

    Attributes
    ----------
    frame : LiveFrame, the last certified frame (the rest shape at first)
    pins : (p,) int64, in the order ``update`` takes targets
    setup_seconds : float

    Raises
    ------
    InvalidMeshError (shapes, indices, not one connected island), DegenerateFacesError (rest
    faces flipped or of zero area), OverlapError (a rest shape that overlaps itself),
    InfeasibleError (no flip-free conformal rest shape), OptionError (options; a ValueError)
    """

    def __init__(self, V, F, pins, bound=5.0, method="arap", rest_uv=None, *, energy_steps=3,
                 max_iterations=40, backend="auto", storage=None):
        t0 = time.perf_counter()
        if method not in LIVE_METHODS:
            raise OptionError("method", f"method must be one of {LIVE_METHODS} for a live "
                              f"session, got {method!r}")
        if not (isinstance(bound, (int, float)) and 1.0 < bound < np.inf):
            raise OptionError("bound", f"bound must be a finite number > 1, got {bound!r}")
        V = np.asarray(V, dtype=np.float64)
        F = np.asarray(F)
        if V.ndim != 2 or V.shape[1] not in (2, 3) or F.ndim != 2 or F.shape[1] != 3 \
                or not len(F) or not np.issubdtype(F.dtype, np.integer):
            raise InvalidMeshError("a live session needs V (n,2) or (n,3) and F (k,3) int with "
                                   "at least one face")
        F = F.astype(np.int64)
        n = len(V)
        if F.min() < 0 or F.max() >= n:
            raise InvalidMeshError(f"face indices must be in 0..{n - 1}")
        adj = sp.coo_array((np.ones(3 * len(F)), (F.ravel(), np.roll(F, 1, 1).ravel())),
                           shape=(n, n))
        if connected_components(adj, directed=False)[0] != 1:
            raise InvalidMeshError("a live session takes one island: its faces must be "
                                   "connected and use every vertex")
        if rest_uv is None:
            rest = V[:, :2].copy() if V.shape[1] == 2 else conformal_rest(V, F)
        else:
            rest = np.asarray(rest_uv, dtype=np.float64)
            if rest.shape != (n, 2) or not np.all(np.isfinite(rest)):
                raise InvalidMeshError(f"rest_uv must be ({n}, 2) finite")
        e1, e2 = rest[F[:, 1]] - rest[F[:, 0]], rest[F[:, 2]] - rest[F[:, 0]]
        bad = np.flatnonzero(~(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] > 0))
        if len(bad):
            raise DegenerateFacesError(
                f"{len(bad)} faces of the rest shape are flipped or of zero area: distortion is "
                "measured against the rest shape, so it must be flip-free (unwrap the island "
                "first)", faces=bad)
        self.bound, self.method, self.n = float(bound), method, n
        self.F, self.rest = F, rest
        self.energy_steps, self.max_iterations = int(energy_steps), int(max_iterations)
        self.backend = backend
        self.storage = None if storage is None else np.dtype(storage)
        self.cert = FrameCertificate(rest, F, self.bound)
        start = self._stored(rest)
        first = self.cert.check(start)
        if first.flipped or not first.max_distortion <= self.bound:
            bad = np.flatnonzero(~(first.distortion <= self.bound))
            raise DegenerateFacesError(
                f"{len(bad)} faces of the rest shape flip or exceed C once rounded to "
                f"{self.storage}: they are too small to store at this scale; rescale the UVs or "
                "clean the mesh up", faces=bad)
        if not first.certified:
            raise OverlapError("the rest shape overlaps itself: a live session starts from an "
                               "overlap-free island (cut it or mark seams)")
        self._U = start.copy()
        self._cancel = threading.Event()
        self._closed = False
        self._pin_sets = {}
        self._work = self._work_pins = None     # the uncertified iterate a short frame stopped at
        self.set_pins(pins)
        self.frame = LiveFrame(start.copy(), True, first.max_distortion, 0, 0, 0.0, 0.0, 0,
                               first.distortion)
        self.setup_seconds = time.perf_counter() - t0

    # -- pins ----------------------------------------------------------------------------------
    def set_pins(self, pins):
        """Change the pinned vertices (``update`` then takes one target per pin, in this order).

        A pin set used before gets its factorisation back; the rest geometry, the certificate
        and the current frame are kept."""
        self._check_open()
        pins = np.asarray(pins).ravel()
        if not np.issubdtype(pins.dtype, np.integer) or not len(pins) \
                or len(np.unique(pins)) != len(pins) or pins.min() < 0 or pins.max() >= self.n:
            raise OptionError("pins", "pins must be distinct vertex indices in "
                              f"0..{self.n - 1}, at least one")
        if len(pins) >= self.n:
            raise OptionError("pins", "every vertex is pinned: nothing is free to follow the pins")
        pins = pins.astype(np.int64)
        key = tuple(np.sort(pins))
        if key not in self._pin_sets:
            self._pin_sets[key] = _PinSet(self.cert.G, self.cert.area, np.array(key),
                                          self.backend)
        self._set = self._pin_sets[key]
        self.pins = pins

    # -- frames --------------------------------------------------------------------------------
    def update(self, targets):
        """The certified frame for the pins' new targets (p,2), one per pin in ``pins`` order.

        Returns
        -------
        LiveFrame (also kept as ``frame``)

        Raises
        ------
        OptionError (targets' shape, non-finite), CancelledError (``cancel`` was called; the
        session keeps its last frame), SessionClosedError
        """
        self._check_open()
        t0 = time.perf_counter()
        try:
            T = np.asarray(targets, dtype=np.float64)
        except (TypeError, ValueError):   # text, ragged lists: not numbers
            T = np.full(0, np.nan)
        if T.shape != (len(self.pins), 2) or not np.all(np.isfinite(T)):
            raise OptionError("targets", f"targets must be ({len(self.pins)}, 2) finite: one "
                              "per pin")
        try:
            # targets dragged out to the overflow range (1e300; beyond float32 storage's 3.4e38)
            # give inf and NaN on the way: such a map is not certified and the frame falls back
            # to the nearest certified one (step 3 of _solve), so numpy's warnings only spoke
            # of arithmetic the certificate already refuses
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                T = self._stored(T)
                U, check, its = self._solve(T)
        except CancelledError:
            self._cancel.clear()
            raise
        self._U = U
        err = float(np.max(np.hypot(*(U[self.pins] - T).T)))
        self.frame = LiveFrame(U.copy(), True, check.max_distortion, 0, 0, err,
                               time.perf_counter() - t0, its, check.distortion)
        return self.frame

    def _stored(self, X):
        """``X`` rounded to the storage dtype (as float64), or ``X`` itself."""
        if self.storage is None:
            return X
        return X.astype(self.storage).astype(np.float64)

    def _solve(self, T):
        prev, cert, pins = self._U, self.cert, self.pins
        # 1. The similarity of the pins applied to the last frame (certified with it).
        s, t = pin_similarity(prev[pins], T)
        moved = None
        if abs(s) > 0:
            moved = apply_similarity(prev, s, t)
            size = float(np.ptp(moved, axis=0).max())
            if np.all(np.hypot(*(moved[pins] - T).T) <= 1e-12 * size):
                moved[pins] = T
            moved = self._stored(moved)
        start = (prev if moved is None else moved).copy()
        start[pins] = T
        # 2. The energy's steps, then, unless that is certified already, projection onto the
        # bounded-distortion set; when the last frame fell short of its pins, the projection goes
        # on from where it stopped.
        ps = self._set
        if self._work is not None and self._work_pins is ps:
            U, its = self._work, 0
            U[pins] = T
            check = None
        else:
            U = ps.steps.iterate(self.method, start, self.energy_steps, self._cancel)
            its = 1 if self.method == "dirichlet" else self.energy_steps
            U[pins] = T
            U = self._stored(U)
            check = cert.check(U, prev)
        self._work = None
        if check is None or not check.certified:
            U, _, n_it = project_frame(ps.steps, U, self.bound, self.max_iterations,
                                       cancel=self._cancel)
            its += n_it
            U[pins] = T
            U = self._stored(U)
            check = cert.check(U, prev)
        if check.certified:
            return U, check, its
        # 3. The nearest certified map on the segment from step 1's map (or the last frame).
        self._work, self._work_pins = U, ps
        base, base_check = prev, None
        if moved is not None:
            c = cert.check(moved)
            if c.certified:
                base, base_check = moved, c
        if base_check is None:
            base_check = cert.check(prev, prev)
        lo, hi, best, best_check = 0.0, 1.0, base, base_check
        for _ in range(BISECTIONS):
            if self._cancel.is_set():
                raise CancelledError("live frame cancelled")
            mid = 0.5 * (lo + hi)
            trial = self._stored(base + mid * (U - base))
            c = cert.check(trial, base)
            if c.certified:
                lo, best, best_check = mid, trial, c
            else:
                hi = mid
        return best, best_check, its

    # -- ending --------------------------------------------------------------------------------
    def cancel(self):
        """Stop an ``update`` under way in another thread: it raises ``CancelledError`` and the
        session keeps its last certified frame. Called between updates, the next one stops."""
        self._cancel.set()

    def close(self):
        """Release the factorisations; later calls raise ``SessionClosedError``."""
        self._cancel.set()
        self._closed = True
        self._pin_sets.clear()
        self._set = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _check_open(self):
        if self._closed:
            raise SessionClosedError("this live session was closed; start a new one")
