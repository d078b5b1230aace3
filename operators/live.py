"""``uv.bd_live``: drag pinned UVs and the island follows, every frame certified within C.

G-style grab in the UV editor: the selected pinned UVs follow the mouse (X / Y constrain the move
to one axis, Ctrl snaps it to 1/64), the other pinned UVs stay, and the island's other UVs follow
with no flipped face, no overlap and every face's conformal distortion against the layout the drag
started from within C (``bd_uv.LiveSession``). The solve runs off the UI thread
(``live_edit.LiveWorker``): a target superseded while a frame is solved is dropped, and the UVs
shown are always the newest certified frame, the island drawn over them coloured by distortion
(``live_overlay``). The header shows C, the max distortion and the pin
error. Enter or left click confirms (one undo step, after the stored UVs pass the certificate
again), Esc or right click puts every UV back bit for bit.

Headless Blender has no event loop: ``LiveDrag`` and ``handle_event`` are the modal operator's
whole step logic (event -> target -> frame -> written UVs) and the tests call them directly.
"""
import numpy as np

import bpy
from bpy.props import EnumProperty, FloatProperty, FloatVectorProperty

from .. import bd_uv
from .edit_uvs import read_edit_uvs, write_loop_uvs
from .live_edit import LiveInputError, LiveIsland, LiveWorker, grab_offset
from .live_overlay import DistortionOverlay

_METHODS = (
    ('arap', "BD-ARAP", "As-rigid-as-possible: keeps lengths and areas of the layout"),
    ('lscm', "BD-LSCM (ASAP)", "As-similar-as-possible: keeps angles"),
    ('dirichlet', "BD-Dirichlet", "Smoothest map (harmonic energy) within C"),
)
CONFIRM_WAIT = 2.0      # seconds to wait, on confirm, for the frame of the last target
HOLD_FRAMES = 30        # execute(): frames at the target at most, until the pins meet it


class LiveDrag:
    """One live drag of the edit object's selected pinned UVs.

    Parameters
    ----------
    context : bpy.types.Context with a mesh in Edit Mode
    bound : float C, method : str
    background : bool, solve in a worker thread (the modal tool) or in the caller (scripts)

    Raises
    ------
    bd_uv.BDError (LiveInputError and the session's errors) with the reason in the user's terms
    """

    def __init__(self, context, bound=5.0, method="arap", background=True):
        self.obj = context.edit_object
        if self.obj is None or self.obj.type != 'MESH':
            raise LiveInputError("needs a mesh in Edit Mode")
        sync = context.scene.tool_settings.use_uv_select_sync
        self.data = read_edit_uvs(self.obj, sync)
        if self.data is None:
            raise LiveInputError(f"{self.obj.name} has no UV map: unwrap it first")
        self.island = LiveIsland(self.data.V, self.data.F, self.data.corner_uv,
                                 self.data.pinned, self.data.selected, bound, method)
        self.bound = float(bound)
        self.original = self.data.corner_uv[self.island.faces].copy()   # float32 values
        self.worker = LiveWorker(self.island) if background else None
        self.frame = self.island.session.frame
        self.start_mouse = None
        self.axis, self.snap = None, False
        self.offset = np.zeros(2)
        self.seq = -1
        self.overlay = None             # a DistortionOverlay when drawn in a window

    # -- event -> target -> frame -> UVs --------------------------------------------------------
    def move(self, mouse_uv):
        """The mouse at ``mouse_uv`` (UV space): the grab's new target is solved (queued to the
        worker, or here) and the frame shown."""
        if self.start_mouse is None:
            self.start_mouse = np.asarray(mouse_uv, dtype=np.float64)
        self.offset = grab_offset(self.start_mouse, mouse_uv, self.axis, self.snap)
        if self.worker is None:
            self.show(self.island.frame_for(self.offset))
        else:
            self.seq = self.worker.submit(self.offset)

    def poll(self):
        """Show the newest frame the worker finished, if any; True when one was shown."""
        got = self.worker.take() if self.worker is not None else None
        if got is None:
            if self.worker is not None and self.worker.error is not None:
                raise self.worker.error
            return False
        self.show(got[1])
        return True

    def show(self, frame):
        """Write a certified frame's UVs to the island's loops."""
        corner = self.island.corner_uvs(frame)
        write_loop_uvs(self.obj, self.data, self.island.faces, corner)
        if self.overlay is not None:
            self.overlay.update(corner, frame.distortion, self.bound)
        self.frame = frame

    def header(self):
        f = self.frame
        axis = f", along {self.axis}" if self.axis else ""
        return (f"Bounded Distortion Live: C {self.bound:g}, max distortion "
                f"{f.max_distortion:.3f}, pin error {f.pin_error:.3g}{axis}"
                f"{', snapping' if self.snap else ''} | X/Y axis, Ctrl snap, Enter confirm, "
                "Esc cancel")

    # -- ending ---------------------------------------------------------------------------------
    def confirm(self):
        """Show the frame of the last target, check the stored UVs and keep them.

        Returns
        -------
        (ok, message): ok False when the stored UVs failed the certificate (then put back)
        """
        if self.worker is not None:
            if self.seq >= 0:
                got = self.worker.wait(self.seq, CONFIRM_WAIT)
                if got is not None:
                    self.show(got[1])
            self.worker.stop()
            self.worker = None
        stored = np.array([[lp[self.data.layer].uv[:] for lp in self.data.tri_loops[f]]
                           for f in self.island.faces.tolist()], dtype=np.float32)
        ok, mx = stored_certificate(self.island, stored.astype(np.float64), self.bound)
        if not ok:
            self.restore()
            return False, ("the stored UVs failed the certificate (float32 rounding); the island "
                           "was put back as it was")
        f = self.frame
        return True, (f"Bounded Distortion Live: max distortion {mx:.3f} <= {self.bound:g}, 0 "
                      f"flipped, no overlap, pin error {f.pin_error:.3g}")

    def cancel(self):
        """Put every UV of the island back bit for bit and end the worker."""
        if self.worker is not None:
            self.worker.stop()
            self.worker = None
        self.restore()
        self.end_overlay()

    def end_overlay(self):
        if self.overlay is not None:
            self.overlay.remove()
            self.overlay = None

    def restore(self):
        write_loop_uvs(self.obj, self.data, self.island.faces, self.original)


