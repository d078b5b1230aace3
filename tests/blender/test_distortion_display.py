"""uv.bd_show_distortion / uv.bd_select_distorted on UV maps with known distortion."""
import numpy as np
import pytest

from conftest import (add_suzanne_with_seams, bpy, load_addon, loop_uv_array, select_polygons,
                      set_mode, triangle_distortion)


def _three_quads():
    """Three unit quads side by side, each its own UV island, with distortion set by hand:
    quad 0 stretched 3:1 (D = 3), quad 1 mirrored (flipped), quad 2 stretched 30:1 (D = 30)."""
    verts = [(x, y, 0.0) for x in range(4) for y in range(2)]  # vertex 2x + y
    faces = [(0, 2, 3, 1), (2, 4, 5, 3), (4, 6, 7, 5)]
    mesh = bpy.data.meshes.new("Quads")
    mesh.from_pydata(verts, [], faces)
    mesh.uv_layers.new(name="UVMap")
    obj = bpy.data.objects.new("Quads", mesh)
    bpy.context.collection.objects.link(obj)
    # Per-loop UV from the loop's vertex position within its quad.
    loop_vert = np.array([l.vertex_index for l in mesh.loops])
    total = np.array([p.loop_total for p in mesh.polygons])
    loop_poly = np.repeat(np.arange(3), total)
    x = np.array([verts[v][0] for v in loop_vert], float) - loop_poly  # 0..1 in the quad
    y = np.array([verts[v][1] for v in loop_vert], float)
    sx = np.array([3.0, -1.0, 30.0])[loop_poly]  # u = sx * x, v = y
    uv = np.stack([sx * x + 2 * loop_poly, y], 1)
    mesh.uv_layers.active.uv.foreach_set("vector", uv.astype(np.float32).ravel())
    set_mode(obj, 'OBJECT')
    return obj


def test_colours_for_known_distortion(addon):
    colors = load_addon().bd_uv.colors
    obj = _three_quads()
    set_mode(obj, 'EDIT')
    assert bpy.ops.uv.bd_show_distortion('EXEC_DEFAULT', bound=5.0) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    mesh = obj.data
    D = np.empty(3, np.float32)
    mesh.attributes["BD Distortion"].data.foreach_get("value", D)
    assert mesh.attributes["BD Distortion"].domain == 'FACE'
    assert D[0] == pytest.approx(3.0, rel=1e-5) and D[2] == pytest.approx(30.0, rel=1e-5)
    assert np.isinf(D[1])
    attr = mesh.attributes["BD Distortion Color"]
    assert (attr.domain, attr.data_type) == ('CORNER', 'FLOAT_COLOR')
    assert mesh.color_attributes.active_color_name == "BD Distortion Color"
    got = np.empty(len(mesh.loops) * 4, np.float32)
    attr.data.foreach_get("color", got)
    got = got.reshape(3, 4, 4)  # polygon, loop, rgba
    # D = 3 with C = 5 is halfway along the grey-to-red ramp: t = (3 - 1) / (5 - 1).
    expected = [0.5 * colors.GREY + 0.5 * colors.RED, colors.FLIPPED, colors.ABOVE_25]
    for face, rgba in enumerate(expected):
        assert np.allclose(got[face], np.asarray(rgba, np.float32)[None], atol=1e-6), face
    assert len({tuple(c) for c in np.asarray(expected).round(6).tolist()}) == 3
    views = [s for a in bpy.context.screen.areas for s in a.spaces if s.type == 'VIEW_3D']
    assert views and all(v.shading.color_type == 'VERTEX' for v in views)  # "Attribute"


def test_distortion_of_blenders_own_unwrap(addon):
    """Any UV map: Blender's Angle Based unwrap, measured against the independent formula."""
    obj = add_suzanne_with_seams()
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    bpy.ops.uv.unwrap(method='ANGLE_BASED', margin=0.01)
    assert bpy.ops.uv.bd_show_distortion('EXEC_DEFAULT', bound=2.0) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    mesh = obj.data
    mesh.calc_loop_triangles()
    tris = np.array([t.vertices[:] for t in mesh.loop_triangles])
    loops = np.array([t.loops[:] for t in mesh.loop_triangles])
    poly = np.array([t.polygon_index for t in mesh.loop_triangles])
    V = np.array([v.co[:] for v in mesh.vertices])
    Dt, _ = triangle_distortion(V, tris, loop_uv_array(mesh)[loops])
    expected = np.full(len(mesh.polygons), -np.inf)
    np.maximum.at(expected, poly, Dt)
    got = np.empty(len(mesh.polygons), np.float32)
    mesh.attributes["BD Distortion"].data.foreach_get("value", got)
    finite = np.isfinite(expected)
    assert np.array_equal(np.isfinite(got), finite)
    assert np.allclose(got[finite], expected[finite], rtol=1e-4)
    assert expected[finite].max() > 1.2  # ABF is not conformal everywhere: a real measurement


def test_select_distorted(addon):
    obj = _three_quads()
    bpy.context.scene.tool_settings.mesh_select_mode = (False, False, True)
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='DESELECT')
    assert bpy.ops.uv.bd_select_distorted('EXEC_DEFAULT', threshold=5.0) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    assert [p.select for p in obj.data.polygons] == [False, True, True]
    set_mode(obj, 'EDIT')
    bpy.ops.uv.bd_select_distorted('EXEC_DEFAULT', threshold=2.0, flipped=False)
    set_mode(obj, 'OBJECT')
    assert [p.select for p in obj.data.polygons] == [True, False, True]
    set_mode(obj, 'EDIT')
    bpy.ops.uv.bd_select_distorted('EXEC_DEFAULT', threshold=50.0, flipped=True)
    set_mode(obj, 'OBJECT')
    assert [p.select for p in obj.data.polygons] == [False, True, False]
    select_polygons(obj, [True, False, False])
    set_mode(obj, 'EDIT')
    bpy.ops.uv.bd_select_distorted('EXEC_DEFAULT', threshold=10.0, flipped=False, extend=True)
    set_mode(obj, 'OBJECT')
    assert [p.select for p in obj.data.polygons] == [True, False, True]


def test_colour_after_unwrap(addon):
    obj = add_suzanne_with_seams()
    before = loop_uv_array(obj.data).copy()
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=1.5, show_distortion=True) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    mesh = obj.data
    D = np.empty(len(mesh.polygons), np.float32)
    mesh.attributes["BD Distortion"].data.foreach_get("value", D)
    # Only the polygons written (an island put back by the post-write check keeps its old UVs).
    from test_post_write_check import _kept_triangles
    kept = _kept_triangles(obj, before)
    written = np.zeros(len(mesh.polygons), bool)
    written[np.array([t.polygon_index for t in mesh.loop_triangles])[kept]] = True
    D = D[written]
    assert np.isfinite(D).all() and D.max() <= 1.5 * (1 + 1e-4) and D.min() >= 1.0
    assert mesh.color_attributes.active_color_name == "BD Distortion Color"
