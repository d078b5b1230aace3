"""The step logic of ``uv.bd_live`` without ``bpy``: grab offsets, one island's live session and
the background solve that drops late targets.

An event becomes a target (``grab_offset``: the mouse's move since the grab started, constrained
to X or Y and snapped to an increment as Blender's transform does), the target a certified frame
(``LiveIsland.frame_for``, or ``LiveWorker`` off the UI thread), the frame the corner UVs written
(``LiveIsland.corner_uvs``). Blender's side (reading and writing the loops) is ``edit_uvs``.
"""
from __future__ import annotations

import threading

import numpy as np

from ..bd_uv.errors import BDError
from ..bd_uv.live import LiveSession
from .uv_deform import uv_islands

__all__ = ["grab_offset", "LiveIsland", "LiveWorker", "LiveInputError"]

SNAP_INCREMENT = 1.0 / 64.0      # Ctrl: the offset in steps of 1/64 of the UV square


class LiveInputError(BDError):
    """The selection cannot be dragged live (no pinned UV selected, pins on several islands,
    a layout that flips or overlaps); the message says what to do."""


def grab_offset(start, mouse, axis=None, snap=False, increment=SNAP_INCREMENT):
    """The grab's offset in UV space.

    Parameters
    ----------
    start, mouse : (2,) float, where the grab started and where the mouse is (UV space)
    axis : None | "X" | "Y", the constraint (X: only u moves, Y: only v)
    snap : bool, round each component to a multiple of ``increment``

    Returns
    -------
    (2,) float64
    """
    d = np.asarray(mouse, dtype=np.float64) - np.asarray(start, dtype=np.float64)
    if axis == "X":
        d[1] = 0.0
    elif axis == "Y":
        d[0] = 0.0
    elif axis is not None:
        raise ValueError(f"axis must be None, 'X' or 'Y', got {axis!r}")
    if snap:
        d = np.round(d / increment) * increment
    return d


class LiveIsland:
    """One UV island of a triangle batch set up for live dragging of its selected pinned UVs.

    Parameters
    ----------
    V : (n,3) float, mesh positions (not used by the solve: distortion is measured against the
        current UV layout, the rest shape)
    F : (m,3) int, triangles (mesh vertex ids)
    corner_uv : (m,3,2) float, current UVs
    pinned : (m,3) bool, pinned corners
    selected : (m,3) bool, selected corners (UV selection)
    bound : float C > 1, method : "arap" | "lscm" | "dirichlet"

    Attributes
    ----------
    faces : (k,) int64, the island's triangles (rows of F)
    pins : (p,) int64, its pinned UV vertices (local ids); moving : (p,) bool, the selected ones
    start : (p,2) float64, the pins' UVs when the drag began
    session : bd_uv.LiveSession

    Raises
    ------
    LiveInputError, or the session's typed errors (a rest layout that flips or overlaps)
    """

    def __init__(self, V, F, corner_uv, pinned, selected, bound=5.0, method="arap"):
        F = np.asarray(F, dtype=np.int64)
        corner_uv = np.asarray(corner_uv, dtype=np.float64)
        cv, uv, face_island = uv_islands(F, corner_uv)
        pinned = np.asarray(pinned, dtype=bool)
        grabbed = pinned & np.asarray(selected, dtype=bool)
        if not grabbed.any():
            raise LiveInputError("no pinned UV is selected: pin UVs (P), select the ones to "
                                 "drag and start again")
        isl = np.unique(face_island[grabbed.any(axis=1)])
        if len(isl) != 1:
            raise LiveInputError(f"the selected pinned UVs lie on {len(isl)} UV islands: drag "
                                 "one island at a time")
        self.faces = np.flatnonzero(face_island == isl[0])
        verts, tris = np.unique(cv[self.faces], return_inverse=True)
        self.tris = tris.reshape(-1, 3)
        self.corner_vertex = cv
        self.verts = verts
        local = np.full(len(uv), -1, dtype=np.int64)
        local[verts] = np.arange(len(verts))
        is_pin = np.zeros(len(verts), dtype=bool)
        is_pin[local[cv[self.faces][pinned[self.faces]]]] = True
        is_moving = np.zeros(len(verts), dtype=bool)
        is_moving[local[cv[self.faces][grabbed[self.faces]]]] = True
        self.pins = np.flatnonzero(is_pin)
        self.moving = is_moving[self.pins]
        rest = uv[verts]
        self.start = rest[self.pins].copy()
        self.rest_corner_uv = corner_uv[self.faces].copy()
        self.session = LiveSession(rest, self.tris, self.pins, bound=bound, method=method,
                                   rest_uv=rest, storage=np.float32)   # as Blender stores UVs
        self.V = np.asarray(V, dtype=np.float64)

    def targets(self, offset):
        """(p,2): the selected pins moved by ``offset`` (2,), the other pins where they were."""
        T = self.start.copy()
        T[self.moving] += np.asarray(offset, dtype=np.float64)
        return T

    def frame_for(self, offset):
        """The certified frame for a grab offset (synchronous: scripts, tests, confirm)."""
        return self.session.update(self.targets(offset))

    def corner_uvs(self, frame):
        """(k,3,2) float64, the island's corner UVs of ``frame`` (rows of ``faces``)."""
        return frame.uv[self.tris]