def stored_certificate(island, stored, bound):
    """The UVs as stored (k,3,2), checked against the rest layout: (certified, max distortion).
    Corners of one UV vertex may differ after float32 rounding only if the frame did; the
    boundary is found from the stored corners themselves (``bd_uv.island_overlaps``)."""
    rest = island.rest_corner_uv
    V = np.column_stack([rest.reshape(-1, 2), np.zeros(3 * len(rest))])
    F = np.arange(3 * len(rest)).reshape(-1, 3)
    D = bd_uv.conformal_distortion(V, F, stored)
    flips = int(bd_uv.flipped_faces(V, F, stored).sum())
    ov = bd_uv.island_overlaps(island.tris, stored, np.zeros(len(stored), dtype=np.int64), 1)
    mx = float(D.max())
    return bool(flips == 0 and mx <= bound and ov.overlap_free[0]), mx


def handle_event(drag, event_type, value, mouse_uv, ctrl=False):
    """One modal event of the tool.

    Parameters
    ----------
    drag : LiveDrag
    event_type, value : str, Blender's ``event.type`` and ``event.value``
    mouse_uv : (2,) float, the mouse in UV space
    ctrl : bool, Ctrl held (snap)

    Returns
    -------
    "RUNNING" | "CONFIRM" | "CANCEL" (the operator then confirms or cancels)
    """
    if event_type in {'ESC', 'RIGHTMOUSE'} and value == 'PRESS':
        return "CANCEL"
    if event_type in {'RET', 'NUMPAD_ENTER', 'LEFTMOUSE'} and value == 'PRESS':
        return "CONFIRM"
    if event_type in {'X', 'Y'} and value == 'PRESS':
        drag.axis = None if drag.axis == event_type else event_type
        drag.move(mouse_uv)
    elif event_type in {'LEFT_CTRL', 'RIGHT_CTRL'} or event_type == 'MOUSEMOVE':
        drag.snap = bool(ctrl)
        drag.move(mouse_uv)
    elif event_type == 'TIMER':
        drag.poll()
    return "RUNNING"


