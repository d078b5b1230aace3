"""uv.bd_pack on islands Blender made (Smart UV Project on Suzanne): the written UVs are checked
independently (float32 as stored): islands kept whole and turned only, inside the square, no two
islands overlapping (exact triangle test), least gap >= padding, one texel density."""
import pathlib
import sys

import numpy as np
import pytest
from conftest import bpy, loop_uv_array, set_mode

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "core"))
from overlap_shapes import overlapping_triangle_pairs  # noqa: E402
from packing_sets import chart_maps, least_gap, texel_densities  # noqa: E402


def smart_suzanne():
    bpy.ops.mesh.primitive_monkey_add(size=2.0)
    ob = bpy.context.object
    set_mode(ob, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    bpy.ops.uv.smart_project(island_margin=0.0)
    set_mode(ob, 'OBJECT')
    return ob


def triangles(ob):
    me = ob.data
    me.calc_loop_triangles()
    n = len(me.loop_triangles)
    loops = np.empty(n * 3, np.int32)
    me.loop_triangles.foreach_get("loops", loops)
    verts = np.empty(n * 3, np.int32)
    me.loop_triangles.foreach_get("vertices", verts)
    V = np.empty(len(me.vertices) * 3, np.float32)
    me.vertices.foreach_get("co", V)
    return V.reshape(-1, 3).astype(np.float64), verts.reshape(-1, 3), loops.reshape(-1, 3)


def test_bd_pack_packs_blender_islands_as_certified(addon):
    from bd_uv_addon.bd_uv.packing import uv_islands
    ob = smart_suzanne()
    V, F, loops = triangles(ob)
    before = loop_uv_array(ob.data)[loops].astype(np.float64)
    lab = uv_islands(F, before)
    set_mode(ob, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    assert bpy.ops.uv.bd_pack(resolution=512, padding=6.0) == {'FINISHED'}
    set_mode(ob, 'OBJECT')
    after = loop_uv_array(ob.data)[loops].astype(np.float64)      # float32 as stored
    assert np.array_equal(uv_islands(F, after), lab)               # islands whole
    assert after.min() >= 3 / 512 * (1 - 1e-4) and after.max() <= 1 - 3 / 512 * (1 - 1e-4)
    pairs = overlapping_triangle_pairs(after)
    assert not np.any(lab[pairs[:, 0]] != lab[pairs[:, 1]])
    assert least_gap(after, lab, reach=12 / 512) * 512 >= 6 * (1 - 1e-4)
    d = texel_densities(V, F, after, lab)
    assert np.allclose(d, np.median(d), rtol=1e-3)
    J = chart_maps(before, after)                                  # a turn and a scale per face
    good = np.abs(np.linalg.det(J)) > 1e-12 * np.abs(J).max() ** 2
    assert np.all(np.linalg.det(J[good]) > 0)
    assert np.allclose(J[good, 0, 0], J[good, 1, 1], atol=1e-3 * np.abs(J).max())


def pin_first_loop(mesh, layer):
    """Pin loop 0 of ``layer``, through foreach_set: in Blender 5.1.2 an item of
    ``MeshUVLoopLayer.pin`` reads as the UV (``Float2AttributeValue``, no ``value``), while the
    collection's foreach_get/foreach_set still address the pins (the operators read them so)."""
    layer.pin_ensure()
    pins = np.zeros(len(mesh.loops), bool)
    pins[0] = True
    layer.pin.foreach_set("value", pins)


def test_bd_pack_keeps_pinned_islands_and_packs_the_rest_beside_them(addon):
    from bd_uv_addon.bd_uv.packing import uv_islands
    ob = smart_suzanne()
    layer = ob.data.uv_layers.active
    pin_first_loop(ob.data, layer)
    V, F, loops = triangles(ob)
    before = loop_uv_array(ob.data)[loops].astype(np.float64)
    lab = uv_islands(F, before)
    kept = lab == lab[np.flatnonzero((loops == 0).any(axis=1))[0]]   # the island of loop 0
    set_mode(ob, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    assert bpy.ops.uv.bd_pack(padding=4.0) == {'FINISHED'}
    set_mode(ob, 'OBJECT')
    after = loop_uv_array(ob.data)[loops].astype(np.float64)
    assert np.array_equal(after[kept], before[kept])                 # the pinned island stays
    assert not np.array_equal(after[~kept], before[~kept])
    pairs = overlapping_triangle_pairs(after)
    assert not np.any(lab[pairs[:, 0]] != lab[pairs[:, 1]])
    assert least_gap(after, lab, reach=8 / 1024) * 1024 >= 4 * (1 - 1e-4)


def test_bd_pack_refuses_a_pinned_island_outside_the_square_and_writes_nothing(addon):
    ob = smart_suzanne()
    layer = ob.data.uv_layers.active
    uv = loop_uv_array(ob.data) + 3.0                                # every island moved out
    layer.uv.foreach_set("vector", uv.ravel())
    pin_first_loop(ob.data, layer)
    before = loop_uv_array(ob.data).copy()
    set_mode(ob, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    with pytest.raises(RuntimeError, match="outside the unit square"):  # ERROR, CANCELLED
        bpy.ops.uv.bd_pack()
    set_mode(ob, 'OBJECT')
    assert np.array_equal(loop_uv_array(ob.data), before)


def test_bd_pack_is_one_undo_step_in_the_uv_menu(addon):
    from bd_uv_addon.operators.pack import UV_OT_bd_pack
    assert {'REGISTER', 'UNDO'} <= UV_OT_bd_pack.bl_options
    from bd_uv_addon.ui import menus
    assert any(draw is menus.draw_pack_entry and menu is bpy.types.IMAGE_MT_uvs
               for menu, draw in menus._menus())


def unwrapped_uvs(ob):
    """bd_unwrap (bound 3) on every face of ``ob``: (V, F, loops, corner UVs as stored)."""
    set_mode(ob, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=3.0) == {'FINISHED'}
    set_mode(ob, 'OBJECT')
    V, F, loops = triangles(ob)
    return V, F, loops, loop_uv_array(ob.data)[loops].astype(np.float64)


def assert_atlas_layout(V, F, uv, lab, density=None):
    """Certified at 3, inside the square with half the 4 px padding to its edge, no two islands
    overlapping, least gap >= 4 px, one texel density on the islands ``density`` (default all)."""
    from conftest import triangle_distortion
    D, det = triangle_distortion(V, F, uv)
    assert (det > 0).all() and D.max() <= 3.0 * (1 + 1e-5)
    assert uv.min() >= 2 / 1024 * (1 - 1e-4) and uv.max() <= 1 - 2 / 1024 * (1 - 1e-4)
    pairs = overlapping_triangle_pairs(uv)
    assert not np.any(lab[pairs[:, 0]] != lab[pairs[:, 1]])
    assert least_gap(uv, lab, reach=8 / 1024) * 1024 >= 4 * (1 - 1e-4)
    d = texel_densities(V, F, uv, lab)
    d = d if density is None else d[density]
    assert np.allclose(d, np.median(d), rtol=1e-3)


def test_unwrap_packs_with_the_atlas_packer_by_default(addon):
    from conftest import add_suzanne_with_seams
    from bd_uv_addon.bd_uv.packing import uv_islands
    V, F, _, uv = unwrapped_uvs(add_suzanne_with_seams())
    lab = uv_islands(F, uv)
    assert lab.max() >= 2
    assert_atlas_layout(V, F, uv, lab)


def test_unwrap_with_a_pinned_island_packs_the_rest_around_it_with_the_atlas_packer(addon):
    """A second unwrap with one island's UVs all pinned: that island stays bit for bit where the
    first unwrap packed it and the others are packed around it by the atlas packer (padding in
    texels, one density among them), not by Blender's bounding boxes."""
    from conftest import add_suzanne_with_seams
    from bd_uv_addon.bd_uv.packing import uv_islands
    ob = add_suzanne_with_seams()
    V, F, loops, first = unwrapped_uvs(ob)
    lab = uv_islands(F, first)
    big = np.argmax(np.bincount(lab))                  # pin every UV of the largest island
    pins = np.zeros(len(ob.data.loops), bool)
    pins[loops[lab == big].ravel()] = True
    layer = ob.data.uv_layers.active
    layer.pin_ensure()
    layer.pin.foreach_set("value", pins)
    _, _, _, uv = unwrapped_uvs(ob)
    kept = lab == big
    assert np.array_equal(uv[kept], first[kept])                     # the pinned island stays
    assert np.array_equal(uv_islands(F, uv), lab)
    assert_atlas_layout(V, F, uv, lab, density=np.unique(lab) != big)
