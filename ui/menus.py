"""Menu entries: UV > Unwrap beside Blender's own methods; UV > Bounded Distortion Deform and
Bounded Distortion Live with the distortion tools; Mesh > Clean Up > Improve Triangles (Bounded
Distortion) in Edit Mode.

``IMAGE_MT_uvs_unwrap`` is the UV editor's UV > Unwrap menu, which the 3D View's U menu embeds
since Blender 4.3; before that the 3D View uses ``VIEW3D_MT_uv_map``.
"""
import bpy

from ..operators.deform import UV_OT_bd_deform
from ..operators.display import UV_OT_bd_select_distorted, UV_OT_bd_show_distortion
from ..operators.improve import MESH_OT_bd_improve
from ..operators.live import UV_OT_bd_live
from ..operators.pack import UV_OT_bd_pack
from ..operators.unwrap import UV_OT_bd_unwrap


def draw_unwrap_entry(self, context):
    layout = self.layout
    layout.separator()
    layout.operator_context = 'INVOKE_DEFAULT'
    layout.operator(UV_OT_bd_unwrap.bl_idname, text="Bounded Distortion")


def draw_distortion_entries(self, context):
    layout = self.layout
    layout.separator()
    layout.operator(UV_OT_bd_show_distortion.bl_idname)
    layout.operator(UV_OT_bd_select_distorted.bl_idname)
    layout.operator_context = 'INVOKE_DEFAULT'  # the background path, Esc cancels
    layout.operator(UV_OT_bd_deform.bl_idname)
    layout.operator(UV_OT_bd_live.bl_idname)


def draw_pack_entry(self, context):
    self.layout.operator(UV_OT_bd_pack.bl_idname)


def draw_improve_entry(self, context):
    layout = self.layout
    layout.separator()
    layout.operator_context = 'INVOKE_DEFAULT'
    layout.operator(MESH_OT_bd_improve.bl_idname)


# From 4.3 the 3D View's U menu (VIEW3D_MT_uv_map) draws IMAGE_MT_uvs_unwrap's contents.
U_MENU_EMBEDS_UNWRAP = (4, 3, 0)


def _menus():
    """(menu class, draw function) pairs for this Blender version."""
    pairs = []
    unwrap_menu = getattr(bpy.types, "IMAGE_MT_uvs_unwrap", None)
    if unwrap_menu is not None:
        pairs.append((unwrap_menu, draw_unwrap_entry))
    if unwrap_menu is None or bpy.app.version < U_MENU_EMBEDS_UNWRAP:
        pairs.append((bpy.types.VIEW3D_MT_uv_map, draw_unwrap_entry))
    uvs_menu = getattr(bpy.types, "IMAGE_MT_uvs", None)
    if uvs_menu is not None:
        pairs.append((uvs_menu, draw_distortion_entries))
        pairs.append((uvs_menu, draw_pack_entry))
    pairs.append((bpy.types.VIEW3D_MT_edit_mesh_clean, draw_improve_entry))
    return pairs


classes = ()


def register():
    for menu, draw in _menus():
        menu.append(draw)


def unregister():
    for menu, draw in _menus():
        menu.remove(draw)
