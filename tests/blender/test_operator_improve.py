"""mesh.bd_improve: a flat triangle selection's interior vertices move within the plane so the
worst triangle is closer to equilateral; boundary vertices bit for bit, no face turned over.
Distortion against the equilateral is recomputed here by an SVD of each face's map."""
import re

import numpy as np

from conftest import bpy, set_mode

EQ = np.array([[1.0, 0.5], [0.0, np.sqrt(3) / 2]])  # equilateral edges (columns), side 1


def _jittered_plate(n=6, seed=3):
    """A flat n x n grid, triangulated, its interior vertices jittered in the plane (bad
    triangles). Object Mode, everything selected."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=n, y_subdivisions=n, size=2.0)
    obj = bpy.context.active_object
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    bpy.ops.mesh.quads_convert_to_tris()
    set_mode(obj, 'OBJECT')
    co = _co(obj)
    interior = np.abs(co[:, :2]).max(axis=1) < 1 - 1e-6
    rng = np.random.default_rng(seed)
    co[interior, :2] += rng.uniform(-0.45, 0.45, (interior.sum(), 2)) * (2.0 / n)
    obj.data.vertices.foreach_set("co", co.ravel())
    obj.data.update()
    return obj, interior


def _co(obj):
    co = np.empty(len(obj.data.vertices) * 3, np.float32)
    obj.data.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


def _distortion(obj):
    """(m,) distortion of each triangle against the equilateral, (m,) the z of its normal."""
    mesh = obj.data
    P = _co(obj).astype(np.float64)
    T = np.array([p.vertices[:] for p in mesh.polygons])
    X = P[T][:, :, :2]
    M = np.stack([X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]], axis=2) @ np.linalg.inv(EQ)
    s = np.linalg.svd(M, compute_uv=False)
    return s[:, 0] / s[:, 1], np.linalg.det(M)


def _edit_all(obj):
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')


def test_improves_a_flat_plate(addon):
    obj, interior = _jittered_plate()
    before = _co(obj).copy()
    D0, det0 = _distortion(obj)
    assert (det0 > 0).all()
    _edit_all(obj)
    assert bpy.ops.mesh.bd_improve('EXEC_DEFAULT') == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    after = _co(obj)
    assert np.array_equal(after[~interior], before[~interior])  # boundary bit for bit
    assert not np.array_equal(after[interior], before[interior])
    assert np.abs(after[:, 2]).max() == 0.0  # still in the plane z = 0
    D1, det1 = _distortion(obj)
    assert (det1 > 0).all()  # nothing turned over
    assert D1.max() <= 0.8 * D0.max()  # at least 20% closer to equilateral
    report = bpy.context.window_manager.bd_uv_last_result.report
    m = re.search(r"max distortion against the equilateral ([\d.]+) \u2192 ([\d.]+)", report)
    assert m, report
    assert abs(float(m.group(1)) - D0.max()) <= 1e-3 * D0.max()
    assert abs(float(m.group(2)) - D1.max()) <= 1e-3 * D1.max()


def test_refuses_what_it_cannot_do_and_leaves_the_mesh(addon):
    obj, interior = _jittered_plate()
    co = _co(obj)
    co[np.flatnonzero(interior)[0], 2] = 0.05  # one vertex off the plane
    obj.data.vertices.foreach_set("co", co.ravel())
    obj.data.update()
    _edit_all(obj)
    assert bpy.ops.mesh.bd_improve('EXEC_DEFAULT') == {'CANCELLED'}
    assert "not flat" in bpy.context.window_manager.bd_uv_last_result.report
    set_mode(obj, 'OBJECT')
    assert np.array_equal(_co(obj), co)
    # Quads are refused (triangulate first).
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=4, y_subdivisions=4, size=2.0)
    quads = bpy.context.active_object
    before = _co(quads).copy()
    _edit_all(quads)
    assert bpy.ops.mesh.bd_improve('EXEC_DEFAULT') == {'CANCELLED'}
    set_mode(quads, 'OBJECT')
    assert np.array_equal(_co(quads), before)


def test_undo_restores_the_positions(addon):
    obj, _ = _jittered_plate()
    before = _co(obj).copy()
    _edit_all(obj)
    bpy.ops.ed.undo_push(message="before bd_improve")
    assert bpy.ops.mesh.bd_improve('EXEC_DEFAULT', True) == {'FINISHED'}
    bpy.ops.ed.undo()
    set_mode(bpy.data.objects[obj.name], 'OBJECT')
    assert np.array_equal(_co(bpy.data.objects[obj.name]), before)


def test_background_job_solves_refuses_and_cancels(addon):
    """The modal path's worker (no event loop here): the same solve, and Esc's cancel."""
    from conftest import load_submodule
    worker = load_submodule("operators.worker")
    planar = load_submodule("operators.planar")
    bd_uv = load_submodule("bd_uv")
    t = np.linspace(0, 2 * np.pi, 9)[:-1]
    ring = np.column_stack([np.cos(t), np.sin(t), np.zeros(8)])
    P = np.vstack([ring, [[0.5, 0.2, 0.0]]])  # a bad centre vertex
    F = np.column_stack([np.arange(8), (np.arange(8) + 1) % 8, np.full(8, 8)])
    tilted = P @ np.array([[1, 0, 0], [0, 0.6, 0.8], [0, -0.8, 0.6]])  # any plane will do
    bent = P.copy()
    bent[8, 2] = 0.3
    done = worker.UnwrapJob(planar.improve_many, [(tilted, F), (bent, F)]).start().wait()
    assert isinstance(done, worker.Finished)
    good, refused = done.result
    assert isinstance(refused, planar.NotFlatError)
    assert list(good.interior) == [8]
    assert good.result.max_after < good.result.max_before
    # The new centre is on the plane and the faces still turn one way.
    n = np.cross(tilted[1] - tilted[0], tilted[2] - tilted[0])
    assert abs((good.positions[0] - tilted[0]) @ n) <= 1e-12 * np.linalg.norm(n)
    job = worker.UnwrapJob(planar.improve_many, [(tilted, F)])
    job.cancel()
    failed = job.start().wait()
    assert isinstance(failed, worker.Failed) and isinstance(failed.error, bd_uv.CancelledError)


def test_a_boundary_only_face_holding_the_max_is_named(addon):
    """A flat ear (all three corners on the boundary) cannot change: the report gives the faces
    with an interior vertex apart, as the command line does."""
    t = np.arange(6) * np.pi / 3
    P = np.column_stack([np.cos(t), np.sin(t), np.zeros(6)])
    ear = 0.5 * (P[0] + P[1]) * 1.05  # just outside the edge 0-1: a flat triangle
    P = np.vstack([P, [[0.3, -0.2, 0.0]], ear])  # 6: an off-centre interior vertex, 7: the ear
    F = [[6, i, (i + 1) % 6] for i in range(6)] + [[0, 7, 1]]
    mesh = bpy.data.meshes.new("ear")
    mesh.from_pydata(P.tolist(), [], F)
    obj = bpy.data.objects.new("ear", mesh)
    bpy.context.scene.collection.objects.link(obj)
    D0, det0 = _distortion(obj)
    if (det0 < 0).any():  # the ear's corner order: counter-clockwise like the rest
        mesh.polygons[6].flip()
        D0, det0 = _distortion(obj)
    assert (det0 > 0).all() and D0.argmax() == 6
    _edit_all(obj)
    assert bpy.ops.mesh.bd_improve('EXEC_DEFAULT') == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    D1, det1 = _distortion(obj)
    report = bpy.context.window_manager.bd_uv_last_result.report
    assert (det1 > 0).all() and D1[6] == D0[6] and D1[:6].max() < D0[:6].max()
    assert "faces with an interior vertex" in report and "all corners on the boundary" in report
