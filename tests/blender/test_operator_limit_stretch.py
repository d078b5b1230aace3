"""uv.bd_unwrap with Seams "Marked" and Limit Stretch: singular values within [1/S, S] of every
written face, recomputed from the stored UVs by an SVD of each face's map; S < sqrt(C) and the
options Limit Stretch cannot take are refused with the UVs untouched."""
import re

import numpy as np
import pytest

from conftest import bpy, loop_uv_array, set_mode

SLACK = 1e-5


def _dome(n=8):
    """A grid bent into a steep dome: its conformal map stretches the rim against the centre."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=n, y_subdivisions=n, size=2.0)
    obj = bpy.context.active_object
    set_mode(obj, 'OBJECT')
    co = np.empty(len(obj.data.vertices) * 3, np.float32)
    obj.data.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    co[:, 2] = 1.2 * np.exp(-2.0 * (co[:, 0] ** 2 + co[:, 1] ** 2))
    obj.data.vertices.foreach_set("co", co.ravel())
    obj.data.update()
    return obj


def _singular_values(obj):
    """(m,2) singular values of each triangle's map from the stored UVs, the UVs scaled so their
    area equals the 3D area (one island), by numpy's SVD of the 2x2 Jacobian."""
    mesh = obj.data
    mesh.calc_loop_triangles()
    tris = np.array([t.vertices[:] for t in mesh.loop_triangles])
    loops = np.array([t.loops[:] for t in mesh.loop_triangles])
    P = np.array([v.co[:] for v in mesh.vertices], np.float64)[tris]
    uv = loop_uv_array(mesh)[loops].astype(np.float64)
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    x = e1 / np.linalg.norm(e1, axis=1)[:, None]
    nrm = np.cross(e1, e2)
    y = np.cross(nrm / np.linalg.norm(nrm, axis=1)[:, None], x)
    X = np.stack([np.stack([(e1 * x).sum(1), (e1 * y).sum(1)], 1),
                  np.stack([(e2 * x).sum(1), (e2 * y).sum(1)], 1)], axis=2)
    U = np.stack([uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]], axis=2)
    J = U @ np.linalg.inv(X)
    assert (np.linalg.det(J) > 0).all()
    area3d = 0.5 * np.linalg.norm(nrm, axis=1).sum()
    area_uv = 0.5 * np.abs(np.linalg.det(U)).sum()
    return np.linalg.svd(J, compute_uv=False) * np.sqrt(area3d / area_uv)


def _edit_all(obj):
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')


def test_limit_stretch_with_marked_seams(addon):
    obj = _dome()
    _edit_all(obj)
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=2.0) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    free = _singular_values(obj)
    assert free.max() > 1.6 or free.min() < 1 / 1.6  # the plain map breaks the limit below
    _edit_all(obj)
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=2.0, limit_stretch=True,
                                stretch=1.6) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    s = _singular_values(obj)
    assert s.max() <= 1.6 * (1 + SLACK) and s.min() >= (1 - SLACK) / 1.6
    assert (s[:, 0] / s[:, 1]).max() <= 2.0 * (1 + SLACK)
    report = bpy.context.window_manager.bd_uv_last_result.report
    m = re.search(r"singular values ([\d.]+) to ([\d.]+) within \[0\.625, 1\.6\]", report)
    assert m, report
    # The figures shown bracket the ones measured here (shown rounded outwards).
    assert float(m.group(1)) <= s.min() * (1 + 1e-4) and float(m.group(2)) >= s.max() * (1 - 1e-4)


def test_stretch_below_sqrt_c_is_refused_and_nothing_changes(addon):
    obj = _dome(5)
    set_mode(obj, 'OBJECT')
    before = loop_uv_array(obj.data).tobytes()
    _edit_all(obj)
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=4.0, limit_stretch=True,
                                stretch=1.5) == {'CANCELLED'}
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=2.0, limit_stretch=True, stretch=2.0,
                                minimise=True, boundary='circle') == {'CANCELLED'}
    set_mode(obj, 'OBJECT')
    assert loop_uv_array(obj.data).tobytes() == before


@pytest.mark.parametrize("S, options", [(1.9, dict(method='arap')),
                                        (1.9, dict(method='stretch-l1')),
                                        (3.0, dict(method='dirichlet', boundary='rectangle')),
                                        (3.0, dict(method='biharmonic', boundary='rectangle')),
                                        (1.9, dict(minimise=True))])
def test_limit_stretch_with_every_method_and_boundary(addon, S, options):
    obj = _dome(6)
    _edit_all(obj)
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=3.0, limit_stretch=True, stretch=S,
                                **options) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    s = _singular_values(obj)
    assert s.max() <= S * (1 + SLACK) and s.min() >= (1 - SLACK) / S
    assert (s[:, 0] / s[:, 1]).max() <= 3.0 * (1 + SLACK)
    assert f"within [{1 / S:.4g}, {S:g}]" in bpy.context.window_manager.bd_uv_last_result.report


def test_stretch_message_names_sqrt_c(addon):
    addon_ops = __import__("bd_uv_addon.operators.unwrap", fromlist=["UV_OT_bd_unwrap"])
    op = type("Options", (), dict(seams='MARKED', method='lscm', minimise=False, boundary='free',
                                  stretch=1.5, bound=4.0))()
    text = addon_ops.UV_OT_bd_unwrap._stretch_problem(op)
    assert "sqrt(C) = 2" in text and "1.5" in text
    op.stretch = 2.0
    assert addon_ops.UV_OT_bd_unwrap._stretch_problem(op) == ""


def test_post_write_check_puts_back_an_island_beyond_the_stretch_limit():
    from conftest import load_submodule
    stored = load_submodule("operators.stored")
    from types import SimpleNamespace
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    F = np.array([[0, 1, 2], [0, 2, 3]])
    uv = V[F][:, :, :2] * np.array([1.5, 1.0])  # singular values 1.5, 1 -> 1.22, 0.82 at scale
    island = SimpleNamespace(bound_certified=2.0, bound_requested=2.0)
    ok, = stored.check_stored(V, F, uv, np.zeros(2, int), [island], stretch=1.3)
    assert ok.certified and abs(ok.max_singular - 1.5 / np.sqrt(1.5)) < 1e-12
    assert abs(ok.min_singular - 1 / np.sqrt(1.5)) < 1e-12
    bad, = stored.check_stored(V, F, uv, np.zeros(2, int), [island], stretch=1.2)
    assert not bad.certified and "singular values" in bad.reason
    # Pinned islands (normalized False) are measured against the 3D geometry itself.
    raw, = stored.check_stored(V, F, uv, np.zeros(2, int), [island], stretch=1.3,
                               normalized=[False])
    assert not raw.certified and abs(raw.max_singular - 1.5) < 1e-12