class UV_OT_bd_live(bpy.types.Operator):
    """Drag the selected pinned UVs; the island follows with every frame certified: no flipped
    face, no overlap, conformal distortion within C"""

    bl_idname = "uv.bd_live"
    bl_label = "Bounded Distortion Live"
    bl_options = {'REGISTER', 'UNDO', 'BLOCKING', 'GRAB_CURSOR'}

    method: EnumProperty(name="Method", items=_METHODS, default='arap')
    bound: FloatProperty(name="Bound C", default=5.0, min=1.0001, soft_min=1.05, soft_max=50.0,
                         description="Largest conformal distortion of any face against the "
                         "layout the drag starts from")
    offset: FloatVectorProperty(name="Offset", size=2, default=(0.0, 0.0),
                                description="Move of the selected pinned UVs (UV units)")

    @classmethod
    def poll(cls, context):
        obj = context.edit_object
        if obj is not None and obj.type == 'MESH':
            return True
        cls.poll_message_set("Needs a mesh in Edit Mode: pin UVs, select some and drag")
        return False

    def execute(self, context):
        """The drag to ``offset`` without events (scripts, redo): frames until the pins meet it."""
        try:
            drag = LiveDrag(context, self.bound, self.method, background=False)
            frame = drag.island.frame_for(self.offset)
            for _ in range(HOLD_FRAMES):
                if frame.pin_error == 0:
                    break
                frame = drag.island.frame_for(self.offset)
            drag.show(frame)
        except bd_uv.BDError as error:
            self.report({'WARNING'}, f"Bounded Distortion Live: {error}")
            return {'CANCELLED'}
        ok, message = drag.confirm()
        self.report({'INFO'} if ok else {'WARNING'}, message)
        return {'FINISHED'} if ok else {'CANCELLED'}

    def invoke(self, context, event):
        try:
            self._drag = LiveDrag(context, self.bound, self.method)
        except bd_uv.BDError as error:
            self.report({'WARNING'}, f"Bounded Distortion Live: {error}")
            return {'CANCELLED'}
        self._drag.start_mouse = self._uv(context, event)
        try:
            self._drag.overlay = DistortionOverlay()
        except (ImportError, RuntimeError, SystemError, ValueError):
            self._drag.overlay = None                   # no GPU context: the UVs alone
        self._drag.show(self._drag.frame)
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.01, window=context.window)
        wm.modal_handler_add(self)
        context.area.header_text_set(self._drag.header())
        return {'RUNNING_MODAL'}

    def modal(self, context, event):
        drag = self._drag
        try:
            state = handle_event(drag, event.type, event.value, self._uv(context, event),
                                 event.ctrl)
        except bd_uv.BDError as error:
            drag.cancel()
            return self._end(context, {'CANCELLED'}, {'WARNING'}, f"Bounded Distortion Live: "
                             f"{error}; the UVs were put back")
        if state == "CANCEL":
            drag.cancel()
            return self._end(context, {'CANCELLED'}, {'INFO'}, "Bounded Distortion Live "
                             "cancelled: the UVs are as they were")
        if state == "CONFIRM":
            ok, message = drag.confirm()
            return self._end(context, {'FINISHED'} if ok else {'CANCELLED'},
                             {'INFO'} if ok else {'WARNING'}, message)
        context.area.header_text_set(drag.header())
        context.area.tag_redraw()                       # the UVs and the overlay of a frame
        return {'RUNNING_MODAL'}

    def _end(self, context, result, level, message):
        self._drag.end_overlay()
        context.window_manager.event_timer_remove(self._timer)
        context.area.header_text_set(None)
        self.report(level, message)
        return result

    @staticmethod
    def _uv(context, event):
        """The mouse in UV space (the UV editor's view), or in region pixels elsewhere."""
        region = context.region
        if region is not None and getattr(region, "view2d", None) is not None:
            return np.array(region.view2d.region_to_view(event.mouse_region_x,
                                                         event.mouse_region_y))
        return np.array([event.mouse_region_x, event.mouse_region_y], dtype=np.float64)


classes = (UV_OT_bd_live,)
