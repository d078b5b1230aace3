"""Issue 6, Blender part: bad input, faults and cancellation for uv.bd_unwrap, through bpy 5.0.1.

Every case asserts the report the user gets (level and text) and that nothing changed: the mesh
and ALL its UV maps byte-for-byte (``snapshot``: positions, topology, seams, selection, every UV
map's UVs and pins, attribute names and every attribute's raw data). Where a certified result is
written for the islands that could be solved, distortion is recomputed from the written loops with
the independent formula of ``conftest.triangle_distortion``: no flip, max <= C.

Reports of a ``bpy.ops`` call are read from what Blender prints for them ("Info: ...",
"Warning: ...", "Error: ..." on ``sys.stdout``; an ERROR also raises ``RuntimeError``). The modal
cases drive ``invoke`` / ``modal`` by hand as ``test_operator_background.py`` does (headless
Blender has no event loop), and record ``self.report`` calls directly.

Already covered elsewhere (only what is missing is added here):
- n-gons alone: test_operator_unwrap_options.py::test_ngons_and_object_scale_ignored_on_request
- non-uniform scale: test_operator_unwrap.py::test_suzanne_is_certified_from_the_written_loops,
  test_operator_unwrap_options.py::test_every_object_in_edit_mode_is_unwrapped
- Esc and an edit while solving, active UV map only:
  test_operator_background.py::test_escape_cancels_and_leaves_everything_untouched,
  ::test_mesh_edited_while_solving_is_not_written
- undo/redo of the active UV map: test_operator_unwrap.py::test_undo_restores_the_previous_uvs
"""
import re

import numpy as np
import pytest

from conftest import add_grid, bpy, loop_uv_array, select_polygons, set_mode
from conftest import triangle_distortion
from test_operator_background import Context, _event, _operator, gated  # noqa: F401 (fixture)

SLACK = 1 + 1e-4  # float32 UV storage, see test_operator_unwrap.py

# -- helpers -------------------------------------------------------------------------------------

_ATTR_TYPES = {  # data_type -> (foreach property, dtype, values per element)
    'FLOAT': ("value", np.float32, 1), 'INT': ("value", np.int32, 1),
    'BOOLEAN': ("value", bool, 1), 'INT8': ("value", np.int32, 1),
    'FLOAT_VECTOR': ("vector", np.float32, 3), 'FLOAT2': ("vector", np.float32, 2),
    'FLOAT_COLOR': ("color", np.float32, 4), 'BYTE_COLOR': ("color", np.float32, 4),
    'INT32_2D': ("value", np.int32, 2), 'QUATERNION': ("value", np.float32, 4),
    'FLOAT4X4': ("value", np.float32, 16),
}


def _get(collection, prop, dtype, n, width=1):
    out = np.empty(n * width, dtype)
    if n:
        collection.foreach_get(prop, out)
    return out


def snapshot(mesh):
    """Everything an unwrap could touch, as bytes (the mesh in Object Mode)."""
    nv, ne, nl, nf = len(mesh.vertices), len(mesh.edges), len(mesh.loops), len(mesh.polygons)
    snap = {
        "counts": (nv, ne, nl, nf),
        "co": _get(mesh.vertices, "co", np.float32, nv, 3).tobytes(),
        "loop_vert": _get(mesh.loops, "vertex_index", np.int32, nl).tobytes(),
        "loop_edge": _get(mesh.loops, "edge_index", np.int32, nl).tobytes(),
        "edge_verts": _get(mesh.edges, "vertices", np.int32, ne, 2).tobytes(),
        "seams": _get(mesh.edges, "use_seam", bool, ne).tobytes(),
        "loop_start": _get(mesh.polygons, "loop_start", np.int32, nf).tobytes(),
        "vert_select": _get(mesh.vertices, "select", bool, nv).tobytes(),
        "edge_select": _get(mesh.edges, "select", bool, ne).tobytes(),
        "poly_select": _get(mesh.polygons, "select", bool, nf).tobytes(),
        "uv_maps": [layer.name for layer in mesh.uv_layers],
        "uv_active": (mesh.uv_layers.active.name if mesh.uv_layers.active else None),
    }
    for layer in mesh.uv_layers:
        snap[f"uv:{layer.name}"] = _get(layer.uv, "vector", np.float32, nl, 2).tobytes()
        snap[f"pin:{layer.name}"] = (_get(layer.pin, "value", bool, nl).tobytes()
                                     if len(layer.pin) == nl else None)
    sizes = {'POINT': nv, 'EDGE': ne, 'CORNER': nl, 'FACE': nf}
    names = []
    for a in mesh.attributes:
        prop, dtype, width = _ATTR_TYPES[a.data_type]
        data = _get(a.data, prop, dtype, sizes[a.domain], width)
        # Blender 5.0 drops internal attributes (".select_vert", ".uv_select_vert", ...) that
        # hold only their default and creates them on demand: absent == all zero.
        if a.name.startswith(".") and not data.any():
            continue
        names.append((a.name, a.domain, a.data_type))
        snap[f"attr:{a.name}"] = data.tobytes()
    snap["attribute_names"] = sorted(names)
    return snap


