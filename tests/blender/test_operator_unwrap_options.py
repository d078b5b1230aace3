"""uv.bd_unwrap options and contexts: several objects in Edit Mode, n-gons, object scale, raising
C, frames from the current UVs, and the UV editor's unselected UVs acting as pins."""
import re

import numpy as np
import pytest

from conftest import add_grid, bpy, loop_uv_array, set_mode, triangle_distortion

SLACK = 1 + 1e-4


def _uv_region(obj):
    """The union of ``obj``'s UV triangles as written (shapely, float64 of the stored float32)."""
    import shapely
    mesh = obj.data
    mesh.calc_loop_triangles()
    loops = np.array([t.loops[:] for t in mesh.loop_triangles])
    tris = loop_uv_array(mesh)[loops].astype(np.float64)
    return shapely.union_all(shapely.polygons(tris))


def _certified(obj, bound, scale=None):
    """Max distortion of ``obj``'s written UVs, asserting no flip (independent formula)."""
    mesh = obj.data
    mesh.calc_loop_triangles()
    tris = np.array([t.vertices[:] for t in mesh.loop_triangles])
    loops = np.array([t.loops[:] for t in mesh.loop_triangles])
    V = np.array([v.co[:] for v in mesh.vertices]) * np.asarray(scale or (1, 1, 1))
    D, det = triangle_distortion(V, tris, loop_uv_array(mesh)[loops])
    assert (det > 0).all(), f"{obj.name}: {(det <= 0).sum()} flipped"
    assert D.max() <= bound * SLACK, (obj.name, D.max(), bound)
    return D.max()


def test_every_object_in_edit_mode_is_unwrapped(addon):
    a = add_grid(5, 4)
    b = add_grid(4, 6)
    b.location.x = 5
    b.scale = (2.0, 0.5, 1.0)
    a.select_set(True)
    b.select_set(True)
    bpy.context.view_layer.objects.active = a
    bpy.ops.object.mode_set(mode='EDIT')
    assert {o.name for o in bpy.context.objects_in_mode} == {a.name, b.name}
    bpy.ops.mesh.select_all(action='SELECT')
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=2.0) == {'FINISHED'}
    assert {o.name for o in bpy.context.objects_in_mode} == {a.name, b.name}
    bpy.ops.object.mode_set(mode='OBJECT')
    _certified(a, 2.0)
    _certified(b, 2.0, scale=(2.0, 0.5, 1.0))  # certified on the shape as scaled
    last = bpy.context.window_manager.bd_uv_last_result
    assert last.islands == 2 and last.faces == 20 + 24  # polygons
    # Packed together: the two objects' islands do not overlap in UV space (an exact test on
    # their triangles: a shape packer may nest one island in the other's bay, so their boxes can
    # overlap while the islands do not).
    assert _uv_region(a).intersection(_uv_region(b)).area == 0.0


def test_ngons_and_object_scale_ignored_on_request(addon):
    bpy.ops.mesh.primitive_circle_add(vertices=12, fill_type='NGON')
    obj = bpy.context.active_object
    obj.scale = (3.0, 1.0, 1.0)
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=1.2, use_object_scale=False,
                                pack=False) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    # The flat 12-gon, unscaled, is mapped by a similarity: distortion 1 on all 10 triangles.
    assert _certified(obj, 1.2) == pytest.approx(1.0, abs=1e-4)


def test_bound_not_raised_fails_clearly_and_raised_succeeds(addon):
    obj = add_grid(6, 5)
    set_mode(obj, 'OBJECT')
    before = loop_uv_array(obj.data).tobytes()
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    # Nothing done: CANCELLED with a WARNING (no RuntimeError), the grid counted in polygons.
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=1.001, raise_bound=False,
                                seams='MARKED') == {'CANCELLED'}
    assert re.search(r"island 0 of Grid \(30 faces\) left as it was: no map within distortion "
                     r"1\.001", bpy.context.window_manager.bd_uv_last_result.report)
    set_mode(obj, 'OBJECT')
    assert loop_uv_array(obj.data).tobytes() == before
    set_mode(obj, 'EDIT')
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=1.001, raise_bound=True,
                                bound_limit=50.0, seams='MARKED') == {'FINISHED'}
    last = bpy.context.window_manager.bd_uv_last_result
    assert 1.001 < last.bound_certified <= 50.0
    set_mode(obj, 'OBJECT')
    _certified(obj, last.bound_certified)


def test_frames_from_current_uvs(addon):
    obj = add_grid(6, 5)  # its UVs are the grid's planar projection: flip-free
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', frames='input-uv', bound=3.0) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    _certified(obj, 3.0)


def test_uv_editor_unselected_uvs_act_as_pins(addon):
    obj = add_grid(6, 5)
    mesh = obj.data
    uv0 = loop_uv_array(mesh).copy()
    loop_vert = np.array([l.vertex_index for l in mesh.loops])
    held = np.isin(loop_vert, [0, 6, 35])  # three boundary vertices' loops: UV-unselected
    mesh.attributes[".uv_select_vert"].data.foreach_set("value", ~held)
    area = bpy.context.screen.areas[0]
    area.type = 'IMAGE_EDITOR'
    area.spaces.active.mode = 'UV'
    bpy.context.scene.tool_settings.use_uv_select_sync = False
    bpy.context.scene.tool_settings.mesh_select_mode = (False, False, True)
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')  # faces; UV selection stays as set
    with bpy.context.temp_override(area=area, space_data=area.spaces.active):
        assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=5.0) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    after = loop_uv_array(mesh)
    assert np.array_equal(after[held], uv0[held])  # held where they were, through packing too
    assert not np.array_equal(after[~held], uv0[~held])
    _certified(obj, bpy.context.window_manager.bd_uv_last_result.bound_certified)
