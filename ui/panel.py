"""UV editor sidebar (N panel), "BD-UV" tab: unwrap and deform, the last result and the distortion
tools."""
import bpy

from ..operators.deform import UV_OT_bd_deform
from ..operators.live import UV_OT_bd_live
from ..operators.display import UV_OT_bd_select_distorted, UV_OT_bd_show_distortion
from ..operators.unwrap import UV_OT_bd_unwrap


class IMAGE_PT_bd_uv_result(bpy.types.Panel):
    bl_space_type = 'IMAGE_EDITOR'
    bl_region_type = 'UI'
    bl_category = "BD-UV"
    bl_label = "Bounded Distortion"

    def draw(self, context):
        layout = self.layout
        row = layout.row(align=True)
        row.operator(UV_OT_bd_unwrap.bl_idname, text="Unwrap")
        row.operator(UV_OT_bd_deform.bl_idname, text="Deform")
        op_row = layout.row()
        op_row.operator_context = 'INVOKE_DEFAULT'
        op_row.operator(UV_OT_bd_live.bl_idname, text="Live Drag")
        last = context.window_manager.bd_uv_last_result
        box = layout.box()
        if not last.valid:
            box.label(text="No result yet")
        else:
            col = box.column(align=True)
            col.label(text=f"{last.method}: {last.islands} islands"
                      + (f", {last.failed} failed" if last.failed else ""))
            col.label(text=f"Max distortion {last.max_distortion:.3f}")
            col.label(text=f"Mean distortion {last.mean_distortion:.3f}")
            col.label(text=f"Certified C {last.bound_certified:.4g}"
                      + (f" (raised on {last.raised})" if last.raised else ""))
            col.label(text=f"Flipped {last.flipped}")
            if last.put_back:
                col.label(text=f"Put back {last.put_back}", icon='ERROR')
            if last.overlaps:
                col.label(text=f"Overlapping island pairs {last.overlaps}", icon='ERROR')
            col.label(text=f"Time {last.seconds:.2f} s")
        col = layout.column(align=True)
        col.operator(UV_OT_bd_show_distortion.bl_idname)
        col.operator(UV_OT_bd_select_distorted.bl_idname)


classes = (IMAGE_PT_bd_uv_result,)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