def assert_unchanged(before, after, ignore=()):
    changed = sorted(k for k in set(before) | set(after)
                     if k not in ignore and before.get(k) != after.get(k))
    assert not changed, f"changed: {changed}"


def snap_object(obj):
    """``snapshot`` of ``obj``'s mesh, leaving every object's mode as it was."""
    was_edit = bpy.context.mode == 'EDIT_MESH'
    if was_edit:
        bpy.ops.object.mode_set(mode='OBJECT')
    try:
        return snapshot(obj.data)
    finally:
        if was_edit:
            bpy.ops.object.mode_set(mode='EDIT')


def run(capsys, *args, **props):
    """``bpy.ops.uv.bd_unwrap(*args, **props)`` -> (result or None when it raised, reports).

    ``reports`` is a list of (level, message) with level 'INFO' | 'WARNING' | 'ERROR'.
    """
    capsys.readouterr()
    try:
        result = bpy.ops.uv.bd_unwrap(*(args or ('EXEC_DEFAULT',)), **props)
    except RuntimeError as error:
        result, raised = None, str(error)
    else:
        raised = None
    out = capsys.readouterr().out
    reports = [({"Info": 'INFO', "Warning": 'WARNING', "Error": 'ERROR'}[m[1]], m[2])
               for m in re.finditer(r"^(Info|Warning|Error): (.*)$", out, re.M)]
    if raised is not None:
        assert raised.startswith("Error: ") or "poll()" in raised, raised
        if "poll()" in raised:
            reports.append(('POLL', raised))
    return result, reports


def add_uv_maps(obj, count, seed=0):
    """Add ``count`` UV maps of random UVs to ``obj`` (Object Mode); the first stays active."""
    rng = np.random.default_rng(seed)
    mesh = obj.data
    for i in range(count):
        layer = mesh.uv_layers.new(name=f"Extra{i}")
        layer.uv.foreach_set("vector", rng.random(2 * len(mesh.loops)).astype(np.float32))
    mesh.uv_layers.active_index = 0
    return [layer.name for layer in mesh.uv_layers]


def pin_some(obj, layer_name, every=5):
    layer = obj.data.uv_layers[layer_name]
    layer.pin_ensure()
    pins = np.zeros(len(obj.data.loops), bool)
    pins[::every] = True
    layer.pin.foreach_set("value", pins)
    return pins


def certified(obj, bound, uv_name=None, poly_mask=None, scale=None):
    """Max distortion of the written loops of ``obj`` (Object Mode), from first principles;
    asserts no flipped triangle (w.r.t. the mesh's own winding) and max <= ``bound``."""
    mesh = obj.data
    mesh.calc_loop_triangles()
    n = len(mesh.loop_triangles)
    tris = _get(mesh.loop_triangles, "vertices", np.int32, n, 3).reshape(-1, 3)
    loops = _get(mesh.loop_triangles, "loops", np.int32, n, 3).reshape(-1, 3)
    poly = _get(mesh.loop_triangles, "polygon_index", np.int32, n)
    V = _get(mesh.vertices, "co", np.float32, len(mesh.vertices), 3).reshape(-1, 3)
    V = V.astype(np.float64) * np.abs(np.asarray(scale if scale is not None else obj.scale))
    keep = np.ones(n, bool) if poly_mask is None else np.asarray(poly_mask)[poly]
    uv = loop_uv_array(mesh, uv_name)[loops[keep]]
    D, det = triangle_distortion(V, tris[keep], uv)
    assert (det > 0).all(), f"{obj.name}: {(det <= 0).sum()} flipped"
    assert D.max() <= bound * SLACK, (obj.name, D.max(), bound)
    return D.max()


def grid_in_edit_mode(x=6, y=5, uv_maps=2):
    obj = add_grid(x, y)
    add_uv_maps(obj, uv_maps)
    pin_some(obj, "Extra0")  # pins on a map that is not the one written
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    return obj


