"""``uv.bd_unwrap``: Bounded Distortion unwrap of the selected faces of every mesh in Edit Mode.

``execute()`` solves synchronously (scripts, the redo panel, tests); ``invoke()`` solves in a
background :class:`~.worker.UnwrapJob`, polls it from a modal timer, shows progress in the status
bar, and Esc cancels leaving mesh and UVs exactly as they were (both from
:class:`~.background.BackgroundSolve`). Both end in ``_finish`` (write back, pack, colour,
report; ``unwrap_finish.py``) so they cannot drift apart. The menus' choices are in
``unwrap_items.py``.
"""
import functools

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty

from .. import bd_uv
from ..bd_uv.options import ENTRY_SEAMS_MODE
from . import auto_seams, needed_seams, session
from .background import BackgroundSolve
from .editmode import edit_mesh_objects, object_mode
from .pack import GROUP_ITEMS
from .unwrap_finish import UnwrapFinish
from .unwrap_items import _BOUNDARY, _FRAMES, _METHODS, _OVERLAP, _SEAMS

# The background job's solve function (tests substitute a gated one to control timing).
SOLVE = bd_uv.unwrap
# ... and with Seams "Add Where Needed".
AUTO_SOLVE = needed_seams.auto_repaired   # auto_seams.solve, a messy mesh repaired
# ... and with Seams "Add Where Needed" (the default).
NEEDED_SOLVE = needed_seams.solve
# The core's defaults (bd_uv.UnwrapOptions) are the operator's: one line there changes both.
# The operator's own: Limit (bound_limit) 100, where the core raises C up to 1000.
DEFAULTS = bd_uv.UnwrapOptions()
# The seams mode the entry points start in (bd_uv.options.ENTRY_SEAMS_MODE: "needed").
_SEAMS_ITEM = {"needed": 'NEEDED', "marked": 'MARKED', "auto": 'AUTO'}


