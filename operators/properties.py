"""The add-on's one PropertyGroup: the last unwrap's result, shown by the UV editor panel."""
import bpy
from bpy.props import BoolProperty, FloatProperty, IntProperty, StringProperty


class BDUV_PG_last_result(bpy.types.PropertyGroup):
    """What the last ``uv.bd_unwrap`` did (kept on the window manager: not saved in files).

    Every figure is from the post-write check of the UVs as stored (float32, after packing)."""

    valid: BoolProperty(name="Has Result", default=False)
    method: StringProperty(name="Method")
    islands: IntProperty(name="Islands", min=0)
    failed: IntProperty(name="Failed Islands", min=0)
    faces: IntProperty(name="Faces", min=0, description="Faces (polygons) unwrapped")
    max_distortion: FloatProperty(name="Max Distortion", precision=3)
    mean_distortion: FloatProperty(name="Mean Distortion", precision=3,
                                   description="Area-weighted mean conformal distortion")
    flipped: IntProperty(name="Flipped", min=0)
    bound_certified: FloatProperty(name="Certified C", precision=3,
                                   description="Largest certified bound over the islands")
    raised: IntProperty(name="C Raised", min=0,
                        description="Islands certified at a bound above the one asked for")
    put_back: IntProperty(name="Put Back", min=0,
                          description="Islands whose stored UVs failed the post-write check and "
                          "were given their previous UVs back")
    overlaps: IntProperty(name="Overlaps", min=0,
                          description="Pairs of islands overlapping in the stored UV layout")
    seconds: FloatProperty(name="Time", precision=2, unit='TIME_ABSOLUTE')
    report: StringProperty(name="Report")


classes = (BDUV_PG_last_result,)


def register():
    bpy.types.WindowManager.bd_uv_last_result = bpy.props.PointerProperty(
        type=BDUV_PG_last_result)


def unregister():
    del bpy.types.WindowManager.bd_uv_last_result
