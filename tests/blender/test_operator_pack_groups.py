"""uv.bd_pack and uv.bd_unwrap with Group Material / Object: the written UVs (float32 as stored)
keep each group's islands in one region: the convex hull of a group's islands meets no island of
another group, hulls are at least the padding apart (shapely on the stored UVs), and the layout
is otherwise certified (exact triangle test, least gap). Each island's group is recomputed here
from the faces' material slots (most 3D area) or its object."""
import pathlib
import sys

import numpy as np
import shapely
from conftest import add_suzanne_with_seams, bpy, loop_uv_array, set_mode

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "core"))
from overlap_shapes import overlapping_triangle_pairs  # noqa: E402
from packing_sets import least_gap  # noqa: E402
from test_operator_pack import smart_suzanne, triangles  # noqa: E402


def two_materials(ob):
    """Two material slots; the polygons left of x = 0.1 take the second."""
    for name in ("left", "right"):
        mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
        ob.data.materials.append(mat)
    centre = np.empty(len(ob.data.polygons) * 3, np.float32)
    ob.data.polygons.foreach_get("center", centre)
    index = (centre.reshape(-1, 3)[:, 0] < 0.1).astype(np.int32)
    ob.data.polygons.foreach_set("material_index", index)
    ob.data.update()


def island_groups(V, F, face_group, lab):
    """Each island's group: the group of most of its faces' 3D area (recomputed here)."""
    P = V[F]
    a = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    w = np.zeros((lab.max() + 1, face_group.max() + 1))
    np.add.at(w, (lab, face_group), a)
    return np.argmax(w, axis=1)


def assert_regions(uv, lab, group_of_island, pad_uv):
    g = group_of_island[lab]
    present = np.unique(g)
    assert len(present) >= 2
    hulls = {b: shapely.convex_hull(shapely.multipoints(uv[g == b].reshape(-1, 2)))
             for b in present}
    for b in present:
        assert not shapely.intersects(hulls[b], shapely.polygons(uv[g != b])).any()
        for c in present[present > b]:
            assert hulls[b].distance(hulls[c]) >= pad_uv * (1 - 1e-4)
    pairs = overlapping_triangle_pairs(uv)
    assert not np.any(lab[pairs[:, 0]] != lab[pairs[:, 1]])
    assert least_gap(uv, lab, reach=2 * pad_uv) >= pad_uv * (1 - 1e-4)
    assert uv.min() >= 0.5 * pad_uv * (1 - 1e-4) and uv.max() <= 1 - 0.5 * pad_uv * (1 - 1e-4)


def polygon_material(ob, loops_tris):
    me = ob.data
    index = np.empty(len(me.polygons), np.int32)
    me.polygons.foreach_get("material_index", index)
    poly = np.empty(len(me.loop_triangles), np.int32)
    me.loop_triangles.foreach_get("polygon_index", poly)
    return index[poly].astype(np.int64)


def test_bd_pack_groups_islands_by_material(addon):
    from bd_uv_addon.bd_uv.packing import uv_islands
    ob = smart_suzanne()
    two_materials(ob)
    V, F, loops = triangles(ob)
    lab = uv_islands(F, loop_uv_array(ob.data)[loops].astype(np.float64))
    groups = island_groups(V, F, polygon_material(ob, loops), lab)
    set_mode(ob, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    assert bpy.ops.uv.bd_pack(resolution=512, padding=6.0, group='material') == {'FINISHED'}
    set_mode(ob, 'OBJECT')
    after = loop_uv_array(ob.data)[loops].astype(np.float64)
    assert np.array_equal(uv_islands(F, after), lab)
    assert_regions(after, lab, groups, 6 / 512)


def test_bd_pack_groups_islands_by_object(addon):
    from bd_uv_addon.bd_uv.packing import uv_islands
    a = smart_suzanne()
    b = smart_suzanne()
    b.location.x = 4
    for ob in (a, b):
        ob.select_set(True)
    bpy.context.view_layer.objects.active = a
    bpy.ops.object.mode_set(mode='EDIT')
    assert {o.name for o in bpy.context.objects_in_mode} == {a.name, b.name}
    bpy.ops.mesh.select_all(action='SELECT')
    assert bpy.ops.uv.bd_pack(padding=4.0, group='object') == {'FINISHED'}
    bpy.ops.object.mode_set(mode='OBJECT')
    uvs, labs, groups, n = [], [], [], 0
    for k, ob in enumerate((a, b)):
        V, F, loops = triangles(ob)
        uv = loop_uv_array(ob.data)[loops].astype(np.float64)
        lab = uv_islands(F, uv)
        uvs.append(uv)
        labs.append(lab + n)
        groups.append(np.full(lab.max() + 1, k))
        n += lab.max() + 1
    assert_regions(np.concatenate(uvs), np.concatenate(labs), np.concatenate(groups), 4 / 1024)


def test_unwrap_packs_by_material_when_asked(addon):
    from bd_uv_addon.bd_uv.packing import uv_islands
    ob = add_suzanne_with_seams()
    two_materials(ob)
    set_mode(ob, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=3.0, pack_group='material') == {'FINISHED'}
    set_mode(ob, 'OBJECT')
    V, F, loops = triangles(ob)
    uv = loop_uv_array(ob.data)[loops].astype(np.float64)
    lab = uv_islands(F, uv)
    groups = island_groups(V, F, polygon_material(ob, loops), lab)
    assert_regions(uv, lab, groups, 4 / 1024)
