"""Show and select distortion of any UV map (bd-uv's or one made by Blender's unwrappers).

``uv.bd_show_distortion`` writes, per mesh:

- ``"BD Distortion"``: FACE-domain float, the conformal distortion of each polygon (the largest
  over its triangles; ``inf`` for flipped or degenerate UVs), Lipman 2012 eq. 4.9;
- ``"BD Distortion Color"``: CORNER-domain float colour from ``bd_uv.distortion_colors`` (the
  paper's scheme, section 6.1), made the active colour attribute for display.

``uv.bd_select_distorted`` selects flipped polygons and polygons above a distortion.
"""
import bpy
import numpy as np
from bpy.props import BoolProperty, FloatProperty

from .. import bd_uv
from . import mesh_data
from .editmode import edit_mesh_objects, object_mode

DISTORTION_ATTRIBUTE = "BD Distortion"
COLOR_ATTRIBUTE = "BD Distortion Color"


def polygon_distortion(mesh, uv_name=None):
    """Conformal distortion and flips of each polygon of ``mesh`` under a UV map.

    Returns
    -------
    distortion : (P,) float64
        Largest distortion over the polygon's triangles (``inf`` when flipped or degenerate;
        NaN for a polygon without triangles).
    flipped : (P,) bool
        Some triangle of the polygon has a flipped or collapsed UV triangle.

    Raises
    ------
    ValueError when the mesh has no such UV map.
    """
    arrays = mesh_data.mesh_arrays(mesh, uv_name=uv_name)
    if arrays.corner_uv is None:
        raise ValueError(f"{mesh.name!r} has no UV map to measure")
    n_poly = len(mesh.polygons)
    distortion = np.full(n_poly, np.nan)
    flipped = np.zeros(n_poly, dtype=bool)
    if len(arrays.F):
        D = bd_uv.conformal_distortion(arrays.V, arrays.F, arrays.corner_uv)
        flips = bd_uv.flipped_faces(arrays.V, arrays.F, arrays.corner_uv)
        distortion[np.unique(arrays.tri_poly)] = -np.inf
        np.maximum.at(distortion, arrays.tri_poly, D)
        np.logical_or.at(flipped, arrays.tri_poly, flips)
    return distortion, flipped


def _loop_polygon(mesh):
    """(L,) int64: polygon index of every loop."""
    total = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_total", total)
    return np.repeat(np.arange(len(mesh.polygons), dtype=np.int64), total)


def _fresh_attribute(mesh, name, type_, domain):
    old = mesh.attributes.get(name)
    if old is not None and (old.data_type != type_ or old.domain != domain):
        mesh.attributes.remove(old)
        old = None
    return old if old is not None else mesh.attributes.new(name, type_, domain)


def write_distortion_attributes(mesh, bound, uv_name=None):
    """Write the distortion attributes of ``mesh`` (Object Mode) and make the colours active.

    Parameters
    ----------
    bound : float
        Distortion at which the ramp reaches full red (the bound C).

    Returns
    -------
    distortion : (P,) float64, flipped : (P,) bool -- as :func:`polygon_distortion`.
    """
    distortion, flipped = polygon_distortion(mesh, uv_name)
    attr = _fresh_attribute(mesh, DISTORTION_ATTRIBUTE, 'FLOAT', 'FACE')
    attr.data.foreach_set("value", distortion.astype(np.float32))
    colors = bd_uv.distortion_colors(distortion, bound, flipped=flipped)
    color_attr = _fresh_attribute(mesh, COLOR_ATTRIBUTE, 'FLOAT_COLOR', 'CORNER')
    color_attr.data.foreach_set("color", colors[_loop_polygon(mesh)].astype(np.float32).ravel())
    mesh.color_attributes.active_color_name = COLOR_ATTRIBUTE
    mesh.update()
    return distortion, flipped


