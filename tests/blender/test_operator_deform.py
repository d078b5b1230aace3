"""uv.bd_deform: pinned UVs moved by the artist are met exactly and the rest of the island follows
within C with no flip, where a plain harmonic re-solve of the same moved pins folds. Numbers are
recomputed here: each face's map against the rest shape by an SVD, handles bit for bit."""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from conftest import bpy, loop_uv_array, select_polygons, set_mode

N = 8            # quads per side of the plate
TURN = np.pi / 3  # the hole's pins are turned by this and shifted


def _plate_with_hole():
    """A flat N x N plate with a 2 x 2 hole in the middle, UVs its planar projection, the UVs
    of the outer boundary and of the hole's rim pinned. Object Mode, all faces selected.

    Returns obj, loop_vert (L,), rim (L,) bool, outer (L,) bool."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=N, y_subdivisions=N, size=2.0)
    obj = bpy.context.active_object
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='DESELECT')
    set_mode(obj, 'OBJECT')
    mesh = obj.data
    centre = np.array([p.center[:2] for p in mesh.polygons])
    hole = (np.abs(centre) < 2.0 / N).all(axis=1)
    assert hole.sum() == 4
    mesh.polygons.foreach_set("select", hole)
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.delete(type='FACE')
    bpy.ops.mesh.select_all(action='SELECT')
    set_mode(obj, 'OBJECT')
    mesh = obj.data
    co = np.array([v.co[:] for v in mesh.vertices])
    loop_vert = np.array([lp.vertex_index for lp in mesh.loops])
    uv = (co[loop_vert, :2] + 1.0) / 2.0
    mesh.uv_layers.active.uv.foreach_set("vector", uv.astype(np.float32).ravel())
    rim = (np.abs(co[loop_vert, :2]).max(axis=1) < 2.0 / N + 1e-6)
    outer = (np.abs(co[loop_vert, :2]).max(axis=1) > 1.0 - 1e-6)
    layer = mesh.uv_layers.active
    layer.pin_ensure()
    layer.pin.foreach_set("value", rim | outer)
    mesh.update()
    return obj, loop_vert, rim, outer


def _turn_rim(obj, rim):
    """Turn the hole's pinned UVs by TURN about the centre and shift them (as G, R would)."""
    uv = loop_uv_array(obj.data).astype(np.float64)
    c, s = np.cos(TURN), np.sin(TURN)
    p = uv[rim] - 0.5
    uv[rim] = np.stack([c * p[:, 0] - s * p[:, 1], s * p[:, 0] + c * p[:, 1]], 1) + [0.58, 0.5]
    obj.data.uv_layers.active.uv.foreach_set("vector", uv.astype(np.float32).ravel())
    obj.data.update()
    return loop_uv_array(obj.data).copy()


def _triangles(obj):
    mesh = obj.data
    mesh.calc_loop_triangles()
    return (np.array([t.vertices[:] for t in mesh.loop_triangles]),
            np.array([t.loops[:] for t in mesh.loop_triangles]))


def _maps(rest, uv):
    """Singular values (k,2) and determinant (k,) of each triangle's affine map rest -> uv,
    from numpy's SVD of the 2x2 Jacobian; ``rest``, ``uv``: (k,3,2)."""
    X = np.stack([rest[:, 1] - rest[:, 0], rest[:, 2] - rest[:, 0]], axis=2)
    U = np.stack([uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]], axis=2)
    J = U @ np.linalg.inv(X)
    return np.linalg.svd(J, compute_uv=False), np.linalg.det(J)