def last():
    return bpy.context.window_manager.bd_uv_last_result


# -- not in Edit Mode / no mesh ------------------------------------------------------------------

def test_not_in_edit_mode_fails_poll_with_a_reason(addon, capsys):
    obj = add_grid()
    add_uv_maps(obj, 2)
    before = snapshot(obj.data)
    for mode in ('EXEC_DEFAULT', 'INVOKE_DEFAULT'):
        result, reports = run(capsys, mode)
        assert result is None
        assert reports == [('POLL', "Operator bpy.ops.uv.bd_unwrap.poll() Needs a mesh in Edit "
                            "Mode: select a mesh object, press Tab and select the faces to "
                            "unwrap")]
    assert not bpy.ops.uv.bd_unwrap.poll()
    assert obj.mode == 'OBJECT' and not last().valid
    assert_unchanged(before, snapshot(obj.data))


def test_no_mesh_or_active_object_not_a_mesh(addon, capsys):
    # An empty scene: nothing to unwrap.
    result, reports = run(capsys)
    assert result is None and reports[0][0] == 'POLL' and "Needs a mesh in Edit Mode" in \
        reports[0][1]
    # A mesh in the scene, but the object in Edit Mode is a curve.
    mesh_obj = add_grid()
    before = snapshot(mesh_obj.data)
    bpy.ops.curve.primitive_bezier_curve_add(location=(4, 0, 0))
    curve = bpy.context.active_object
    mesh_obj.select_set(True)  # selected too, but not active
    bpy.ops.object.mode_set(mode='EDIT')
    assert bpy.context.mode == 'EDIT_CURVE'
    result, reports = run(capsys)
    assert result is None and reports[0][0] == 'POLL' and "Needs a mesh in Edit Mode" in \
        reports[0][1]
    bpy.ops.object.mode_set(mode='OBJECT')
    # A selected mesh in Object Mode with an Empty active.
    bpy.ops.object.empty_add(location=(0, 4, 0))
    mesh_obj.select_set(True)
    result, reports = run(capsys)
    assert result is None and reports[0][0] == 'POLL'
    assert curve.type == 'CURVE' and mesh_obj.mode == 'OBJECT'
    assert_unchanged(before, snapshot(mesh_obj.data))


# -- no faces / mixed selection ------------------------------------------------------------------

def test_no_faces_selected(addon, capsys, request):
    obj = grid_in_edit_mode()
    bpy.ops.mesh.select_all(action='DESELECT')
    before = snap_object(obj)
    for mode in ('EXEC_DEFAULT', 'INVOKE_DEFAULT'):  # headless INVOKE runs execute()
        assert run(capsys, mode) == ({'CANCELLED'}, [
            ('WARNING', "No faces selected: select the faces to unwrap in Edit Mode")])
    # The modal path (an event loop faked by ``gated``) refuses before starting a job.
    request.getfixturevalue("gated")
    op, context = _operator(), Context()
    assert op.invoke(context, _event('LEFTMOUSE', 'PRESS')) == {'CANCELLED'}
    assert op.reports == [({'WARNING'}, "No faces selected: select the faces to unwrap in "
                           "Edit Mode")]
    assert not hasattr(op, "_job") and context.window_manager.calls == []
    # Vertices and edges selected, but no whole face.
    set_mode(obj, 'OBJECT')
    obj.data.vertices[0].select = obj.data.vertices[1].select = True
    obj.data.edges[0].select = True
    set_mode(obj, 'EDIT')
    before = snap_object(obj)
    result, reports = run(capsys)
    assert result == {'CANCELLED'} and reports[0][0] == 'WARNING'
    assert reports[0][1].startswith("No faces selected")
    assert obj.mode == 'EDIT' and not last().valid
    assert_unchanged(before, snap_object(obj))


