"""operators/mesh_data/: the bpy <-> numpy transfer, checked against Blender's own collections."""
import numpy as np
import pytest

from conftest import add_suzanne_with_seams, bpy, loop_uv_array, select_polygons, set_mode


def _loop_vertex(mesh):
    out = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", out)
    return out


def test_suzanne_arrays_match_blender(empty_scene, mesh_data):
    obj = add_suzanne_with_seams()
    obj.scale = (2.0, 1.0, 0.5)
    mesh = obj.data
    a = mesh_data.mesh_arrays(obj, scale=obj.scale)

    assert a.V.dtype == np.float64 and a.F.dtype == np.int64 and a.tri_loops.dtype == np.int64
    assert a.F.shape == (968, 3) == a.tri_loops.shape and a.tri_poly.shape == (968,)
    # Every corner's vertex is the vertex of its Blender loop.
    assert np.array_equal(a.vertices[a.F], _loop_vertex(mesh)[a.tri_loops])
    # Positions are the vertex coordinates with the object scale applied.
    co = np.array([v.co[:] for v in mesh.vertices])
    assert np.allclose(a.V, co[a.vertices] * [2.0, 1.0, 0.5], rtol=0, atol=1e-6)
    # Triangles of polygon p are made of p's loops.
    loop_start = np.array([p.loop_start for p in mesh.polygons])
    loop_total = np.array([p.loop_total for p in mesh.polygons])
    rel = a.tri_loops - loop_start[a.tri_poly][:, None]
    assert (rel >= 0).all() and (rel < loop_total[a.tri_poly][:, None]).all()
    # Seams: exactly Blender's seam edges (Suzanne's faces are all triangles or quads).
    seam_pairs = {tuple(sorted(e.vertices)) for e in mesh.edges if e.use_seam}
    got = {tuple(sorted(p)) for p in a.vertices[a.seams].tolist()}
    assert len(seam_pairs) > 50 and got == seam_pairs
    # Corner UVs are the stored float32 values, bit for bit.
    uv = loop_uv_array(mesh)
    assert np.array_equal(a.corner_uv.astype(np.float32), uv[a.tri_loops])
    assert a.pin_corners.size == 0 and a.pin_uv.shape == (0, 2)


def test_ngon_is_triangulated_by_blender(empty_scene, mesh_data):
    bpy.ops.mesh.primitive_circle_add(vertices=9, fill_type='NGON')
    obj = bpy.context.active_object
    a = mesh_data.mesh_arrays(obj)
    assert len(obj.data.polygons) == 1
    assert a.F.shape == (7, 3) and (a.tri_poly == 0).all()
    assert set(a.tri_loops.ravel().tolist()) == set(range(9))
    # The triangles tile the regular 9-gon of radius 1: total area 9/2 sin(2 pi / 9).
    P = a.V[a.F]
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1).sum()
    assert area == pytest.approx(4.5 * np.sin(2 * np.pi / 9), rel=1e-6)


def test_selection_pins_and_seams(empty_scene, mesh_data):
    obj = add_suzanne_with_seams()
    mesh = obj.data
    sel = np.zeros(len(mesh.polygons), bool)
    sel[:40] = True
    select_polygons(obj, sel)
    layer = mesh.uv_layers.active
    layer.pin_ensure()
    pins = np.zeros(len(mesh.loops), bool)
    pins[[0, 1, 2, 500]] = True  # loops 0..2 are in polygon 0 (selected); 500 is not
    layer.pin.foreach_set("value", pins)

    a = mesh_data.mesh_arrays(obj, selected_only=True)
    assert set(a.tri_poly.tolist()) == set(range(40))
    assert a.F.max() == len(a.V) - 1 and np.unique(a.F).size == len(a.V)
    pinned_loops = a.tri_loops.ravel()[a.pin_corners]
    assert set(pinned_loops.tolist()) == {0, 1, 2}
    uv = loop_uv_array(mesh)
    assert np.array_equal(a.pin_uv.astype(np.float32), uv[pinned_loops])
    # Seams kept are edges of the kept triangles only.
    kept_edges = {tuple(sorted(e)) for t in a.F.tolist() for e in ((t[0], t[1]), (t[1], t[2]),
                                                                  (t[2], t[0]))}
    assert {tuple(p) for p in a.seams.tolist()} <= kept_edges
    all_seams = {tuple(sorted(e.vertices)) for e in mesh.edges if e.use_seam}
    expected = {tuple(sorted(p)) for p in all_seams
                if all(v in set(a.vertices.tolist()) for v in p)}
    expected = {p for p in expected
                if tuple(sorted(np.searchsorted(a.vertices, p))) in kept_edges}
    assert {tuple(p) for p in a.vertices[a.seams].tolist()} == expected


