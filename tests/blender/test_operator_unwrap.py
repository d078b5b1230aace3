"""uv.bd_unwrap through bpy: the UVs written are checked from the loops, with an independent
distortion formula (conftest.triangle_distortion, numpy SVD of each triangle's 2x2 Jacobian).

Tolerance: the core certifies in float64; Blender stores UVs as float32, whose rounding moves the
distortion of a small UV triangle by ~1e-6 relative, so ``max <= C * (1 + 1e-4)`` is asserted.
"""
import numpy as np
import pytest

from conftest import (add_grid, add_suzanne_with_seams, bpy, loop_uv_array, select_polygons,
                      set_mode, triangle_distortion)

SLACK = 1 + 1e-4


def _loop_triangles(obj):
    """(V with object scale, tris, tri_loops, tri_poly) read straight from Blender."""
    mesh = obj.data
    mesh.calc_loop_triangles()
    n = len(mesh.loop_triangles)
    tris = np.empty(3 * n, np.int32)
    mesh.loop_triangles.foreach_get("vertices", tris)
    loops = np.empty(3 * n, np.int32)
    mesh.loop_triangles.foreach_get("loops", loops)
    poly = np.empty(n, np.int32)
    mesh.loop_triangles.foreach_get("polygon_index", poly)
    co = np.empty(3 * len(mesh.vertices), np.float32)
    mesh.vertices.foreach_get("co", co)
    V = co.reshape(-1, 3).astype(np.float64) * np.array(obj.scale)
    return V, tris.reshape(-1, 3), loops.reshape(-1, 3), poly


def _edit_all(obj):
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')


def test_suzanne_is_certified_from_the_written_loops(addon):
    obj = add_suzanne_with_seams()
    obj.scale = (1.0, 1.3, 1.0)  # non-uniform: the certificate is on the scaled shape
    before = loop_uv_array(obj.data).copy()
    _edit_all(obj)
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=1.5) == {'FINISHED'}
    assert obj.mode == 'EDIT'
    set_mode(obj, 'OBJECT')
    # Islands the post-write check put back (the solve's own output overlapping itself) hold
    # their old UVs bit for bit; every other face was written and is measured.
    from test_post_write_check import _kept_triangles
    kept = _kept_triangles(obj, before)
    V, tris, loops, _ = _loop_triangles(obj)
    tris, loops = tris[kept], loops[kept]
    uv = loop_uv_array(obj.data)[loops]
    D, det = triangle_distortion(V, tris, uv)
    assert (det > 0).all(), f"{(det <= 0).sum()} flipped"
    assert D.max() <= 1.5 * SLACK
    assert D.max() > 1.3  # the bound is active somewhere: the test is not vacuous
    # Packed by Blender into the unit square.
    assert uv.min() >= 0.0 and uv.max() <= 1.0
    last = bpy.context.window_manager.bd_uv_last_result
    assert last.valid and last.flipped == 0 and last.failed == 0 and last.islands > 10
    assert last.put_back == last.report.count(") as solved already")
    assert last.bound_certified == pytest.approx(1.5)
    assert last.max_distortion == pytest.approx(D.max(), rel=1e-3)
    assert last.report.startswith(f"BD-LSCM: {last.islands} islands, max distortion ")
    assert "\u2264 1.5, 0 flipped" in last.report


def test_arap_minimise_on_a_bent_grid(addon):
    obj = add_grid(8, 6)
    _edit_all(obj)
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', method='arap', minimise=True) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    V, tris, loops, _ = _loop_triangles(obj)
    D, det = triangle_distortion(V, tris, loop_uv_array(obj.data)[loops])
    last = bpy.context.window_manager.bd_uv_last_result
    assert (det > 0).all()
    assert D.max() <= last.bound_certified * SLACK
    assert last.method == "BD-ARAP" and 1.0 <= last.bound_certified < 5.0