def test_mixed_selection_across_objects(addon, capsys):
    """Three meshes in Edit Mode: all faces, no face, some faces selected."""
    a, b, c = add_grid(5, 4), add_grid(4, 4), add_grid(6, 5)
    b.location.x, c.location.x = 5, -5
    for ob in (a, b, c):
        add_uv_maps(ob, 2, seed=len(ob.data.loops))
        pin_some(ob, "Extra1")
    select_polygons(a, np.ones(len(a.data.polygons), bool))
    select_polygons(b, np.zeros(len(b.data.polygons), bool))
    c_sel = np.zeros(len(c.data.polygons), bool)
    c_sel[:12] = True
    select_polygons(c, c_sel)
    before = {ob.name: snapshot(ob.data) for ob in (a, b, c)}
    for ob in (a, b, c):
        ob.select_set(True)
    bpy.context.view_layer.objects.active = a
    bpy.ops.object.mode_set(mode='EDIT')
    assert {o.name for o in bpy.context.objects_in_mode} == {a.name, b.name, c.name}

    result, reports = run(capsys, bound=2.0)
    assert result == {'FINISHED'}
    assert len(reports) == 1 and reports[0][0] == 'INFO'
    assert reports[0][1].startswith("BD-LSCM: 2 islands, max distortion ")
    assert last().faces == len(a.data.polygons) + 12  # polygons, as the user counts faces
    assert {o.name for o in bpy.context.objects_in_mode} == {a.name, b.name, c.name}
    bpy.ops.object.mode_set(mode='OBJECT')
    # b: nothing selected, nothing changed at all.
    assert_unchanged(before[b.name], snapshot(b.data))
    # a, c: only the active UV map's selected loops changed, and they are certified.
    for ob, sel in ((a, np.ones(len(a.data.polygons), bool)), (c, c_sel)):
        after = snapshot(ob.data)
        assert_unchanged(before[ob.name], after, ignore=("uv:UVMap", "attr:UVMap"))
        total = _get(ob.data.polygons, "loop_total", np.int32, len(ob.data.polygons))
        loop_sel = np.repeat(sel, total)
        old = np.frombuffer(before[ob.name]["uv:UVMap"], np.float32).reshape(-1, 2)
        new = loop_uv_array(ob.data, "UVMap")
        assert np.array_equal(new[~loop_sel], old[~loop_sel])
        assert (new[loop_sel] != old[loop_sel]).any(axis=1).mean() > 0.9
        certified(ob, 2.0, "UVMap", poly_mask=sel)


def test_object_that_cannot_be_solved_keeps_every_map(addon, capsys):
    """A grid and a closed cube (no seams) in Edit Mode together: the grid is written and
    certified, the cube named in a WARNING and left byte-for-byte as it was, all three maps."""
    grid = add_grid(5, 4)
    bpy.ops.mesh.primitive_cube_add(location=(5, 0, 0))
    cube = bpy.context.active_object
    for ob in (grid, cube):
        add_uv_maps(ob, 2, seed=len(ob.data.loops))
        pin_some(ob, "Extra0")
        select_polygons(ob, np.ones(len(ob.data.polygons), bool))
    before = snapshot(cube.data)
    grid.select_set(True)
    cube.select_set(True)
    bpy.context.view_layer.objects.active = grid
    bpy.ops.object.mode_set(mode='EDIT')
    result, reports = run(capsys, bound=2.0, seams='MARKED')
    assert result == {'FINISHED'} and len(reports) == 1 and reports[0][0] == 'WARNING'
    message = reports[0][1]
    assert message.startswith("BD-LSCM: 1 island, max distortion ")
    assert re.search(r"; island \d+ of Cube \(6 faces\) is closed: .*seam.*; left as it was$",
                     message, re.I), message
    bpy.ops.object.mode_set(mode='OBJECT')
    assert_unchanged(before, snapshot(cube.data))
    certified(grid, 2.0)


# -- modifiers, scale, linked duplicates ---------------------------------------------------------

def test_modifiers_unwrap_the_base_mesh(addon, capsys):
    obj = add_grid(6, 5)
    add_uv_maps(obj, 1)
    subsurf = obj.modifiers.new("Subdivision", 'SUBSURF')
    subsurf.levels = 2
    mirror = obj.modifiers.new("Mirror", 'MIRROR')
    mirror.use_axis = (True, False, False)
    mirror.mirror_offset_u = 0.25
    base_faces = len(obj.data.polygons)
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
    assert len(evaluated.polygons) == 2 * 16 * base_faces  # the modifiers really do something
    before = snapshot(obj.data)
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    result, reports = run(capsys, bound=2.0)
    assert result == {'FINISHED'} and [r[0] for r in reports] == ['INFO']
    assert reports[0][1].startswith("BD-LSCM: 1 island, max distortion ")
    assert last().faces == base_faces  # the base mesh's polygons, not the subdivided ones
    set_mode(obj, 'OBJECT')
    assert_unchanged(before, snapshot(obj.data), ignore=("uv:UVMap", "attr:UVMap"))
    assert [(m.name, m.type) for m in obj.modifiers] == [("Subdivision", 'SUBSURF'),
                                                         ("Mirror", 'MIRROR')]
    assert subsurf.levels == 2 and tuple(mirror.use_axis) == (True, False, False)
    certified(obj, 2.0)


