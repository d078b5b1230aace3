"""The operators' post-write check returns the core's one certificate record (issue 20, item 6):
``bd_uv.Certificate`` with the island's index in the unwrap, the stretch figures and whether
the UVs failed as solved already; every figure recomputed here from the stored UVs."""
from types import SimpleNamespace

import numpy as np

from conftest import load_submodule


def strip(n=4):
    """A flat strip of 2n triangles along x, counter-clockwise."""
    x = np.arange(n + 1, dtype=float)
    V = np.concatenate([np.stack([x, 0 * x, 0 * x], 1), np.stack([x, 1 + 0 * x, 0 * x], 1)])
    a = np.arange(n)
    F = np.concatenate([np.stack([a, a + 1, a + n + 2], 1), np.stack([a, a + n + 2, a + n + 1], 1)])
    return V, F.astype(np.int64)


def svd_distortion(V, F, uv):
    """Per face: conformal distortion sigma_1 / sigma_2 and the signed UV area."""
    e1, e2 = V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]
    x = e1 / np.linalg.norm(e1, axis=1)[:, None]
    n = np.cross(e1, e2)
    y = np.cross(n / np.linalg.norm(n, axis=1)[:, None], x)
    P = np.stack([np.stack([(e1 * x).sum(1), (e1 * y).sum(1)], 1),
                  np.stack([(e2 * x).sum(1), (e2 * y).sum(1)], 1)], 2)      # columns e1, e2
    U = np.stack([uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]], 2)
    J = U @ np.linalg.inv(P)
    s = np.linalg.svd(J, compute_uv=False)
    return s[:, 0] / s[:, 1], np.linalg.det(J)


def test_check_stored_returns_the_core_certificate():
    stored = load_submodule("operators.stored")
    Certificate = load_submodule("bd_uv.certificate").Certificate
    V, F = strip()
    solved = V[F][:, :, :2] * np.array([1.3, 1.0])           # distortion 1.3 on every face
    as_stored = solved.astype(np.float32)
    islands = [SimpleNamespace(bound_certified=2.0, bound_requested=2.0)] * 4
    labels = np.full(len(F), 3)                               # island 3 of the unwrap
    cert, = stored.check_stored(V, F, as_stored, labels, islands, solved_uv=solved,
                                stretch=1.5)
    assert isinstance(cert, Certificate)
    D, det = svd_distortion(V, F, as_stored.astype(np.float64))
    assert cert.island == 3 and cert.certified and cert.reason == ""
    assert cert.flipped == int((det <= 0).sum()) == 0
    assert abs(cert.max_distortion - D.max()) <= 1e-9 * D.max() and D.max() <= cert.bound
    assert cert.faces == len(F) and cert.overlap_free and not cert.failed_as_solved
    # singular values at the island's own scale (UV area = 3D area): 1.3 / sqrt(1.3), 1 / sqrt(1.3)
    assert abs(cert.max_singular - np.sqrt(1.3)) < 1e-6
    assert abs(cert.min_singular - 1 / np.sqrt(1.3)) < 1e-6


def test_failed_as_solved_tells_storage_from_the_solve():
    stored = load_submodule("operators.stored")
    V, F = strip()
    solved = V[F][:, :, :2].copy()
    broken = solved.copy()
    broken[0] = broken[0][[0, 2, 1]]                          # face 0 flipped as stored
    islands = [SimpleNamespace(bound_certified=2.0, bound_requested=2.0)]
    labels = np.zeros(len(F), np.int64)
    by_storage, = stored.check_stored(V, F, broken, labels, islands, solved_uv=solved)
    _, det = svd_distortion(V, F, broken)
    assert not by_storage.certified and by_storage.flipped == int((det <= 0).sum()) == 1
    assert not by_storage.failed_as_solved                    # the solved UVs pass
    already, = stored.check_stored(V, F, broken, labels, islands, solved_uv=broken)
    assert not already.certified and already.failed_as_solved


def test_the_operator_passes_unwrap_options_with_the_cores_defaults(addon, monkeypatch):
    """uv.bd_unwrap's defaults are UnwrapOptions' (one place), and what reaches bd_uv.unwrap is
    an UnwrapOptions made from the operator's settings; the UVs it writes are certified."""
    from conftest import add_grid, bpy, loop_uv_array, set_mode, triangle_distortion
    ops = load_submodule("operators.unwrap")
    core = load_submodule("bd_uv")
    defaults = core.UnwrapOptions()
    props = ops.UV_OT_bd_unwrap.__annotations__
    assert props["method"].keywords["default"] == defaults.method
    assert props["bound"].keywords["default"] == defaults.bound
    assert props["frames"].keywords["default"] == defaults.frames
    assert props["raise_bound"].keywords["default"] == defaults.raise_bound
    # The operator starts where every entry point does: options.ENTRY_SEAMS_MODE ("needed").
    assert props["seams"].keywords["default"] == \
        {"needed": 'NEEDED', "auto": 'AUTO', "marked": 'MARKED'}[core.options.ENTRY_SEAMS_MODE]
    seen = []

    def recording(*args, **kwargs):
        seen.append(kwargs["options"])
        return core.unwrap(*args, **kwargs)
    monkeypatch.setattr(ops, "SOLVE", recording)
    obj = add_grid(5, 4)
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', seams='MARKED', bound=2.5, method='arap',
                                raise_bound=False) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    (options,) = seen
    assert isinstance(options, core.UnwrapOptions)
    assert (options.bound, options.method, options.raise_bound, options.seams_mode) == \
        (2.5, "arap", False, "marked")
    mesh = obj.data
    mesh.calc_loop_triangles()
    tris = np.array([t.vertices[:] for t in mesh.loop_triangles])
    loops = np.array([t.loops[:] for t in mesh.loop_triangles])
    V = np.array([v.co[:] for v in mesh.vertices])
    D, det = triangle_distortion(V, tris, loop_uv_array(mesh)[loops])
    assert (det > 0).all() and D.max() <= 2.5 * (1 + 1e-4)