class LiveWorker:
    """Solves the newest target off the UI thread; targets superseded while a frame is solved
    are dropped, and a frame older than one already taken is never returned.

    Parameters
    ----------
    island : LiveIsland
    """

    def __init__(self, island):
        self.island = island
        self._cond = threading.Condition()
        self._pending = None            # (seq, offset) not yet started
        self._done = None               # (seq, frame) newest finished
        self._taken = -1                # seq of the last frame handed out
        self._busy = False
        self._submitted = -1
        self.error = None
        self.dropped = 0
        self._stop = False
        self._thread = threading.Thread(target=self._run, name="bd_uv live", daemon=True)
        self._thread.start()

    def submit(self, offset):
        """Queue a grab offset (replacing one not started yet); returns its sequence number."""
        with self._cond:
            if self._pending is not None:
                self.dropped += 1
            self._submitted += 1
            self._pending = (self._submitted, np.array(offset, dtype=np.float64))
            self._cond.notify_all()
            return self._submitted

    def take(self):
        """The newest finished frame not handed out yet, as (seq, frame), or None."""
        with self._cond:
            if self._done is None or self._done[0] <= self._taken:
                return None
            self._taken = self._done[0]
            return self._done

    def wait(self, seq, timeout=None):
        """Block until the frame of ``seq`` (or a newer one) is finished; returns (seq, frame) of
        the newest, or None on timeout or error (``error`` then says which)."""
        with self._cond:
            ok = self._cond.wait_for(lambda: self.error is not None or (
                self._done is not None and self._done[0] >= seq), timeout)
            if not ok or self.error is not None:
                return None
            self._taken = max(self._taken, self._done[0])
            return self._done

    def stop(self):
        """End the thread (an update under way is cancelled)."""
        with self._cond:
            self._stop = True
            self._cond.notify_all()
        self.island.session.cancel()
        self._thread.join()

    def _run(self):
        while True:
            with self._cond:
                self._cond.wait_for(lambda: self._stop or self._pending is not None)
                if self._stop:
                    return
                seq, offset = self._pending
                self._pending = None
                self._busy = True
            try:
                frame = self.island.frame_for(offset)
            except BDError as error:
                with self._cond:
                    if self._stop:
                        return
                    self.error = error
                    self._cond.notify_all()
                return
            with self._cond:
                self._busy = False
                if self._done is None or seq > self._done[0]:
                    self._done = (seq, frame)
                self._cond.notify_all()

    def _busy_started(self):
        """True while a frame is being solved (for tests)."""
        with self._cond:
            return self._busy