@pytest.mark.parametrize("scale", [(-1.5, 0.7, 1.0), (-2.0, -1.0, -0.5)])
def test_negative_scale_is_certified_and_not_mirrored(addon, capsys, scale):
    """A mirroring scale unwraps exactly as its magnitudes do (same UVs to the bit, without
    packing), and with packing the written UVs keep the mesh's own winding (no flip)."""
    pos = add_grid(6, 5)
    neg = add_grid(6, 5)
    neg.location.x = 5
    pos.scale = tuple(abs(c) for c in scale)
    neg.scale = scale
    written = {}
    for ob in (pos, neg):
        set_mode(ob, 'EDIT')
        bpy.ops.mesh.select_all(action='SELECT')
        result, reports = run(capsys, bound=2.0, pack=False)
        assert result == {'FINISHED'} and reports[0][0] == 'INFO', reports
        set_mode(ob, 'OBJECT')
        written[ob.name] = loop_uv_array(ob.data).tobytes()
        certified(ob, 2.0)
    assert written[pos.name] == written[neg.name]
    set_mode(neg, 'EDIT')
    result, reports = run(capsys, bound=2.0)  # packed
    assert result == {'FINISHED'} and reports[0][0] == 'INFO'
    set_mode(neg, 'OBJECT')
    certified(neg, 2.0)
    uv = loop_uv_array(neg.data)
    assert uv.min() >= 0 and uv.max() <= 1


def test_zero_scale_is_refused_by_name(addon, capsys):
    """A zero scale flattens the object: refused up front, naming the object and the fix (the
    core would otherwise report 'zero-area faces' of a mesh that has none)."""
    obj = add_grid()
    obj.scale = (1.0, 0.0, 1.0)
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    before = snap_object(obj)
    assert run(capsys) == ({'CANCELLED'}, [
        ('WARNING', "Grid has scale (1, 0, 1), which flattens it: give it a non-zero scale or "
                    "turn off Use Object Scale")])
    assert_unchanged(before, snap_object(obj))
    # Without the object scale the mesh itself is unwrapped.
    result, reports = run(capsys, bound=2.0, use_object_scale=False)
    assert result == {'FINISHED'} and reports[0][0] == 'INFO'
    set_mode(obj, 'OBJECT')
    certified(obj, 2.0, scale=(1, 1, 1))


def test_linked_duplicates_share_one_unwrap(addon, capsys):
    """Two objects on one mesh: Blender puts only the active one in Edit Mode, so the mesh is
    unwrapped once, for the active object's scale, and both show the same UVs."""
    a = add_grid(6, 5)
    b = a.copy()
    bpy.context.collection.objects.link(b)
    b.location.x = 5
    b.scale = (2.0, 0.5, 1.0)
    assert a.data is b.data
    faces = len(a.data.polygons)
    for active, other in ((b, a), (a, b)):
        set_mode(active, 'OBJECT')
        other.select_set(True)
        bpy.ops.object.mode_set(mode='EDIT')
        assert (active.mode, other.mode) == ('EDIT', 'OBJECT')  # Blender edits the mesh once
        bpy.ops.mesh.select_all(action='SELECT')
        result, reports = run(capsys, bound=1.5, pack=False)
        assert result == {'FINISHED'} and reports[0][0] == 'INFO'
        assert reports[0][1].startswith("BD-LSCM: 1 island, ")
        assert last().faces == faces  # once, not once per object
        bpy.ops.object.mode_set(mode='OBJECT')
        assert a.data is b.data
        certified(active, 1.5)  # certified for the scale of the object being edited
    # The two scales need different maps: with b's (non-uniform) scale the map for a's shape
    # is more than 1.5 off somewhere, so the last write really was for a.
    with pytest.raises(AssertionError):
        certified(b, 1.5)


# -- UV-map limit --------------------------------------------------------------------------------

