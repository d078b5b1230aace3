"""uv.bd_live's step logic (event -> target -> frame -> written UVs), called directly: headless
Blender has no event loop. Every written frame is checked here from the stored UVs (an SVD per
triangle against the layout the drag started from, signed areas, the separating-axis test on
every pair of triangles); Esc puts every UV back bit for bit."""
import pathlib
import sys

import numpy as np

from conftest import bpy, load_submodule, set_mode, triangle_distortion

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "core"))
from planar import overlapping_pairs  # noqa: E402

BOUND = 4.0


def _grid_with_two_pins():
    """A flat 10 x 10 grid with its own planar UVs; every UV of two vertices pinned, the right
    one selected (sync selection). Edit Mode. Returns obj, the two vertices (left, right)."""
    import bmesh
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=10, y_subdivisions=10, size=2.0)
    obj = bpy.context.active_object
    bpy.context.scene.tool_settings.use_uv_select_sync = True
    set_mode(obj, 'EDIT')
    bm = bmesh.from_edit_mesh(obj.data)
    bm.verts.ensure_lookup_table()
    co = np.array([v.co[:2] for v in bm.verts])
    a = int(np.argmin(np.linalg.norm(co - [-0.6, 0.0], axis=1)))
    b = int(np.argmin(np.linalg.norm(co - [0.6, 0.0], axis=1)))
    layer = bm.loops.layers.uv.active
    for f in bm.faces:                      # (deselecting a face deselects its vertices)
        f.select = False
    for v in bm.verts:
        v.select = v.index == b
        for lp in v.link_loops:
            lp[layer].pin_uv = v.index in (a, b)
    bmesh.update_edit_mesh(obj.data)
    return obj, a, b


def _stored(obj):
    """Every loop's UV as stored (float32) and its vertex, from the edit mesh."""
    import bmesh
    bm = bmesh.from_edit_mesh(obj.data)
    layer = bm.loops.layers.uv.active
    loops = [lp for f in bm.faces for lp in f.loops]
    return (np.array([lp[layer].uv[:] for lp in loops], dtype=np.float32),
            np.array([lp.vert.index for lp in loops]))