def test_unselected_uvs_pin_when_asked(empty_scene, mesh_data):
    obj = add_suzanne_with_seams()
    mesh = obj.data
    attr = mesh.attributes.get(".uv_select_vert")
    layer = mesh.uv_layers.active
    if attr is not None:
        seq = attr.data
    else:
        seq = layer.vertex_selection
    sel = np.ones(len(mesh.loops), bool)
    sel[[4, 5, 6]] = False
    seq.foreach_set("value", sel)
    a = mesh_data.mesh_arrays(obj)
    assert a.pin_corners.size == 0
    b = mesh_data.mesh_arrays(obj, pin_unselected_uvs=True)
    assert set(b.tri_loops.ravel()[b.pin_corners].tolist()) == {4, 5, 6}


def test_write_only_masked_faces(empty_scene, mesh_data):
    obj = add_suzanne_with_seams()
    mesh = obj.data
    before = loop_uv_array(mesh).copy()
    a = mesh_data.mesh_arrays(obj)
    # One value per loop (a quad's two triangles share two loops).
    new = np.random.default_rng(0).random((len(mesh.loops), 2))[a.tri_loops]
    mask = a.tri_poly % 3 == 0
    new[5] = np.nan  # never written, even though masked
    mask[5] = True
    mesh_data.write_corner_uvs(mesh, None, a.tri_loops, new, mask)
    after = loop_uv_array(mesh)
    written = np.zeros(len(mesh.loops), bool)
    m2 = mask.copy()
    m2[5] = False
    written[a.tri_loops[m2].ravel()] = True
    assert np.array_equal(after[~written], before[~written])  # untouched, to the bit
    assert np.array_equal(after[a.tri_loops[m2]], new[m2].astype(np.float32))


def test_write_creates_uv_map(empty_scene, mesh_data):
    bpy.ops.mesh.primitive_plane_add()
    obj = bpy.context.active_object
    obj.data.uv_layers.remove(obj.data.uv_layers[0])
    a = mesh_data.mesh_arrays(obj)
    assert a.corner_uv is None
    uv = np.array([[[0, 0], [1, 0], [1, 1]], [[0, 0], [1, 1], [0, 1]]], float)[: len(a.F)]
    name = mesh_data.write_corner_uvs(obj.data, None, a.tri_loops, uv, np.ones(len(a.F), bool))
    assert name == "UVMap" and obj.data.uv_layers.active.name == "UVMap"
    assert np.array_equal(loop_uv_array(obj.data)[a.tri_loops], uv.astype(np.float32))


def test_edit_mode_refused_and_topology_key(empty_scene, mesh_data):
    obj = add_suzanne_with_seams()
    k1 = mesh_data.mesh_arrays(obj).topology_key
    assert mesh_data.mesh_arrays(obj).topology_key == k1
    set_mode(obj, 'EDIT')
    with pytest.raises(RuntimeError, match="Edit Mode"):
        mesh_data.mesh_arrays(obj)
    set_mode(obj, 'OBJECT')
    obj.data.vertices[3].co.x += 0.01
    assert mesh_data.mesh_arrays(obj).topology_key != k1