def test_mesh_at_the_uv_map_limit(addon, capsys):
    """Blender allows 8 UV maps and keeps one active in Edit Mode while any exist (checked
    below), so bd_unwrap never needs a new map there: it writes the active one and leaves the
    other seven and every pin layer byte-for-byte as they were."""
    obj = add_grid(6, 5)
    mesh = obj.data
    names = add_uv_maps(obj, 7)
    assert len(names) == 8 and mesh.uv_layers.new(name="Ninth") is None  # the limit
    pin_some(obj, "Extra2")
    # There is no way to leave 8 maps without an active one where bd_unwrap runs (Edit Mode):
    # Blender 5.0 keeps one active even in Object Mode; 5.1 lets Object Mode clear it, and
    # entering Edit Mode makes one active again.
    mesh.uv_layers.active_index = -1
    mesh.uv_layers.active = None
    set_mode(obj, 'EDIT')
    set_mode(obj, 'OBJECT')
    assert mesh.uv_layers.active is not None
    mesh.uv_layers.active = mesh.uv_layers["Extra4"]
    before = snapshot(mesh)
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    result, reports = run(capsys, bound=2.0)
    assert result == {'FINISHED'} and reports[0][0] == 'INFO'
    set_mode(obj, 'OBJECT')
    assert [layer.name for layer in mesh.uv_layers] == names
    assert_unchanged(before, snapshot(mesh), ignore=("uv:Extra4", "attr:Extra4"))
    assert snapshot(mesh)["uv:Extra4"] != before["uv:Extra4"]
    certified(obj, 2.0, "Extra4")


def test_frames_from_uvs_without_a_uv_map(addon, capsys):
    """'From Current UVs' needs a UV map: refused by name, and no map is created."""
    obj = add_grid()
    obj.data.uv_layers.remove(obj.data.uv_layers[0])
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    before = snap_object(obj)
    assert run(capsys, frames='input-uv') == ({'CANCELLED'}, [
        ('WARNING', "Grid has no UV map to take frames from")])
    set_mode(obj, 'OBJECT')
    assert len(obj.data.uv_layers) == 0
    assert_unchanged(before, snapshot(obj.data))


# -- n-gons and loose geometry -------------------------------------------------------------------

def test_ngons_and_loose_geometry(addon, capsys):
    import bmesh

    obj = add_grid(5, 4)
    add_uv_maps(obj, 1)
    set_mode(obj, 'EDIT')
    bm = bmesh.from_edit_mesh(obj.data)
    # An n-gon (a flat 9-gon away from the grid), two loose vertices and a loose edge chain.
    ring = [bm.verts.new((4 + np.cos(t), np.sin(t), 0.1 * np.sin(3 * t)))
            for t in np.linspace(0, 2 * np.pi, 9, endpoint=False)]
    bm.faces.new(ring)
    loose = [bm.verts.new(p) for p in ((0, 3, 1), (1, 3, 1), (2, 3, 1), (-3, 0, 0))]
    bm.edges.new(loose[:2])
    bm.edges.new(loose[1:3])
    bmesh.update_edit_mesh(obj.data)
    bpy.ops.mesh.select_all(action='SELECT')
    before = snap_object(obj)
    mesh = obj.data
    set_mode(obj, 'OBJECT')
    poly_sides = _get(mesh.polygons, "loop_total", np.int32, len(mesh.polygons))
    assert poly_sides.max() == 9 and len(mesh.vertices) > 9 + 4
    loose_ids = np.arange(len(mesh.vertices))[-4:]
    set_mode(obj, 'EDIT')
    result, reports = run(capsys, bound=2.0)
    assert result == {'FINISHED'} and reports[0][0] == 'INFO'
    assert reports[0][1].startswith("BD-LSCM: 2 islands, ")
    assert last().faces == len(poly_sides)  # polygons (n-gon counted once); loose: none
    set_mode(obj, 'OBJECT')
    after = snapshot(mesh)
    assert_unchanged(before, after, ignore=("uv:UVMap", "attr:UVMap"))
    co = np.frombuffer(after["co"], np.float32).reshape(-1, 3)
    assert np.array_equal(co[loose_ids], [(0, 3, 1), (1, 3, 1), (2, 3, 1), (-3, 0, 0)])
    certified(obj, 2.0)  # every triangle of every polygon, the 9-gon's seven too


# -- background solve: edits, deletion, Esc ------------------------------------------------------

def _two_grids_in_edit_mode():
    a, b = add_grid(6, 5), add_grid(5, 4)
    b.location.x = 5
    for ob in (a, b):
        add_uv_maps(ob, 2, seed=len(ob.data.loops))
        pin_some(ob, "Extra0")
        select_polygons(ob, np.ones(len(ob.data.polygons), bool))
    a.select_set(True)
    b.select_set(True)
    bpy.context.view_layer.objects.active = a
    bpy.ops.object.mode_set(mode='EDIT')
    return a, b


@pytest.mark.parametrize("edit", ["move vertex", "move uv", "select", "scale", "rename",
                                  "add uv map"])
