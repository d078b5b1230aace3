"""LiveSession: every frame of a drag certified, checked independently of bd_uv (SVD of each
face's affine map, signed areas, the separating-axis test on every pair of triangles)."""
import numpy as np
import pytest

import bd_uv
from bd_uv.live import LiveSession, SessionClosedError

from planar import circle, mesh_polygon, overlapping_pairs, svd_of_maps

BOUND = 3.0


def _disk():
    return mesh_polygon(circle(40), area=0.006)


def _disk_with_hole():
    return mesh_polygon(circle(40), [circle(14, 0.35)[::-1]], [[0.0, 0.0]], area=0.006)


def _near(V, p):
    return int(np.argmin(np.linalg.norm(V - p, axis=1)))


def _independent_check(rest, frame, F, bound):
    """Flips, distortion and overlaps of a frame recomputed from its coordinates."""
    s, det = svd_of_maps(rest, frame.uv, F)
    assert np.all(det > 0), "flipped face"
    D = s[:, 0] / s[:, 1]
    assert D.max() <= bound
    assert abs(D.max() - frame.max_distortion) <= 1e-9 * D.max()
    assert overlapping_pairs(frame.uv, F) == 0
    assert frame.certified and frame.flipped == 0 and frame.overlaps == 0


def _drag_targets(P0, steps=12):
    """Two pins turned about their midpoint up to 150 degrees and pulled apart to 1.3x, then
    back."""
    mid = P0.mean(axis=0)
    out = []
    for f in np.concatenate([np.linspace(0, 1, steps + 1)[1:], np.linspace(1, 0, steps + 1)[1:]]):
        a = np.deg2rad(150) * f
        R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        out.append(mid + (P0 - mid) @ R.T * (1 + 0.3 * f))
    return out


@pytest.mark.parametrize("mesh", [_disk, _disk_with_hole])
@pytest.mark.parametrize("method", ["arap", "lscm"])
def test_two_pin_drag_gives_only_certified_frames_with_pins_on_target(mesh, method):
    V, F = mesh()
    pins = [_near(V, [-0.7, 0.1]), _near(V, [0.7, -0.1])]
    s = LiveSession(V, F, pins, bound=BOUND, method=method)
    size = float(np.ptp(V, axis=0).max())
    last = None
    for T in _drag_targets(V[pins]):
        fr = s.update(T)
        _independent_check(V, fr, F, BOUND)
        assert np.max(np.linalg.norm(fr.uv[pins] - T, axis=1)) <= 1e-9 * size
        assert fr.pin_error <= 1e-9 * size
        last = fr
    # The drag came back to the start: the map is the rest shape's again, up to the bound.
    assert last.max_distortion < BOUND


def test_an_infeasible_target_gives_certified_frames_with_a_positive_pin_error():
    """Two distinct pins sent to one point: no one-to-one map meets that."""
    V, F = _disk_with_hole()
    pins = [_near(V, [-0.7, 0.0]), _near(V, [0.7, 0.0]), _near(V, [0.0, 0.7])]
    s = LiveSession(V, F, pins, bound=BOUND)
    T = V[pins].copy()
    T[1] = T[0]
    for _ in range(4):
        fr = s.update(T)
        _independent_check(V, fr, F, BOUND)
        err = np.max(np.linalg.norm(fr.uv[pins] - T, axis=1))
        assert fr.pin_error > 0 and fr.pin_error == pytest.approx(err, rel=1e-12)
        # Never a jump back to the rest shape.
        assert not np.allclose(fr.uv, V)


def test_a_target_out_of_reach_in_one_frame_keeps_converging_to_it():
    V, F = _disk()
    pins = [_near(V, [-0.7, 0.0]), _near(V, [0.7, 0.0]), _near(V, [0.0, 0.7])]
    s = LiveSession(V, F, pins, bound=2.0, max_iterations=1, energy_steps=1)
    T = V[pins].copy()
    T[2] = [0.0, 1.5]
    errors = []
    for _ in range(30):
        fr = s.update(T)
        _independent_check(V, fr, F, 2.0)
        errors.append(fr.pin_error)
        if fr.pin_error == 0:
            break
    assert errors[0] > 0 and errors[-1] == 0
    assert np.array_equal(fr.uv[pins], T)