def _harmonic(rest_v, tris, fixed, targets):
    """The plain harmonic re-solve: cotangent Laplacian of the rest shape, ``fixed`` vertices at
    ``targets``, the others where the Laplacian puts them."""
    n = len(rest_v)
    rows, cols, vals = [], [], []
    for k in range(3):
        i, j, o = tris[:, k], tris[:, (k + 1) % 3], tris[:, (k + 2) % 3]
        u, v = rest_v[i] - rest_v[o], rest_v[j] - rest_v[o]
        cot = (u * v).sum(1) / np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
        rows += [i, j, i, j]
        cols += [j, i, i, j]
        vals += [-cot / 2, -cot / 2, cot / 2, cot / 2]
    L = sp.coo_array((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                     shape=(n, n)).tocsc()
    free = np.setdiff1d(np.arange(n), fixed)
    out = np.zeros((n, 2))
    out[fixed] = targets
    out[free] = spla.spsolve(L[free][:, free].tocsc(), -(L[free][:, fixed] @ targets))
    return out


def test_moved_pins_are_met_and_the_plate_follows_without_a_flip(addon):
    obj, loop_vert, rim, outer = _plate_with_hole()
    rest_loops = loop_uv_array(obj.data).astype(np.float64)  # the layout before the move
    moved = _turn_rim(obj, rim)
    tris, loops = _triangles(obj)
    # The plain harmonic re-solve of the same moved pins folds.
    pinned_v = np.unique(loop_vert[rim | outer])
    rest_v = np.zeros((len(obj.data.vertices), 2))
    rest_v[loop_vert] = rest_loops
    target_v = np.zeros_like(rest_v)
    target_v[loop_vert] = moved
    plain = _harmonic(rest_v, tris, pinned_v, target_v[pinned_v])
    _, det = _maps(rest_v[tris], plain[tris])
    assert (det <= 0).sum() > 0
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    assert bpy.ops.uv.bd_deform('EXEC_DEFAULT', bound=5.0) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    after = loop_uv_array(obj.data)
    pins = rim | outer
    assert np.array_equal(after[pins], moved[pins])  # handles bit for bit
    assert not np.array_equal(after[~pins], moved[~pins])
    s, det = _maps(rest_loops[loops], after[loops].astype(np.float64))
    assert (det > 0).all()
    assert (s[:, 0] / s[:, 1]).max() <= 5.0 * (1 + 1e-5)
    report = bpy.context.window_manager.bd_uv_last_result.report
    assert report.startswith("BD-ARAP deform: 1 island, max distortion ") and "0 flipped" in report


def test_every_method_certifies(addon):
    obj, _, rim, _ = _plate_with_hole()
    rest_loops = loop_uv_array(obj.data).astype(np.float64)
    moved = _turn_rim(obj, rim)
    tris, loops = _triangles(obj)
    for method in ('lscm', 'dirichlet', 'biharmonic'):
        # Each from the same moved pins (a second run starts from the first's layout).
        obj.data.uv_layers.active.uv.foreach_set("vector", moved.ravel())
        set_mode(obj, 'EDIT')
        assert bpy.ops.uv.bd_deform('EXEC_DEFAULT', method=method, bound=5.0) == {'FINISHED'}
        set_mode(obj, 'OBJECT')
        s, det = _maps(rest_loops[loops], loop_uv_array(obj.data)[loops].astype(np.float64))
        assert (det > 0).all() and (s[:, 0] / s[:, 1]).max() <= 5.0 * (1 + 1e-5), method


def test_refused_islands_keep_their_uvs(addon):
    obj, _, rim, outer = _plate_with_hole()
    mesh = obj.data
    # No pins: refused, said so, nothing written.
    mesh.uv_layers.active.pin.foreach_set("value", np.zeros(len(mesh.loops), bool))
    before = loop_uv_array(mesh).tobytes()
    set_mode(obj, 'EDIT')
    assert bpy.ops.uv.bd_deform('EXEC_DEFAULT') == {'CANCELLED'}
    report = bpy.context.window_manager.bd_uv_last_result.report
    assert "island 0 of Grid (60 faces) left as it was: no pinned UVs; pin at least two" in report
    set_mode(obj, 'OBJECT')
    assert loop_uv_array(mesh).tobytes() == before
    # A flipped layout (one unpinned UV thrown across the plate): refused, faces named.
    mesh.uv_layers.active.pin_ensure()  # Edit Mode dropped the all-False pin layer
    mesh.uv_layers.active.pin.foreach_set("value", rim | outer)
    uv = loop_uv_array(mesh)
    loop_vert = np.array([lp.vertex_index for lp in mesh.loops])
    inner = np.flatnonzero(~(rim | outer))
    uv[loop_vert == loop_vert[inner[0]]] = (0.95, 0.95)
    mesh.uv_layers.active.uv.foreach_set("vector", uv.ravel())
    mesh.update()
    before = loop_uv_array(mesh).tobytes()
    set_mode(obj, 'EDIT')
    assert bpy.ops.uv.bd_deform('EXEC_DEFAULT') == {'CANCELLED'}
    report = bpy.context.window_manager.bd_uv_last_result.report
    assert "3 flipped or zero-area faces (faces " in report
    # Too small a bound for the move: refused by the core, nothing written.
    set_mode(obj, 'OBJECT')
    assert loop_uv_array(mesh).tobytes() == before


def test_infeasible_bound_leaves_uvs_and_undo_restores(addon):
    obj, _, rim, _ = _plate_with_hole()
    moved = _turn_rim(obj, rim)
    set_mode(obj, 'EDIT')
    assert bpy.ops.uv.bd_deform('EXEC_DEFAULT', bound=1.05) == {'CANCELLED'}
    assert "left as it was: no deformation within C = 1.05" in \
        bpy.context.window_manager.bd_uv_last_result.report
    set_mode(obj, 'OBJECT')
    assert np.array_equal(loop_uv_array(obj.data), moved)
    set_mode(obj, 'EDIT')
    bpy.ops.ed.undo_push(message="before bd_deform")
    assert bpy.ops.uv.bd_deform('EXEC_DEFAULT', True) == {'FINISHED'}
    bpy.ops.ed.undo()
    set_mode(bpy.context.edit_object or obj, 'OBJECT')
    obj = bpy.data.objects[obj.name]
    assert np.array_equal(loop_uv_array(obj.data), moved)


def test_background_job_solves_and_cancels(addon):
    """The modal path's worker (no event loop here): the same solve, and Esc's cancel."""
    from conftest import load_submodule
    worker = load_submodule("operators.worker")
    uv_deform = load_submodule("operators.uv_deform")
    bd_uv = load_submodule("bd_uv")
    V = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0]], float)
    F = np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]])
    uv = V[F][:, :, :2].copy()
    uv[F == 2] = (2.0, 0.3)  # the right end pinned and moved up
    pins = np.flatnonzero(np.isin(F.ravel(), [0, 3, 2, 5]))
    done = worker.UnwrapJob(uv_deform.deform_islands, V, F, uv, pins, bound=4.0).start().wait()
    assert isinstance(done, worker.Finished)
    res = done.result
    assert [r.status for r in res.islands] == ["certified"]
    assert np.array_equal(res.corner_uv.reshape(-1, 2)[pins], uv.reshape(-1, 2)[pins])
    job = worker.UnwrapJob(uv_deform.deform_islands, V, F, uv, pins, bound=4.0)
    job.cancel()
    failed = job.start().wait()
    assert isinstance(failed, worker.Failed)
    assert isinstance(failed.error, bd_uv.CancelledError)