def test_pinned_uvs_keep_their_values_to_the_bit(addon):
    obj = add_grid(6, 5)
    mesh = obj.data
    layer = mesh.uv_layers.active
    layer.pin_ensure()
    uv0 = loop_uv_array(mesh).copy()
    # Pin every loop of three boundary vertices, at values of our own choosing.
    loop_vert = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", loop_vert)
    pins = np.isin(loop_vert, [0, 5, 29])
    targets = {0: (0.1, 0.2), 5: (0.9, 0.2), 29: (0.85, 0.95)}
    for v, t in targets.items():
        uv0[loop_vert == v] = np.float32(t)
    layer.uv.foreach_set("vector", uv0.ravel())
    layer.pin.foreach_set("value", pins)
    _edit_all(obj)
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=5.0) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    after = loop_uv_array(mesh)
    assert np.array_equal(after[pins], uv0[pins])  # bit for bit, through solve and packing
    assert not np.array_equal(after[~pins], uv0[~pins])
    V, tris, loops, _ = _loop_triangles(obj)
    D, det = triangle_distortion(V, tris, after[loops])
    last = bpy.context.window_manager.bd_uv_last_result
    assert (det > 0).all() and D.max() <= last.bound_certified * SLACK


def test_unselected_faces_keep_their_uvs(addon):
    obj = add_suzanne_with_seams()
    mesh = obj.data
    bpy.context.scene.tool_settings.mesh_select_mode = (False, False, True)
    poly_sel = np.zeros(len(mesh.polygons), bool)
    poly_sel[100:300] = True
    select_polygons(obj, poly_sel)
    before = loop_uv_array(mesh).copy()
    set_mode(obj, 'EDIT')
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=2.0) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    after = loop_uv_array(mesh)
    total = np.array([p.loop_total for p in mesh.polygons])
    loop_sel = np.repeat(poly_sel, total)
    assert np.array_equal(after[~loop_sel], before[~loop_sel])
    assert (after[loop_sel] != before[loop_sel]).any(axis=1).mean() > 0.9
    V, tris, loops, poly = _loop_triangles(obj)
    keep = poly_sel[poly]
    D, det = triangle_distortion(V, tris[keep], after[loops[keep]])
    assert (det > 0).all() and D.max() <= 2.0 * SLACK
    # The selection is as it was (packing selects temporarily).
    assert np.array_equal(np.array([p.select for p in mesh.polygons]), poly_sel)


