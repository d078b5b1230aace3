"""uv.bd_unwrap with Seams "Add Where Needed" (issue 11) through bpy: a closed mesh with no seams
unwraps in one click, the seams it added are marked on the mesh, undo takes back UVs and seams.

Independent checks: distortion from an SVD of each triangle's map (conftest.triangle_distortion),
and the marked seams against the UVs read from the loops: the UVs are continuous across every
edge that is not a seam (so the charts are exactly what the marked seams cut).
"""
import numpy as np

from conftest import bpy, load_submodule, loop_uv_array, set_mode, triangle_distortion
from test_bad_input_blender import _get, assert_unchanged, last, run, snapshot
from test_operator_unwrap import SLACK, _loop_triangles

C, S = 2.0, 2.0


def _uv_sphere(segments=16, rings=8, uv=False):
    """A closed UV sphere (quads and two triangle fans), no seams, no UV map unless ``uv``."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=segments, ring_count=rings)
    obj = bpy.context.active_object
    if not uv:
        while obj.data.uv_layers:
            obj.data.uv_layers.remove(obj.data.uv_layers[0])
    return obj


def _cube_sphere(cuts=3):
    """A closed cube-sphere: a cube subdivided and cast to a sphere (all quads)."""
    bpy.ops.mesh.primitive_cube_add()
    obj = bpy.context.active_object
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    bpy.ops.mesh.subdivide(number_cuts=cuts)
    bpy.ops.transform.tosphere(value=1.0)
    set_mode(obj, 'OBJECT')
    return obj


def _seams(mesh):
    return _get(mesh.edges, "use_seam", bool, len(mesh.edges))


def _edit_all(obj):
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')


def _discontinuous_edges(mesh):
    """(e,) bool: edges whose two polygons give one of its vertices different UVs (Object Mode)."""
    nl, ne, nv = len(mesh.loops), len(mesh.edges), len(mesh.vertices)
    uv = np.ascontiguousarray(loop_uv_array(mesh))
    loop_vert = _get(mesh.loops, "vertex_index", np.int32, nl).astype(np.int64)
    loop_edge = _get(mesh.loops, "edge_index", np.int32, nl).astype(np.int64)
    start = _get(mesh.polygons, "loop_start", np.int32, len(mesh.polygons)).astype(np.int64)
    total = _get(mesh.polygons, "loop_total", np.int32, len(mesh.polygons)).astype(np.int64)
    # Loop i runs along edge loop_edge[i] from its vertex to the vertex of the polygon's next
    # loop: both ends of the edge with the UVs this polygon gives them.
    nxt = np.arange(nl) + 1
    nxt[start + total - 1] = start
    bits = uv.view(np.int32)  # exact comparison of the stored float32 values
    rows = np.unique(np.concatenate([
        np.stack([loop_edge, loop_vert[j], bits[j, 0], bits[j, 1]], axis=1)
        for j in (np.arange(nl), nxt)]), axis=0)
    # One row per (edge, vertex, UV): two rows for the same (edge, vertex) mean two UVs.
    uk, counts = np.unique(rows[:, 0] * nv + rows[:, 1], return_counts=True)
    bad = np.zeros(ne, dtype=bool)
    bad[uk[counts > 1] // nv] = True
    return bad


def _check_certified(obj, bound=C):
    V, tris, loops, _ = _loop_triangles(obj)
    D, det = triangle_distortion(V, tris, loop_uv_array(obj.data)[loops])
    assert (det > 0).all(), f"{(det <= 0).sum()} faces flipped or without UVs"
    assert D.max() <= bound * SLACK
    return D


def test_closed_uv_sphere_unwraps_in_one_click(addon, capsys):
    obj = _uv_sphere()
    set_mode(obj, 'OBJECT')
    assert not _seams(obj.data).any() and not obj.data.uv_layers
    _edit_all(obj)
    result, reports = run(capsys, 'EXEC_DEFAULT', seams='AUTO', bound=C, stretch=S)
    assert result == {'FINISHED'}, reports
    level, message = reports[0]
    assert level == 'INFO', message
    set_mode(obj, 'OBJECT')
    seams = _seams(obj.data)
    assert seams.any()
    assert f"; {int(seams.sum())} seams added, " in message and " charts" in message
    charts = int(message.rsplit(", ", 1)[1].split()[0])
    assert last().valid and last().islands == charts and last().failed == 0
    # Every face has UVs (a fresh map holds zeros: det > 0 means written), certified.
    _check_certified(obj)
    # The UVs are cut exactly along the marked seams: continuous across every other edge, and
    # discontinuous across the added seams (else the seam would be for nothing).
    torn = _discontinuous_edges(obj.data)
    assert not (torn & ~seams).any()
    assert torn[seams].mean() > 0.5


def test_cube_sphere_keeps_polygons_whole_and_marked_seams(addon, capsys):
    """All quads: the core's charts may cut a quad's diagonal, which no UV map can hold; the
    operator keeps every quad in one chart. The seams marked before stay marked."""
    obj = _cube_sphere()
    mesh = obj.data
    # Mark the four edges of one face as seams (a closed loop: the face is its own island).
    before = np.zeros(len(mesh.edges), bool)
    loop_edge = _get(mesh.loops, "edge_index", np.int32, len(mesh.loops))
    start, total = mesh.polygons[0].loop_start, mesh.polygons[0].loop_total
    before[loop_edge[start:start + total]] = True
    mesh.edges.foreach_set("use_seam", before)
    mesh.update()
    _edit_all(obj)
    result, reports = run(capsys, 'EXEC_DEFAULT', seams='AUTO', bound=C, stretch=S)
    assert result == {'FINISHED'} and reports[0][0] == 'INFO', reports
    set_mode(obj, 'OBJECT')
    after = _seams(mesh)
    assert after[before].all() and (after & ~before).any()
    _check_certified(obj)
    torn = _discontinuous_edges(mesh)
    assert not (torn & ~after).any()


def test_undo_restores_uvs_and_seams(addon, capsys):
    import bmesh

    obj = _uv_sphere(12, 6, uv=True)
    _edit_all(obj)

    def state():
        bm = bmesh.from_edit_mesh(bpy.context.edit_object.data)
        layer = bm.loops.layers.uv.active
        uv = np.array([l[layer].uv[:] for f in bm.faces for l in f.loops], np.float32)
        return uv, np.array([e.seam for e in bm.edges], bool)

    bpy.ops.ed.undo_push(message="before bd_unwrap")
    uv0, seams0 = state()
    assert not seams0.any()
    result, reports = run(capsys, 'EXEC_DEFAULT', True, seams='AUTO', bound=C)
    assert result == {'FINISHED'}, reports
    uv1, seams1 = state()
    assert seams1.any() and not np.array_equal(uv1, uv0)
    bpy.ops.ed.undo()
    uv2, seams2 = state()
    assert np.array_equal(uv2, uv0) and np.array_equal(seams2, seams0)
    bpy.ops.ed.redo()
    uv3, seams3 = state()
    assert np.array_equal(uv3, uv1) and np.array_equal(seams3, seams1)


def test_minimise_with_added_seams_is_refused(addon, capsys):
    obj = _uv_sphere(12, 6, uv=True)
    set_mode(obj, 'OBJECT')
    before = snapshot(obj.data)
    _edit_all(obj)
    result, reports = run(capsys, 'EXEC_DEFAULT', seams='AUTO', minimise=True)
    assert result == {'CANCELLED'}
    assert reports[0][0] == 'WARNING' and "turn off Minimise" in reports[0][1]
    set_mode(obj, 'OBJECT')
    assert_unchanged(before, snapshot(obj.data), ignore=("vert_select", "edge_select",
                                                          "poly_select"))


def test_marked_still_refuses_a_closed_mesh(addon, capsys):
    """Seams "Marked" (an explicit choice since issue 20) on a closed mesh still refuses to cut
    it: no seam added."""
    obj = _uv_sphere(12, 6, uv=True)
    _edit_all(obj)
    result, reports = run(capsys, 'EXEC_DEFAULT', seams='MARKED')
    assert result == {'CANCELLED'} and reports[0][0] == 'WARNING'
    set_mode(obj, 'OBJECT')
    assert not _seams(obj.data).any()


def test_whole_polygon_labels_and_torn_loops():
    auto = load_submodule("operators.auto_seams")
    # Two quads (0: triangles 0,1; 1: triangles 2,3), quad 0 split 0/1 with more area on 1.
    island = np.array([0, 1, 1, 1])
    poly = np.array([0, 0, 1, 1])
    area = np.array([1.0, 3.0, 1.0, 1.0])
    assert auto.split_polygons(island, poly).tolist() == [0]
    assert auto.whole_polygon_labels(island, poly, area).tolist() == [1, 1, 1, 1]
    # Triangles 0 and 1 share loops 1 and 2 (the diagonal's ends); triangle 1 gives loop 2
    # another UV: both are torn, triangle 2 (own loops) is not.
    loops = np.array([[0, 1, 2], [2, 1, 3], [4, 5, 6]])
    uv = np.zeros((3, 3, 2))
    uv[0] = [[0, 0], [1, 0], [1, 1]]
    uv[1] = [[1, 1.5], [1, 0], [0, 1]]
    uv[2] = [[0, 0], [1, 0], [0, 1]]
    assert auto.torn_loops(uv, loops).tolist() == [True, True, False]
    uv[1, 0] = [1, 1]
    assert auto.torn_loops(uv, loops).tolist() == [False, False, False]


def test_same_seams_whatever_blender_numbers_or_splits():
    """Blender numbers the polygons of a new UV sphere differently from one session to the next
    and splits its symmetric quads along either diagonal (the seams changed from run to run).
    solve() finds the same seams for any polygon order, triangle order, corner rotation and
    diagonals; every chart still a union of whole polygons."""
    auto = load_submodule("operators.auto_seams")
    obj = _uv_sphere()
    set_mode(obj, 'OBJECT')
    V, tris, loops, poly = (np.asarray(a, t) for a, t in zip(
        _loop_triangles(obj), (np.float64, np.int64, np.int64, np.int64)))
    first = auto.solve(V, tris, tri_poly=poly, tri_loops=loops, bound=C, stretch=S)
    assert first.result.certified
    expect = {tuple(sorted(p)) for p in first.added.tolist()}
    rng = np.random.default_rng(3)
    for _ in range(2):
        F, L = tris.copy(), loops.copy()
        # Other diagonals: each quad's two triangles rebuilt on the other diagonal.
        for q in np.flatnonzero(np.bincount(poly) == 2):
            a, b = np.flatnonzero(poly == q)
            ring = np.unique(L[[a, b]])                  # the quad's 4 loops, in order
            vert = {int(l): int(v) for l, v in zip(L[[a, b]].ravel(), F[[a, b]].ravel())}
            k = rng.integers(2)
            t1, t2 = ring[[k, k + 1, k + 2]], ring[[k, k + 2, (k + 3) % 4]]
            L[a], L[b] = t1, t2
            F[a], F[b] = [vert[int(x)] for x in t1], [vert[int(x)] for x in t2]
        rot = rng.integers(3, size=len(F))[:, None]
        idx = (rot + np.arange(3)) % 3
        F, L = np.take_along_axis(F, idx, 1), np.take_along_axis(L, idx, 1)
        perm = rng.permutation(len(F))
        relabel = rng.permutation(poly.max() + 1)
        again = auto.solve(V, F[perm], tri_poly=relabel[poly[perm]], tri_loops=L[perm],
                           bound=C, stretch=S)
        assert again.result.certified
        assert {tuple(sorted(p)) for p in again.added.tolist()} == expect


# -- the background path (invoke + modal, driven by hand as in test_operator_background.py) -----

def _gated_auto(monkeypatch):
    import threading

    unwrap_module = load_submodule("operators.unwrap")
    real, gate = unwrap_module.AUTO_SOLVE, threading.Event()

    def solve(*args, **kwargs):
        gate.wait()
        return real(*args, **kwargs)

    monkeypatch.setattr(unwrap_module, "AUTO_SOLVE", solve)
    # invoke() is BackgroundSolve.invoke: it asks the background module
    monkeypatch.setattr(load_submodule("operators.background"), "has_event_loop",
                        lambda context: True)
    return gate


def test_modal_path_marks_the_added_seams(addon, monkeypatch):
    from test_operator_background import Context, _event, _invoke, _operator

    gate = _gated_auto(monkeypatch)
    obj = _uv_sphere(12, 6, uv=True)
    _edit_all(obj)
    op, context = _operator(seams='AUTO', bound=C), Context()
    assert _invoke(op, context) == {'RUNNING_MODAL'}
    assert op.modal(context, _event('TIMER')) == {'PASS_THROUGH'}  # still gated
    gate.set()
    op._job.wait()
    assert op.modal(context, _event('TIMER')) == {'FINISHED'}, op.reports
    assert " seams added, " in op.reports[-1][1]
    set_mode(obj, 'OBJECT')
    seams = _seams(obj.data)
    assert seams.any()
    _check_certified(obj)
    assert not (_discontinuous_edges(obj.data) & ~seams).any()


def test_escape_leaves_uvs_and_seams_untouched(addon, monkeypatch):
    from test_operator_background import Context, _event, _invoke, _operator

    gate = _gated_auto(monkeypatch)
    obj = _uv_sphere(12, 6, uv=True)
    set_mode(obj, 'OBJECT')
    before = snapshot(obj.data)
    _edit_all(obj)
    op, context = _operator(seams='AUTO', bound=C), Context()
    assert _invoke(op, context) == {'RUNNING_MODAL'}
    assert op.modal(context, _event('ESC', 'PRESS')) == {'CANCELLED'}
    gate.set()  # the solve starts only now, sees the cancel event and stops
    outcome = op._job.wait()
    assert isinstance(outcome.error, load_submodule("bd_uv").CancelledError)
    set_mode(obj, 'OBJECT')
    assert_unchanged(before, snapshot(obj.data), ignore=("vert_select", "edge_select",
                                                          "poly_select"))


def test_subdivided_suzanne_every_chart_kept(addon, capsys):
    """About 2,000 quads (Suzanne subdivided once: a head with open eye sockets, two closed
    eyes). The certifying solve cuts overlapping charts again, through quads too; every polygon
    still ends in one chart and every chart is written and kept (an INFO report: nothing failed,
    nothing put back)."""
    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.active_object
    modifier = obj.modifiers.new("subdivide", 'SUBSURF')
    modifier.levels = 1
    bpy.ops.object.modifier_apply(modifier=modifier.name)
    _edit_all(obj)
    result, reports = run(capsys, 'EXEC_DEFAULT', seams='AUTO', bound=C, stretch=S)
    assert result == {'FINISHED'} and reports[0][0] == 'INFO', reports
    set_mode(obj, 'OBJECT')
    seams = _seams(obj.data)
    _check_certified(obj)
    assert not (_discontinuous_edges(obj.data) & ~seams).any()
    assert last().failed == 0 and last().put_back == 0 and last().islands > 1


def test_seams_follow_a_material_boundary(addon, capsys):
    """Two materials meeting along a meridian of a UV sphere: the seams added run along the
    material boundary (all 24 edges, in every session; without materials only 2 of them are
    chosen)."""
    obj = _uv_sphere()
    set_mode(obj, 'OBJECT')
    mesh = obj.data
    for name in ("a", "b"):
        mesh.materials.append(bpy.data.materials.new(name))
    centre = _get(mesh.polygons, "center", np.float32, len(mesh.polygons), 3).reshape(-1, 3)
    side = centre[:, 0] > 0.3
    mesh.polygons.foreach_set("material_index", side.astype(np.int32))
    mesh.update()
    total = _get(mesh.polygons, "loop_total", np.int32, len(mesh.polygons))
    loop_edge = _get(mesh.loops, "edge_index", np.int32, len(mesh.loops))
    loop_side = np.repeat(side, total)
    on = np.zeros((2, len(mesh.edges)), bool)
    on[0, loop_edge[loop_side]] = True
    on[1, loop_edge[~loop_side]] = True
    boundary = on.all(axis=0)
    assert boundary.sum() == 24
    _edit_all(obj)
    result, reports = run(capsys, 'EXEC_DEFAULT', seams='AUTO', bound=C, stretch=S)
    assert result == {'FINISHED'} and reports[0][0] == 'INFO', reports
    set_mode(obj, 'OBJECT')
    seams = _seams(mesh)
    print("material boundary edges marked:", int(seams[boundary].sum()))
    assert seams[boundary].sum() >= 20
    _check_certified(obj)