def test_set_pins_keeps_the_frame_and_reuses_a_pin_sets_factorisation():
    V, F = _disk()
    a, b, c = _near(V, [-0.7, 0.0]), _near(V, [0.7, 0.0]), _near(V, [0.0, 0.7])
    s = LiveSession(V, F, [a, b], bound=BOUND)
    fr = s.update(V[[a, b]] + [0.2, 0.1])
    first = s._set
    s.set_pins([c, a])
    assert np.array_equal(s.frame.uv, fr.uv)
    fr2 = s.update(np.array([fr.uv[c] + [0.0, 0.2], fr.uv[a]]))
    _independent_check(V, fr2, F, BOUND)
    assert np.array_equal(fr2.uv[[c, a]], np.array([fr.uv[c] + [0.0, 0.2], fr.uv[a]]))
    s.set_pins([b, a])                       # the same set as the first, in another order
    assert s._set is first


def test_rest_from_3d_is_the_conformal_map_and_distortion_is_measured_against_it():
    x, y = np.meshgrid(np.linspace(-1, 1, 9), np.linspace(-1, 1, 9))
    V2 = np.column_stack([x.ravel(), y.ravel()])
    F = []
    for i in range(8):
        for j in range(8):
            v = i * 9 + j
            F += [[v, v + 1, v + 10], [v, v + 10, v + 9]]
    F = np.array(F)
    V = np.column_stack([V2, 0.3 * V2[:, 0] ** 2])        # a curved sheet
    s = LiveSession(V, F, [0, 80], bound=BOUND)
    rest = s.rest
    ref = bd_uv.conformal_distortion(V, F, rest[F])
    assert np.all(np.isfinite(ref))
    fr = s.update(rest[[0, 80]] * 1.2)
    _independent_check(rest, fr, F, BOUND)


def test_bad_input_is_refused_with_typed_errors_and_a_closed_session_says_so():
    V, F = _disk()
    with pytest.raises(bd_uv.InvalidMeshError):
        LiveSession(V, F + len(V), [0, 1])
    flipped = V.copy()
    flipped[:, 0] *= -1
    with pytest.raises(bd_uv.DegenerateFacesError):
        LiveSession(V, F, [0, 1], rest_uv=flipped)
    with pytest.raises(bd_uv.OptionError, match="distinct"):
        LiveSession(V, F, [0, 0])
    with pytest.raises(bd_uv.OptionError, match="method"):
        LiveSession(V, F, [0, 1], method="stretch-l1")
    s = LiveSession(V, F, [0, 1])
    with pytest.raises(bd_uv.OptionError, match="one per pin"):
        s.update(np.zeros((3, 2)))
    s.close()
    with pytest.raises(SessionClosedError):
        s.update(V[[0, 1]])
    assert isinstance(SessionClosedError("x"), bd_uv.BDError)


def test_cancel_stops_the_next_update_and_keeps_the_last_frame():
    V, F = _disk()
    s = LiveSession(V, F, [0, 1])
    fr = s.update(V[[0, 1]] + 0.1)
    s.cancel()
    with pytest.raises(bd_uv.CancelledError):
        s.update(V[[0, 1]] + 0.3)
    assert s.frame is fr
    assert s.update(V[[0, 1]] + 0.3).certified


def test_frames_rounded_to_float32_are_certified_as_stored():
    V, F = _disk_with_hole()
    pins = [_near(V, [-0.7, 0.1]), _near(V, [0.7, -0.1])]
    s = LiveSession(V, F, pins, bound=BOUND, storage=np.float32)
    for T in _drag_targets(V[pins], steps=6):
        fr = s.update(T)
        assert np.array_equal(fr.uv.astype(np.float32).astype(np.float64), fr.uv)
        _independent_check(V, fr, F, BOUND)
        assert np.array_equal(fr.uv[pins], T.astype(np.float32).astype(np.float64))
        assert fr.pin_error == 0