def test_uvs_shared_with_unselected_faces_are_held(addon):
    obj, loop_vert, rim, _ = _plate_with_hole()
    mesh = obj.data
    before = _turn_rim(obj, rim)
    centre = np.array([p.center[:2] for p in mesh.polygons])
    keep = (centre[:, 0] > 0.5) & (centre[:, 1] > 0.5)  # a corner of the plate stays unselected
    select_polygons(obj, ~keep)
    set_mode(obj, 'EDIT')
    assert bpy.ops.uv.bd_deform('EXEC_DEFAULT') == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    after = loop_uv_array(mesh)
    poly_of_loop = np.repeat(np.arange(len(mesh.polygons)),
                             [p.loop_total for p in mesh.polygons])
    unselected = keep[poly_of_loop]
    assert np.array_equal(after[unselected], before[unselected])
    assert not np.array_equal(after[~unselected], before[~unselected])
    # No tear: every vertex's loops still share one UV.
    for v in np.unique(loop_vert[unselected]):
        assert len(np.unique(after[loop_vert == v], axis=0)) == 1


def test_an_island_failing_the_post_write_check_is_put_back(addon, monkeypatch):
    """The stored UVs are certified again (here: a certificate that always fails); the island
    gets the UVs it had before the operator, bit for bit."""
    import dataclasses
    from conftest import load_submodule
    bd_uv = load_submodule("bd_uv")
    real = bd_uv.certify_islands

    def failing(*args, **kwargs):
        return [dataclasses.replace(c, certified=False, reason="made to fail")
                for c in real(*args, **kwargs)]

    monkeypatch.setattr(bd_uv, "certify_islands", failing)
    obj, _, rim, _ = _plate_with_hole()
    moved = _turn_rim(obj, rim)
    set_mode(obj, 'EDIT')
    assert bpy.ops.uv.bd_deform('EXEC_DEFAULT') == {'CANCELLED'}
    report = bpy.context.window_manager.bd_uv_last_result.report
    assert "island 0 of Grid (60 faces) put back as it was" in report and "made to fail" in report
    set_mode(obj, 'OBJECT')
    assert np.array_equal(loop_uv_array(obj.data), moved)