class UV_OT_bd_unwrap(UnwrapFinish, BackgroundSolve, bpy.types.Operator):
    """Unwrap the selected faces with a certified bound on conformal distortion and no flipped
    faces (Bounded Distortion Mapping Spaces, Lipman 2012)"""

    bl_idname = "uv.bd_unwrap"
    bl_label = "Bounded Distortion"
    bl_options = {'REGISTER', 'UNDO'}
    JOB = "Bounded Distortion unwrap"
    CANCELLED = "Unwrap cancelled: mesh and UVs unchanged"

    method: EnumProperty(name="Method", items=_METHODS, default=DEFAULTS.method)
    seams: EnumProperty(name="Seams", items=_SEAMS,
                        default=_SEAMS_ITEM[ENTRY_SEAMS_MODE])
    overlap: EnumProperty(name="Overlaps", items=_OVERLAP, default=DEFAULTS.overlap.upper())
    boundary: EnumProperty(name="Boundary", items=_BOUNDARY, default=DEFAULTS.boundary)
    stretch: FloatProperty(name="Limit Stretch", default=DEFAULTS.seams_stretch, min=1.0,
                           soft_min=1.1,
                           soft_max=10.0,
                           description="Largest stretch allowed on any face, with each chart "
                           "scaled to its 3D area (both singular values within [1/S, S]; S must be "
                           "at least the square root of C). Add Where Needed always limits it; "
                           "with Marked seams, turn on Limit Stretch")
    atlas_cuts: BoolProperty(name="Atlas Cuts", default=DEFAULTS.atlas_cuts,
                             description="Where seams are added: also cut a chart the search "
                             "made in two where it alone limits how much of the texture the "
                             "packed charts cover (a torus's band, a long strip) and both pieces "
                             "pass; the report counts these cuts. Off: only the seams the "
                             "certificate needs. Islands of your marked seams are never cut for "
                             "the atlas")
    limit_stretch: BoolProperty(name="Limit Stretch", default=False,
                                description="Marked seams: also bound every face's singular "
                                "values to [1/S, S] (Lipman 2012, section 6.3), keeping texel "
                                "density even; Minimise only with Boundary Free")
    bound: FloatProperty(name="Bound C", default=DEFAULTS.bound, min=1.0001, soft_min=1.05,
                         soft_max=50.0,
                         description="Largest conformal distortion allowed on any face")
    minimise: BoolProperty(name="Minimise", default=False,
                           description="Find the smallest certified bound instead (optimal "
                           "quasi-conformal map; slower). With Add Where Needed, islands whose "
                           "smallest bound is over 5 get seams, each chart its smallest bound")
    raise_bound: BoolProperty(name="Raise C Automatically", default=DEFAULTS.raise_bound,
                              description="Seams Marked: when no map within C exists, raise C "
                              "up to the limit (with Add Where Needed such an island gets seams "
                              "instead, C is never raised)")
    bound_limit: FloatProperty(name="Limit", default=100.0, min=1.0001, soft_max=1000.0,
                               description="Largest bound tried when raising C")
    frames: EnumProperty(name="Frames", items=_FRAMES, default=DEFAULTS.frames)
    margin: FloatProperty(name="Margin", default=0.001, min=0.0, max=1.0,
                          description="Space between islands when packing")
    pack: BoolProperty(name="Pack Islands", default=True,
                       description="Pack the unwrapped islands with Blender's Pack Islands; "
                       "islands with pinned UVs stay where they are")
    pack_shape: EnumProperty(
        name="Packer", default='ATLAS',
        items=(('ATLAS', "Atlas (Bounded Distortion)", "bd-uv's packer: true shapes, turns "
                "only, padding in texels, the layout certified as written; Blender's packer "
                "(bounding box) when pinned islands must stay put"),
               ('AABB', "Bounding Box", "Blender's packer: fastest, like Blender's own Unwrap"),
               ('CONVEX', "Convex Hull", "Tighter than bounding boxes; can take seconds on "
                "thousands of faces, sometimes longer than Exact Shape"),
               ('CONCAVE', "Exact Shape", "Tightest; can take seconds on thousands of faces")),
        description="Which packer, and for Blender's the island shape it works with")
    pack_resolution: IntProperty(name="Resolution", default=1024, min=8, max=65536,
                                 description="Texture size the atlas padding is measured at")
    pack_padding: FloatProperty(name="Padding", default=4.0, min=0.0, soft_max=32.0,
                                description="Least gap between islands in texels (atlas packer)")
    pack_group: EnumProperty(name="Group", items=GROUP_ITEMS, default='none',
                             description="Atlas packer: pack the islands of one material or one "
                             "object together")
    show_distortion: BoolProperty(name="Colour by Distortion", default=False,
                                  description="Colour faces by their distortion afterwards")
    use_object_scale: BoolProperty(name="Use Object Scale", default=True,
                                   description="Unwrap the object as scaled in the scene (Blender's "
                                   "own unwrap ignores a non-uniform scale)")

    @classmethod
    def poll(cls, context):
        if edit_mesh_objects(context):
            return True
        # Shown in the disabled menu entry's tooltip and in the error of a scripted call.
        cls.poll_message_set("Needs a mesh in Edit Mode: select a mesh object, press Tab and "
                             "select the faces to unwrap")
        return False

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "method")
        layout.prop(self, "seams")
        if self.seams != 'MARKED':
            layout.prop(self, "atlas_cuts")
        if self.seams == 'AUTO':
            layout.prop(self, "stretch")
        else:
            layout.prop(self, "overlap")
            layout.prop(self, "boundary")
            row = layout.row(heading="Limit Stretch")
            row.prop(self, "limit_stretch", text="")
            sub = row.row()
            sub.active = self.limit_stretch or self.seams == 'NEEDED'  # added charts: always
            sub.prop(self, "stretch", text="")
        if self.seams == 'AUTO' or self.limit_stretch:
            problem = self._stretch_problem()
            if problem:
                layout.label(text=problem, icon='ERROR')
        layout.prop(self, "minimise")
        row = layout.row()
        row.active = not self.minimise
        row.prop(self, "bound")
        row = layout.row()
        row.active = self.seams == 'MARKED' and not self.minimise   # else seams or least C
        row.prop(self, "raise_bound")
        row = layout.row()
        row.active = self.raise_bound and not self.minimise and self.seams == 'MARKED'
        row.prop(self, "bound_limit")
        layout.prop(self, "frames")
        layout.prop(self, "use_object_scale")
        layout.prop(self, "pack")
        row = layout.row()
        row.active = self.pack
        row.prop(self, "pack_shape")
        atlas = self.pack_shape == 'ATLAS'
        for name in (("pack_resolution", "pack_padding", "pack_group") if atlas
                     else ("margin",)):
            row = layout.row()
            row.active = self.pack
            row.prop(self, name)
        layout.prop(self, "show_distortion")

    # -- shared --------------------------------------------------------------------------------
    def _prepare(self, context):
        """``BackgroundSolve``'s (state, solve, args, kwargs): the batch, and ``auto_seams.solve``
        (Seams "Add Where Needed") or ``bd_uv.unwrap`` with every polygon kept in one island (the
        core's overlap cut may split one); None after reporting why not."""
        gathered = self._gather(context)
        if gathered is None:
            return None
        batch, auto, args, kwargs = gathered
        if auto == 'NEEDED':
            solve = functools.partial(NEEDED_SOLVE, unwrap=SOLVE)
        elif auto:
            solve = AUTO_SOLVE
        else:
            solve = functools.partial(auto_seams.whole_polygons, SOLVE,
                                      **session.polygon_ids(batch))
        return batch, solve, args, kwargs


    def _gather(self, context):
        """Gather the batch, whether the seams are added (``auto_seams.solve``) and the solve's
        arguments, or report why not (returns None). With Seams "Add Where Needed" C is not
        raised: a chart that cannot be certified at C is cut further."""
        space = context.space_data
        pin_unselected = (space is not None and space.type == 'IMAGE_EDITOR'
                          and not context.scene.tool_settings.use_uv_select_sync)
        try:
            with object_mode(context) as objects:
                batch = session.gather(objects, pin_unselected_uvs=pin_unselected,
                                       use_object_scale=self.use_object_scale,
                                       need_uvs=(self.frames == 'input-uv'
                                                 and self.seams != 'AUTO'))
            if self.seams == 'NEEDED' and needed_seams.applies(
                    self.minimise, self.frames, self.boundary, len(batch.pin_corners)):
                problem = self._stretch_problem() if self.limit_stretch else ""
                if problem:
                    raise session.UserError(problem)
                args, kwargs = session.needed_arguments(
                    batch, method=self.method, bound=self.bound, stretch=self.stretch,
                    frames=self.frames, overlap='cut' if self.overlap == 'CUT' else 'fail',
                    limit_stretch=self.limit_stretch, atlas_cuts=self.atlas_cuts,
                    minimise=self.minimise)
                return batch, 'NEEDED', args, kwargs
            if self.seams == 'AUTO':
                args, kwargs = session.auto_arguments(
                    batch, method=self.method, bound=self.bound, minimise=self.minimise,
                    stretch=self.stretch, frames=self.frames, atlas_cuts=self.atlas_cuts)
                return batch, True, args, kwargs
        except session.UserError as error:
            self.report({'WARNING'}, str(error))
            return None
        problem = self._stretch_problem() if self.limit_stretch else ""
        if problem:
            self.report({'WARNING'}, problem)
            return None
        if self.boundary != 'free' and (self.minimise or self.frames == 'input-uv'):
            self.report({'WARNING'}, "A fixed boundary needs a bound C and the Auto frames: turn "
                        "off Minimise and From Current UVs, or set Boundary to Free")
            return None
        try:
            args, kwargs = session.unwrap_arguments(
                batch, method=self.method, bound=self.bound, minimise=self.minimise,
                raise_bound=self.raise_bound, bound_limit=self.bound_limit, frames=self.frames,
                overlap='cut' if self.overlap == 'CUT' else 'fail', boundary=self.boundary,
                stretch=self.stretch if self.limit_stretch else None)
        except session.UserError as error:
            self.report({'WARNING'}, str(error))
            return None
        return batch, False, args, kwargs

    def _stretch_problem(self):
        """Why Limit Stretch cannot run with these options ("" when it can)."""
        if self.seams == 'MARKED' and self.minimise and self.boundary != 'free':
            return "Limit Stretch with Minimise needs Boundary Free"
        if self.stretch ** 2 < self.bound * (1 - 1e-12) and not self.minimise:
            return (f"Limit Stretch {self.stretch:g} cannot hold with C = {self.bound:g}: "
                    f"raise it to at least sqrt(C) = {self.bound ** 0.5:.4g} or lower C")
        return ""


classes = (UV_OT_bd_unwrap,)