def test_edited_while_solving_is_not_written(addon, gated, edit):
    """The user changes the mesh in Edit Mode while the solve runs (test_operator_background.py
    moves a vertex in Object Mode and checks the active map only): nothing is written to it, all
    its maps stay as they are, the untouched object is written. A new object scale counts as a
    change (the result is certified for the scale it was solved at); a renamed object is not
    written either (objects are found again by name)."""
    import bmesh

    a, b = _two_grids_in_edit_mode()
    op, context = _operator(bound=2.0), Context()
    assert op.invoke(context, _event('LEFTMOUSE', 'PRESS')) == {'RUNNING_MODAL'}
    bm = bmesh.from_edit_mesh(b.data)
    if edit == "move vertex":
        bm.verts.ensure_lookup_table()
        bm.verts[3].co.z += 0.2
    elif edit == "move uv":
        layer = bm.loops.layers.uv.active
        bm.faces.ensure_lookup_table()
        bm.faces[2].loops[0][layer].uv.x += 0.1
    elif edit == "select":
        bm.verts.ensure_lookup_table()
        bm.verts[0].select_set(False)  # a corner vertex: its face is deselected too
        bm.select_flush_mode()
    elif edit == "scale":
        b.scale = (1.0, 3.0, 1.0)
    elif edit == "rename":
        b_name = b.name
        b.name = "Renamed"
    else:
        bm.loops.layers.uv.new("Late")  # a new map, not active: the active one is unchanged
    bmesh.update_edit_mesh(b.data)
    before_b = snap_object(b)
    gated.set()
    op._job.wait()
    if edit == "add uv map":  # a map the unwrap does not read: b is still written
        assert op.modal(context, _event('TIMER')) == {'FINISHED'}
        assert [r[0] for r in op.reports] == [{'INFO'}]
        bpy.ops.object.mode_set(mode='OBJECT')
        certified(b, 2.0)
        assert [layer.name for layer in b.data.uv_layers][-1] == "Late"
        return
    assert op.modal(context, _event('TIMER')) == {'FINISHED'}
    assert op.reports[-1][0] == {'WARNING'}
    # Only what was written and kept is counted: a's island.
    assert op.reports[-1][1].startswith("BD-LSCM: 1 island, max distortion ")
    if edit == "rename":
        assert op.reports[-1][1].endswith(
            f"; {b_name} not written: deleted or renamed while solving")
    else:
        assert op.reports[-1][1].endswith(f"; {b.name} not written: changed while solving")
    assert {o.name for o in bpy.context.objects_in_mode} == {a.name, b.name}
    bpy.ops.object.mode_set(mode='OBJECT')
    assert_unchanged(before_b, snapshot(b.data))
    certified(a, 2.0)


