import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import bd_uv
from helpers import grid, load_off, reference_distortion


@pytest.fixture(scope="module")
def nefertiti():
    return load_off("nefertiti.off")


def _check_certified(V, F, res):
    for r in res.islands:
        assert r.status == "certified", r.message
        D, flip = reference_distortion(V, F[r.faces], res.corner_uv[r.faces])
        assert not flip.any()
        assert D.max() <= r.bound_certified * (1 + 1e-6)
        np.testing.assert_allclose(D, r.distortion, rtol=1e-6)
        assert r.max_distortion == pytest.approx(D.max(), rel=1e-9)


def test_core_does_not_import_blender():
    out = subprocess.run([sys.executable, "-c", "import sys, bd_uv; print('bpy' in sys.modules)"],
                         capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_bd_lscm_on_a_real_mesh_is_certified_and_keeps_3d_area(nefertiti):
    V, F = nefertiti
    res = bd_uv.unwrap(V, F, bound=2.0)
    _check_certified(V, F, res)
    r = res.islands[0]
    assert r.bound_certified == 2.0 and r.max_distortion <= 2.0
    uv = res.corner_uv
    e1, e2 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    uv_area = 0.5 * np.sum(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    P = V[F]
    area3d = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1).sum()
    assert uv_area == pytest.approx(area3d, rel=1e-9)
    assert uv[..., 0].min() == pytest.approx(0.0, abs=1e-12)
    assert uv[..., 1].min() == pytest.approx(0.0, abs=1e-12)
    # Corners of one island vertex carry one UV (the map is continuous).
    flat = res.corner_uv.reshape(-1, 2)
    for v in (F[0, 0], F[10, 1]):
        same = flat[F.ravel() == v]
        np.testing.assert_array_equal(same, np.broadcast_to(same[0], same.shape))


@pytest.mark.parametrize("method", ["arap", "dirichlet"])
@pytest.mark.parametrize("cone", ["soc", "linf"])
def test_other_energies_and_the_linf_space_are_certified(nefertiti, method, cone):
    V, F = nefertiti
    res = bd_uv.unwrap(V, F, method=method, bound=3.0, cone=cone)
    _check_certified(V, F, res)


def test_auto_finds_a_smaller_certified_bound_than_a_fixed_one(nefertiti):
    V, F = nefertiti
    fixed = bd_uv.unwrap(V, F, bound=5.0).islands[0]
    auto = bd_uv.unwrap(V, F, bound="auto")
    _check_certified(V, F, auto)
    r = auto.islands[0]
    # the certified bound keeps a little room above the map's distortion for float32 storage
    assert r.max_distortion <= r.bound_certified <= r.max_distortion * 1.001
    assert r.bound_certified <= fixed.max_distortion
    assert r.bound_certified < 1.35  # Blender ABF reaches 1.405 on this mesh (BENCHMARKS.md)


def test_seams_cut_a_closed_tube_open():
    # A closed-around cylinder band: without a seam it has two boundary loops (an annulus, which
    # is fine); closing the ends makes it a sphere that needs a seam.
    n, h = 16, 4
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    V = np.concatenate([np.stack([np.cos(t), np.sin(t), np.full(n, z)], 1) for z in range(h)])
    idx = np.arange(n * h).reshape(h, n)
    a, b = idx[:-1], np.roll(idx[:-1], -1, axis=1)
    c, d = idx[1:], np.roll(idx[1:], -1, axis=1)
    F = np.concatenate([np.stack([a.ravel(), b.ravel(), d.ravel()], 1),
                        np.stack([a.ravel(), d.ravel(), c.ravel()], 1)])
    annulus = bd_uv.unwrap(V, F)
    _check_certified(V, F, annulus)
    seam = np.stack([idx[:-1, 0], idx[1:, 0]], 1)
    cut = bd_uv.unwrap(V, F, seams=seam)
    _check_certified(V, F, cut)
    assert len(cut.islands[0].vertices) == n * h + h  # the seam's vertices were split
    # Cap both ends: a closed surface without seams cannot be flattened.
    top = len(V)
    Vc = np.concatenate([V, [[0, 0, 0], [0, 0, h - 1]]])
    caps = np.concatenate([np.stack([np.roll(idx[0], -1), idx[0], np.full(n, top)], 1),
                           np.stack([idx[-1], np.roll(idx[-1], -1), np.full(n, top + 1)], 1)])
    Fc = np.concatenate([F, caps])
    closed = bd_uv.unwrap(Vc, Fc)
    r = closed.islands[0]
    assert isinstance(r.error, bd_uv.ClosedIslandError)
    assert "seam" in r.message
    assert np.isnan(closed.corner_uv).all()


def test_pins_are_kept_to_the_bit(nefertiti):
    V, F = nefertiti
    loop = bd_uv.islands(V, F)[0].loops[0]
    corners = [int(np.flatnonzero(F.ravel() == loop[0])[0]),
               int(np.flatnonzero(F.ravel() == loop[len(loop) // 2])[0])]
    pins = np.array([[0.123456789, 0.2], [0.9, 0.7654321]])
    res = bd_uv.unwrap(V, F, pin_corners=corners, pin_uv=pins, bound=3.0)
    _check_certified(V, F, res)
    got = res.corner_uv.reshape(-1, 2)[corners]
    assert np.array_equal(got, pins)


def test_pins_that_force_a_flip_give_a_typed_error(nefertiti):
    V, F = nefertiti
    f = 100
    res = bd_uv.unwrap(V, F, pin_corners=[3 * f, 3 * f + 1, 3 * f + 2],
                       pin_uv=[[0, 0], [0, 1], [1, 0]], bound=5.0, bound_limit=20.0)
    r = res.islands[0]
    assert r.status == "failed"
    assert isinstance(r.error, bd_uv.InfeasibleError)
    assert r.error.island == 0 and "island 0" in r.message and "pins" in r.message
    assert np.isnan(res.corner_uv).all()
    assert not res.certified


def test_preset_cancel_returns_promptly_with_nothing(nefertiti):
    V, F = nefertiti
    ev = threading.Event()
    ev.set()
    t = time.perf_counter()
    with pytest.raises(bd_uv.CancelledError):
        bd_uv.unwrap(V, F, cancel=ev)
    assert time.perf_counter() - t < 30  # generous: a sanity bound, not a performance claim


def test_cancel_during_the_solve(nefertiti):
    V, F = nefertiti
    ev = threading.Event()
    seen = []

    def progress(frac, msg):
        seen.append(msg)
        if "solving" in msg:
            ev.set()
    with pytest.raises(bd_uv.CancelledError):  # C = 1.3: below the conformal map's 1.443
        bd_uv.unwrap(V, F, bound=1.3, cancel=ev, progress=progress)
    assert any("solving" in m for m in seen)


def test_constant_frames_on_a_planar_mesh_reach_distortion_one():
    V, F = grid(8, 7)
    res = bd_uv.unwrap(V, F, frames="constant", bound="auto")
    _check_certified(V, F, res)
    assert res.islands[0].max_distortion < 1.0 + 1e-6
    assert res.islands[0].frames == "constant"


def test_input_uv_frames(nefertiti):
    V, F = nefertiti
    first = bd_uv.unwrap(V, F, bound=3.0)
    again = bd_uv.unwrap(V, F, bound=3.0, frames="input-uv", initial_uv=first.corner_uv)
    _check_certified(V, F, again)
    assert again.islands[0].frames == "input-uv"


def test_report_has_the_documented_fields(nefertiti):
    V, F = nefertiti
    rep = bd_uv.unwrap(V, F).report()
    isl = rep["islands"][0]
    for key in ("faces", "bound_requested", "bound_certified", "max_distortion",
                "mean_distortion", "flipped", "frames", "seconds", "status"):
        assert key in isl
    assert isl["faces"] == len(F) and isl["flipped"] == 0 and isl["status"] == "certified"