def _check_frame(drag, rest_corner):
    """The island's stored UVs: 0 flips, distortion <= C against the start, no overlap."""
    stored = np.array([[lp[drag.data.layer].uv[:] for lp in drag.data.tri_loops[f]]
                       for f in drag.island.faces.tolist()], dtype=np.float32).astype(float)
    V = np.column_stack([rest_corner.reshape(-1, 2), np.zeros(rest_corner.size // 2)])
    D, det = triangle_distortion(V, np.arange(len(V)).reshape(-1, 3), stored)
    assert np.all(det > 0)
    assert D.max() <= BOUND
    X = stored.reshape(-1, 2)
    assert overlapping_pairs(X, np.arange(len(X)).reshape(-1, 3)) == 0


def test_drag_writes_certified_frames_axis_and_snap_and_esc_restores_bit_for_bit(addon):
    live = load_submodule("operators.live")
    obj, a, b = _grid_with_two_pins()
    before, loop_vert = _stored(obj)
    drag = live.LiveDrag(bpy.context, bound=BOUND, background=False)
    rest_corner = drag.island.rest_corner_uv
    start = before[loop_vert == b][0].astype(float)
    fixed = before[loop_vert == a][0]
    assert live.handle_event(drag, 'MOUSEMOVE', 'NOTHING', np.zeros(2)) == "RUNNING"
    for step in range(1, 7):                          # the right pin pulled out and up
        mouse = np.array([0.04 * step, 0.03 * step])
        assert live.handle_event(drag, 'MOUSEMOVE', 'NOTHING', mouse) == "RUNNING"
        uv, lv = _stored(obj)
        assert np.all(uv[lv == b] == np.float32(start + mouse))      # the grabbed pin
        assert np.all(uv[lv == a] == fixed)                          # the other pin stays
        assert drag.frame.certified and drag.frame.pin_error == 0
        _check_frame(drag, rest_corner)
    # X: only u moves; Ctrl: the move snapped to 1/64.
    live.handle_event(drag, 'X', 'PRESS', np.array([0.1, 0.2]))
    uv, lv = _stored(obj)
    assert np.all(uv[lv == b] == np.float32(start + [0.1, 0.0]))
    live.handle_event(drag, 'MOUSEMOVE', 'NOTHING', np.array([0.101, 0.2]), ctrl=True)
    uv, lv = _stored(obj)
    assert np.all(uv[lv == b] == np.float32(start + [round(0.101 * 64) / 64, 0.0]))
    _check_frame(drag, rest_corner)
    assert "C 4" in drag.header() and "pin error 0" in drag.header()
    assert live.handle_event(drag, 'ESC', 'PRESS', np.zeros(2)) == "CANCEL"
    drag.cancel()
    after, _ = _stored(obj)
    assert after.tobytes() == before.tobytes()


def test_the_background_worker_shows_the_newest_frame_and_confirm_keeps_it(addon):
    live = load_submodule("operators.live")
    obj, a, b = _grid_with_two_pins()
    before, loop_vert = _stored(obj)
    drag = live.LiveDrag(bpy.context, bound=BOUND)
    rest_corner = drag.island.rest_corner_uv
    start = before[loop_vert == b][0].astype(float)
    live.handle_event(drag, 'MOUSEMOVE', 'NOTHING', np.zeros(2))
    for step in range(1, 11):                          # faster than frames are solved
        live.handle_event(drag, 'MOUSEMOVE', 'NOTHING', np.array([0.03 * step, -0.02 * step]))
    seq = drag.seq
    assert seq == 10
    ok, message = drag.confirm()
    assert ok, message
    uv, lv = _stored(obj)
    assert np.all(uv[lv == b] == np.float32(start + [0.3, -0.2]))
    _check_frame(drag, rest_corner)
    assert "0 flipped, no overlap" in message


def test_execute_drags_to_the_offset_and_refuses_without_a_selected_pin(addon):
    obj, a, b = _grid_with_two_pins()
    before, loop_vert = _stored(obj)
    assert bpy.ops.uv.bd_live('EXEC_DEFAULT', offset=(0.2, 0.1), bound=BOUND) == {'FINISHED'}
    uv, lv = _stored(obj)
    assert np.all(uv[lv == b] == np.float32(before[loop_vert == b][0] + [0.2, 0.1]))
    import bmesh
    bm = bmesh.from_edit_mesh(obj.data)
    for v in bm.verts:
        v.select = False
    bmesh.update_edit_mesh(obj.data)
    now, _ = _stored(obj)
    assert bpy.ops.uv.bd_live('EXEC_DEFAULT', offset=(0.2, 0.1)) == {'CANCELLED'}
    assert _stored(obj)[0].tobytes() == now.tobytes()


def test_the_overlay_colours_each_triangle_by_its_distortion(addon):
    overlay = load_submodule("operators.live_overlay")
    corner = np.array([[[0, 0], [1, 0], [0, 1]], [[1, 0], [1, 1], [0, 1]]], float)
    pos, col = overlay.overlay_arrays(corner, np.array([1.0, 4.0]), 4.0)
    assert pos.shape == (6, 2) and np.array_equal(pos, corner.reshape(-1, 2).astype(np.float32))
    assert col.shape == (6, 4) and np.all(col[:, 3] == overlay.ALPHA)
    assert np.all(col[0] == col[1]) and np.all(col[3] == col[5])
    assert not np.allclose(col[0, :3], col[3, :3])       # distortion 1 and C differ in colour


def test_the_worker_drops_targets_superseded_while_a_frame_is_solved(addon):
    """Targets 1 and 2 arrive while target 0 is solved: only 0 and 3 are solved, and a frame
    older than one already taken is never handed out."""
    import threading
    live_edit = load_submodule("operators.live_edit")

    class SlowIsland:
        def __init__(self):
            self.release = threading.Event()
            self.solved = []
            self.session = type("S", (), {"cancel": lambda self: None})()

        def frame_for(self, offset):
            self.release.wait()
            self.solved.append(float(offset[0]))
            return f"frame {offset[0]:g}"

    island = SlowIsland()
    worker = live_edit.LiveWorker(island)
    try:
        assert worker.submit([0.0, 0.0]) == 0
        while not worker._busy_started():
            pass
        for k in (1, 2, 3):
            worker.submit([float(k), 0.0])
        assert worker.dropped == 2
        assert worker.take() is None
        island.release.set()
        assert worker.wait(3, timeout=10) == (3, "frame 3")
        assert island.solved == [0.0, 3.0]
        assert worker.take() is None                  # frame 0 is older than frame 3
    finally:
        island.release.set()
        worker.stop()