def show_colors_in_viewports(screen):
    """Solid-mode 3D views of ``screen`` display the active colour attribute."""
    if screen is None:
        return
    for area in screen.areas:
        if area.type == 'VIEW_3D':
            for space in area.spaces:
                if space.type == 'VIEW_3D':
                    space.shading.color_type = 'VERTEX'  # shown as "Attribute"


def _target_objects(context):
    objects = edit_mesh_objects(context)
    if objects:
        return objects
    return [ob for ob in context.selected_objects if ob.type == 'MESH'] or (
        [context.active_object] if context.active_object is not None
        and context.active_object.type == 'MESH' else [])


def _last_bound(context):
    result = getattr(context.window_manager, "bd_uv_last_result", None)
    if result is not None and result.valid and result.bound_certified > 1.0:
        return result.bound_certified
    return 5.0


class UV_OT_bd_show_distortion(bpy.types.Operator):
    """Colour faces by the conformal distortion of the active UV map (grey = none, red = at the
    bound; flipped faces purple, degenerate yellow, above 25 green, above 50 blue)"""

    bl_idname = "uv.bd_show_distortion"
    bl_label = "Show Distortion"
    bl_options = {'REGISTER', 'UNDO'}

    bound: FloatProperty(name="Bound C", default=5.0, min=1.0001, soft_max=50.0,
                         description="Distortion shown in full red")

    @classmethod
    def poll(cls, context):
        return bool(_target_objects(context))

    def invoke(self, context, event):
        if not self.properties.is_property_set("bound"):
            self.bound = _last_bound(context)
        return self.execute(context)

    def execute(self, context):
        lines = []
        with object_mode(context) as edit_objects:
            objects = edit_objects or _target_objects(context)
            for ob in objects:
                if not ob.data.uv_layers:
                    lines.append(f"{ob.name}: no UV map")
                    continue
                distortion, flipped = write_distortion_attributes(ob.data, self.bound)
                finite = distortion[np.isfinite(distortion)]
                top = f"{finite.max():.2f}" if finite.size else "-"
                lines.append(f"{ob.name}: max distortion {top}, {int(flipped.sum())} flipped")
        show_colors_in_viewports(context.screen)
        if not lines:
            self.report({'WARNING'}, "No mesh to measure")
            return {'CANCELLED'}
        self.report({'INFO'}, "; ".join(lines))
        return {'FINISHED'}


class UV_OT_bd_select_distorted(bpy.types.Operator):
    """Select faces whose UVs are flipped or more distorted than a threshold"""

    bl_idname = "uv.bd_select_distorted"
    bl_label = "Select Distorted"
    bl_options = {'REGISTER', 'UNDO'}

    threshold: FloatProperty(name="Distortion Above", default=5.0, min=1.0, soft_max=50.0,
                             description="Select faces with a larger conformal distortion")
    flipped: BoolProperty(name="Flipped", default=True, description="Select flipped faces")
    extend: BoolProperty(name="Extend", default=False,
                         description="Add to the selection instead of replacing it")

    @classmethod
    def poll(cls, context):
        return bool(edit_mesh_objects(context))

    def execute(self, context):
        total = 0
        select_mode = tuple(context.scene.tool_settings.mesh_select_mode)
        with object_mode(context) as objects:
            for ob in objects:
                mesh = ob.data
                if not mesh.uv_layers:
                    continue
                distortion, flipped = polygon_distortion(mesh)
                pick = (distortion > self.threshold) & np.isfinite(distortion)
                if self.flipped:
                    pick |= flipped
                if self.extend:
                    current = np.empty(len(mesh.polygons), bool)
                    mesh.polygons.foreach_get("select", current)
                    pick |= current
                hidden = np.empty(len(mesh.polygons), bool)
                mesh.polygons.foreach_get("hide", hidden)
                pick &= ~hidden
                # Counted as Edit Mode shows it (in vertex select mode more faces light up).
                total += int(mesh_data.select_polygons(mesh, pick, select_mode).sum())
        self.report({'INFO'}, f"{total} faces selected")
        return {'FINISHED'}


classes = (UV_OT_bd_show_distortion, UV_OT_bd_select_distorted)