def test_closed_island_reports_and_changes_nothing(addon):
    """Nothing can be done: CANCELLED with a WARNING (no RuntimeError: a script looping over
    objects goes on), the sphere counted in polygons (128, not its 224 triangles)."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=16, ring_count=8)
    obj = bpy.context.active_object
    before = loop_uv_array(obj.data).tobytes()
    assert len(obj.data.polygons) == 128
    _edit_all(obj)
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', seams='MARKED') == {'CANCELLED'}
    message = bpy.context.window_manager.bd_uv_last_result.report
    assert message == ("BD-LSCM: nothing unwrapped; island 0 of Sphere (128 faces) is closed: it "
                       "has no boundary and cannot be flattened; mark seams that cut it open; "
                       "left as it was")
    set_mode(obj, 'OBJECT')
    assert loop_uv_array(obj.data).tobytes() == before


def test_a_failed_island_is_named_and_the_others_are_written(addon):
    grid = add_grid(5, 4)
    bpy.ops.mesh.primitive_cube_add(location=(5, 0, 0))  # closed, no seams
    cube = bpy.context.active_object
    grid.select_set(True)
    bpy.context.view_layer.objects.active = grid
    bpy.ops.object.join()
    obj = bpy.context.active_object
    mesh = obj.data
    before = loop_uv_array(mesh).copy()
    _edit_all(obj)
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=3.0, seams='MARKED') == {'FINISHED'}
    report = bpy.context.window_manager.bd_uv_last_result.report
    assert report.startswith("BD-LSCM: 1 island, max distortion")
    assert "island 1 of Grid (6 faces) is closed" in report and "seam" in report.lower()
    set_mode(obj, 'OBJECT')
    after = loop_uv_array(mesh)
    V, tris, loops, poly = _loop_triangles(obj)
    on_cube = V[:, 0][tris].min(axis=1) > 3.0
    cube_loops = np.unique(loops[on_cube])
    grid_loops = np.unique(loops[~on_cube])
    assert len(cube_loops) == 24
    assert after[cube_loops].tobytes() == before[cube_loops].tobytes()
    D, det = triangle_distortion(V, tris[~on_cube], after[loops[~on_cube]])
    assert (det > 0).all() and D.max() <= 3.0 * SLACK
    assert not np.array_equal(after[grid_loops], before[grid_loops])


def test_mesh_without_uv_map_gets_one(addon):
    obj = add_grid(4, 4)
    obj.data.uv_layers.remove(obj.data.uv_layers[0])
    _edit_all(obj)
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT') == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    assert [l.name for l in obj.data.uv_layers] == ["UVMap"]
    V, tris, loops, _ = _loop_triangles(obj)
    D, det = triangle_distortion(V, tris, loop_uv_array(obj.data)[loops])
    assert (det > 0).all() and D.max() <= 5.0 * SLACK


def _edit_mode_uvs(obj):
    """(L,2) UVs read from the edit-mesh with bmesh (so reading toggles no mode: a mode toggle
    is an undo step of its own)."""
    import bmesh

    bm = bmesh.from_edit_mesh(obj.data)
    layer = bm.loops.layers.uv.active
    return np.array([loop[layer].uv[:] for face in bm.faces for loop in face.loops], np.float32)


def test_undo_restores_the_previous_uvs(addon):
    """Headless undo works: ed.undo steps back over the operator's own undo step (UNDO flag),
    ed.redo brings its UVs back.

    A bpy.ops call from Python pushes the operator's undo step only when asked with the third
    positional argument ``undo=True`` (the UI always does); without it neither this operator nor
    Blender's own uv.unwrap leaves a step, measured with bpy 5.0.1 in background mode."""
    obj = add_grid(5, 5)
    _edit_all(obj)
    bpy.ops.ed.undo_push(message="before bd_unwrap")
    before = _edit_mode_uvs(obj)
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', True) == {'FINISHED'}
    unwrapped = _edit_mode_uvs(obj)
    assert not np.array_equal(unwrapped, before)
    bpy.ops.ed.undo()
    assert np.array_equal(_edit_mode_uvs(bpy.context.edit_object), before)
    bpy.ops.ed.redo()
    assert np.array_equal(_edit_mode_uvs(bpy.context.edit_object), unwrapped)


def test_stored_uvs_are_recertified_after_packing(addon, monkeypatch):
    """A pack step that ruins the written island (here: collapses it to one point) must not
    leave uncertified UVs behind: the island is measured again as stored and put back."""
    from conftest import load_submodule
    session = load_submodule("operators.session")
    editmode = load_submodule("operators.editmode")
    obj = add_grid()
    before = loop_uv_array(obj.data).tobytes()
    calls = []

    def ruinous_pack(context, written, margin, shape='AABB'):
        calls.append(len(written))
        with editmode.object_mode(context):
            layer = obj.data.uv_layers.active.uv
            layer.foreach_set("vector", np.full(2 * len(layer), 0.5, np.float32))
    monkeypatch.setattr(session, "pack", ruinous_pack)
    _edit_all(obj)
    bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', pack=True, pack_shape='AABB')
    set_mode(obj, 'OBJECT')
    assert calls == [1]
    assert loop_uv_array(obj.data).tobytes() == before


def test_stored_uvs_pass_recertification_after_a_real_pack(addon):
    obj = add_grid()
    _edit_all(obj)
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=2.0, pack=True) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    V, tris, loops, _ = _loop_triangles(obj)
    D, det = triangle_distortion(V, tris, loop_uv_array(obj.data)[loops])
    assert (det > 0).all() and D.max() <= 2.0 * SLACK
