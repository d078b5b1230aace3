"""The background path of uv.bd_unwrap (invoke + modal), driven by hand.

Headless Blender has no event loop, so timers never fire and a modal operator never gets events.
Here the operator's own ``invoke`` / ``modal`` functions are called with a stand-in for the
operator instance and for the window-manager calls that need a window, and with fake TIMER / ESC
events; the mesh, the solve (``bd_uv.unwrap`` in a worker thread) and the write-back are real.
A gate in front of the real solve decides when it runs, so nothing depends on timing.
"""
import threading
import types

import numpy as np
import pytest

from conftest import add_grid, bpy, load_submodule, loop_uv_array, set_mode, triangle_distortion


class Recorder:
    """Window-manager / workspace stand-in: forwards attributes, records the calls a window
    needs (timers, progress, modal handler, status text)."""

    def __init__(self, real=None):
        self._real = real
        self.calls = []

    def __getattr__(self, name):
        if name in ("event_timer_add", "event_timer_remove", "progress_begin", "progress_update",
                    "progress_end", "modal_handler_add", "status_text_set"):
            return lambda *a, **k: self.calls.append((name, a)) or object()
        return getattr(self._real, name)


class Context:
    def __init__(self):
        self.window_manager = Recorder(bpy.context.window_manager)
        self.workspace = Recorder(bpy.context.workspace)

    def __getattr__(self, name):
        return getattr(bpy.context, name)


def _operator(**props):
    op_cls = load_submodule("operators.unwrap").UV_OT_bd_unwrap
    defaults = {name: op_cls.__annotations__[name].keywords.get("default")
                for name in op_cls.__annotations__}
    defaults.update(props)
    op = types.SimpleNamespace(**defaults)
    op.reports = []
    op.report = lambda level, message: op.reports.append((set(level), message))
    for name in ("_prepare", "_gather", "_stretch_problem", "_failed", "_cancelled", "_finish",
                 "_status", "_end_modal", "modal", "invoke", "execute", "_pack"):
        setattr(op, name, types.MethodType(getattr(op_cls, name), op))
    op.JOB, op.CANCELLED = op_cls.JOB, op_cls.CANCELLED
    return op


def _event(type_, value='NOTHING'):
    return types.SimpleNamespace(type=type_, value=value)


@pytest.fixture
def gated(monkeypatch):
    """The operator's solve, held until ``gate.set()``."""
    unwrap_module = load_submodule("operators.unwrap")
    real = unwrap_module.SOLVE
    gate = threading.Event()

    def solve(*args, **kwargs):
        gate.wait()
        return real(*args, **kwargs)

    monkeypatch.setattr(unwrap_module, "SOLVE", solve)
    # Pretend there is an event loop, or invoke() would fall back to execute().
    # invoke() is BackgroundSolve.invoke: it asks the background module
    monkeypatch.setattr(load_submodule("operators.background"), "has_event_loop",
                        lambda context: True)
    return gate


def _invoke(op, context):
    return op.invoke(context, _event('LEFTMOUSE', 'PRESS'))


def _grid_in_edit_mode():
    obj = add_grid(6, 5)
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    return obj


def test_modal_path_writes_what_execute_writes(addon, gated):
    obj = _grid_in_edit_mode()
    op, context = _operator(bound=2.0), Context()
    assert _invoke(op, context) == {'RUNNING_MODAL'}
    names = [c[0] for c in context.window_manager.calls]
    assert names[:2] == ["event_timer_add", "progress_begin"] and "modal_handler_add" in names
    assert op.modal(context, _event('TIMER')) == {'PASS_THROUGH'}  # still gated
    assert op.modal(context, _event('MOUSEMOVE')) == {'PASS_THROUGH'}
    gated.set()
    op._job.wait()
    assert op.modal(context, _event('TIMER')) == {'FINISHED'}
    assert "progress_end" in [c[0] for c in context.window_manager.calls]
    assert context.workspace.calls[-1] == ("status_text_set", (None,))
    assert op.reports[-1][1].startswith("BD-LSCM: 1 island, max distortion")
    set_mode(obj, 'OBJECT')
    modal_uv = loop_uv_array(obj.data).copy()

    # The synchronous path on the same mesh writes the same UVs.
    set_mode(obj, 'EDIT')
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=2.0) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    assert np.allclose(loop_uv_array(obj.data), modal_uv, atol=1e-6)


def test_escape_cancels_and_leaves_everything_untouched(addon, gated):
    obj = _grid_in_edit_mode()
    set_mode(obj, 'OBJECT')
    before = loop_uv_array(obj.data).tobytes()
    set_mode(obj, 'EDIT')
    op, context = _operator(), Context()
    assert _invoke(op, context) == {'RUNNING_MODAL'}
    assert op.modal(context, _event('ESC', 'PRESS')) == {'CANCELLED'}
    assert op._job.cancelled
    assert "cancelled" in op.reports[-1][1]
    gated.set()  # the solve starts only now, sees the cancel event and stops
    outcome = op._job.wait()
    bd_uv = load_submodule("bd_uv")
    assert isinstance(outcome.error, bd_uv.CancelledError)
    set_mode(obj, 'OBJECT')
    assert loop_uv_array(obj.data).tobytes() == before


def test_mesh_edited_while_solving_is_not_written(addon, gated):
    obj = _grid_in_edit_mode()
    op, context = _operator(), Context()
    assert _invoke(op, context) == {'RUNNING_MODAL'}
    set_mode(obj, 'OBJECT')
    obj.data.vertices[7].co.z += 0.25  # the user edits the mesh meanwhile
    before = loop_uv_array(obj.data).tobytes()
    set_mode(obj, 'EDIT')
    gated.set()
    op._job.wait()
    assert op.modal(context, _event('TIMER')) == {'CANCELLED'}
    assert "Grid not written: changed while solving" in op.reports[-1][1]
    assert op.reports[-1][0] == {'ERROR'}
    set_mode(obj, 'OBJECT')
    assert loop_uv_array(obj.data).tobytes() == before


def test_invoke_without_event_loop_solves_synchronously(addon):
    """In background mode INVOKE_DEFAULT (what the menu uses) must not start a modal job that
    would never be polled: it solves at once."""
    obj = _grid_in_edit_mode()
    assert bpy.ops.uv.bd_unwrap('INVOKE_DEFAULT', bound=2.0) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    mesh = obj.data
    mesh.calc_loop_triangles()
    tris = np.array([t.vertices[:] for t in mesh.loop_triangles])
    loops = np.array([t.loops[:] for t in mesh.loop_triangles])
    V = np.array([v.co[:] for v in mesh.vertices])
    D, det = triangle_distortion(V, tris, loop_uv_array(mesh)[loops])
    assert (det > 0).all() and D.max() <= 2.0 * (1 + 1e-4)