def test_deleted_while_solving(addon, gated):
    """One of two objects is deleted while the solve runs: the other is written, the deleted one
    reported; then the only object in Edit Mode is deleted (and its mesh purged): no crash."""
    a, b = _two_grids_in_edit_mode()
    b_name = b.name
    op, context = _operator(bound=2.0), Context()
    assert op.invoke(context, _event('LEFTMOUSE', 'PRESS')) == {'RUNNING_MODAL'}
    bpy.ops.object.mode_set(mode='OBJECT')
    bpy.data.objects.remove(b)
    bpy.context.view_layer.objects.active = a
    a.select_set(True)
    bpy.ops.object.mode_set(mode='EDIT')
    gated.set()
    op._job.wait()
    assert op.modal(context, _event('TIMER')) == {'FINISHED'}
    assert op.reports[-1][0] == {'WARNING'}
    assert op.reports[-1][1].endswith(f"; {b_name} not written: deleted or renamed while solving")
    bpy.ops.object.mode_set(mode='OBJECT')
    certified(a, 2.0)

    # The only object being unwrapped is deleted, its mesh purged, and another mesh is in
    # Edit Mode when the result arrives: nothing is written anywhere.
    gated.clear()
    c = add_grid(4, 4)
    c.location.y = 5
    set_mode(a, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    op, context = _operator(bound=2.0), Context()
    assert op.invoke(context, _event('LEFTMOUSE', 'PRESS')) == {'RUNNING_MODAL'}
    bpy.ops.object.mode_set(mode='OBJECT')
    a_name, mesh = a.name, a.data
    bpy.data.objects.remove(a)
    bpy.data.meshes.remove(mesh)
    before_c = snapshot(c.data)
    set_mode(c, 'EDIT')
    gated.set()
    op._job.wait()
    assert op.modal(context, _event('TIMER')) == {'CANCELLED'}
    assert op.reports[-1] == ({'ERROR'}, op.reports[-1][1])
    assert op.reports[-1][1].endswith(f"; {a_name} not written: deleted or renamed while solving")
    set_mode(c, 'OBJECT')
    assert_unchanged(before_c, snapshot(c.data))

    # Deleted and Edit Mode left: the modal step says so.
    gated.clear()
    set_mode(c, 'EDIT')
    op, context = _operator(bound=2.0), Context()
    assert op.invoke(context, _event('LEFTMOUSE', 'PRESS')) == {'RUNNING_MODAL'}
    bpy.ops.object.mode_set(mode='OBJECT')
    bpy.data.objects.remove(c)
    gated.set()
    op._job.wait()
    assert op.modal(context, _event('TIMER')) == {'CANCELLED'}
    assert op.reports[-1] == ({'WARNING'}, "Left Edit Mode while solving: nothing written")


@pytest.mark.parametrize("when", ["while solving", "after the solve, before the timer"])
def test_escape_leaves_every_uv_map_untouched(addon, gated, when):
    a, b = _two_grids_in_edit_mode()
    before = {ob.name: snap_object(ob) for ob in (a, b)}
    op, context = _operator(bound=2.0), Context()
    assert op.invoke(context, _event('LEFTMOUSE', 'PRESS')) == {'RUNNING_MODAL'}
    if when != "while solving":
        gated.set()
        assert op._job.wait() is not None  # a result is waiting in the queue
    assert op.modal(context, _event('ESC', 'PRESS')) == {'CANCELLED'}
    assert op.reports == [({'WARNING'}, "Unwrap cancelled: mesh and UVs unchanged")]
    gated.set()
    op._job.wait()
    assert {o.name for o in bpy.context.objects_in_mode} == {a.name, b.name}
    bpy.ops.object.mode_set(mode='OBJECT')
    for ob in (a, b):
        assert_unchanged(before[ob.name], snapshot(ob.data))
    assert not last().valid


# -- undo ----------------------------------------------------------------------------------------

def test_undo_restores_every_object(addon, capsys):
    """Two objects in Edit Mode, one unwrap, one undo: both meshes back byte-for-byte."""
    a, b = _two_grids_in_edit_mode()
    before = {ob.name: snap_object(ob) for ob in (a, b)}
    bpy.ops.ed.undo_push(message="before bd_unwrap")
    result, reports = run(capsys, 'EXEC_DEFAULT', True, bound=2.0)
    assert result == {'FINISHED'} and reports[0][0] == 'INFO'
    assert reports[0][1].startswith("BD-LSCM: 2 islands, ")
    bpy.ops.ed.undo()
    assert {o.name for o in bpy.context.objects_in_mode} == set(before)
    bpy.ops.object.mode_set(mode='OBJECT')
    for name, snap in before.items():
        assert_unchanged(snap, snapshot(bpy.data.objects[name].data))


def test_undo_restores_every_uv_map_and_attribute(addon, capsys):
    """Undo right after an unwrap that also packed and added distortion attributes: every map,
    pin and attribute is back byte-for-byte (test_operator_unwrap.py checks the active map)."""
    obj = add_grid(6, 5)
    add_uv_maps(obj, 2)
    pin_some(obj, "Extra1")
    select_polygons(obj, np.ones(len(obj.data.polygons), bool))
    before = snapshot(obj.data)
    set_mode(obj, 'EDIT')
    bpy.ops.ed.undo_push(message="before bd_unwrap")
    result, reports = run(capsys, 'EXEC_DEFAULT', True, bound=2.0, show_distortion=True)
    assert result == {'FINISHED'} and reports[0][0] == 'INFO'
    # Read without leaving Edit Mode (a mode toggle would be an undo step of its own).
    import bmesh

    bm = bmesh.from_edit_mesh(obj.data)
    uv_layer = bm.loops.layers.uv["UVMap"]
    unwrapped = np.array([l[uv_layer].uv[:] for f in bm.faces for l in f.loops], np.float32)
    old = np.frombuffer(before["uv:UVMap"], np.float32).reshape(-1, 2)
    assert not np.array_equal(unwrapped, old)
    added = (set(bm.faces.layers.float.keys()) | set(bm.faces.layers.color.keys())
             | set(bm.loops.layers.color.keys()) | set(bm.loops.layers.float.keys()))
    assert added, "show_distortion wrote no attribute"  # so undo has something to remove
    bpy.ops.ed.undo()
    assert bpy.context.mode == 'EDIT_MESH'
    obj = bpy.data.objects[obj.name]  # undo rebuilt the data-blocks
    bpy.ops.object.mode_set(mode='OBJECT')
    assert_unchanged(before, snapshot(obj.data))