def test_a_deformation_that_would_overlap_is_refused_and_the_island_left_as_it_was(addon):
    """A U whose left arm's tip is pulled past the right one's: BD-Biharmonic's direct solve
    lays the arms over each other and cannot be mended (``bd_uv.deform``): the island keeps its
    UVs bit for bit and the report says why."""
    import triangle
    outline = np.array([(0, 0), (3, 0), (3, 2), (2, 2), (2, 0.5), (1, 0.5), (1, 2), (0, 2)],
                       float)
    seg = np.stack([np.arange(8), (np.arange(8) + 1) % 8], 1)
    T = triangle.triangulate(dict(vertices=outline, segments=seg), "pq30a0.01")
    V2, F = T["vertices"], T["triangles"]
    mesh = bpy.data.meshes.new("U")
    mesh.from_pydata(np.column_stack([V2, np.zeros(len(V2))]).tolist(), [], F.tolist())
    mesh.update()
    obj = bpy.data.objects.new("U", mesh)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    layer = mesh.uv_layers.new(name="UVMap")
    loop_vert = np.array([lp.vertex_index for lp in mesh.loops])
    uv = V2[loop_vert] / 3.0
    tips = [int(np.argmin(np.linalg.norm(V2 - p, axis=1))) for p in ([0.5, 2.0], [2.5, 2.0])]
    uv[loop_vert == tips[0]] = (3.0 / 3.0, 2.0 / 3.0)
    layer.uv.foreach_set("vector", uv.astype(np.float32).ravel())
    layer.pin_ensure()
    layer.pin.foreach_set("value", np.isin(loop_vert, tips))
    mesh.polygons.foreach_set("select", np.ones(len(mesh.polygons), bool))
    mesh.update()
    before = loop_uv_array(mesh).tobytes()
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    assert bpy.ops.uv.bd_deform('EXEC_DEFAULT', method='biharmonic') == {'CANCELLED'}
    report = bpy.context.window_manager.bd_uv_last_result.report
    assert "left as it was: the deformation would lay the island over itself" in report
    set_mode(obj, 'OBJECT')
    assert loop_uv_array(mesh).tobytes() == before
