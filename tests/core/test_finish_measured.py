"""``finish`` for ``bound="auto"``: a map whose UVs, as stored, measure over the problem's own max
(faces shrunk to float64's step, cow-strip1500z) is certified at the least C those UVs pass,
flagged ``bound_measured``; a fixed C, a flip or the stretch limits still fail it."""
import time
from types import SimpleNamespace

import numpy as np
import pytest

from bd_uv.unwrapping.finish import finish
from bd_uv.unwrapping.margins import certified_bound


def _problem():
    """Two right triangles of a unit square in 3D, one island, no pins."""
    V = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    tris = np.array([[0, 1, 2], [0, 2, 3]])
    island = SimpleNamespace(index=0, faces=np.arange(2), vertices=np.arange(4), tris=tris)
    return SimpleNamespace(island=island, V=V, pin_idx=np.zeros(0, np.int64),
                           pin_val=np.zeros(0, complex), area3d=1.0, faces_3d=None,
                           timings={"certify": 0.0}, solves=0, iterations=0)


def _distortion(V, tris, uv):
    """Each face's conformal distortion sigma_max / sigma_min of its 3D-to-UV map, by an SVD of
    the Jacobian in a frame of the face (independent of bd_uv.metrics)."""
    out = []
    for t in tris:
        p, q = V[t], uv[t]
        e1, e2 = p[1] - p[0], p[2] - p[0]
        x = e1 / np.linalg.norm(e1)
        y = np.cross(np.cross(e1, e2), e1)
        y /= np.linalg.norm(y)
        P = np.array([[e1 @ x, e2 @ x], [e1 @ y, e2 @ y]])
        Q = np.array([q[1] - q[0], q[2] - q[0]]).T
        s = np.linalg.svd(Q @ np.linalg.inv(P), compute_uv=False)
        out.append(s[0] / s[1])
    return np.array(out)


def _stretched_map():
    """The square's map stretched 3x along u: both faces' distortion exactly 3."""
    return np.array([0, 3, 3 + 1j, 1j], dtype=complex)


def test_auto_certifies_the_stored_uvs_where_they_measure_over_the_problems_max():
    prob = _problem()
    u = _stretched_map()
    r = finish(prob, u, 2.0, "auto", "conformal", [], time.perf_counter())
    D = _distortion(prob.V, prob.island.tris, r.uv)
    assert D.max() == pytest.approx(3.0, rel=1e-12)
    assert r.status == "certified" and "bound_measured" in r.flags
    assert r.bound_certified == certified_bound(r.max_distortion) >= D.max()
    assert r.max_distortion == pytest.approx(D.max(), rel=1e-12)


def test_auto_within_the_problems_max_is_not_flagged():
    r = finish(_problem(), _stretched_map(), 3.0, "auto", "conformal", [], time.perf_counter())
    assert r.status == "certified" and "bound_measured" not in r.flags


@pytest.mark.parametrize("case", ["fixed", "flipped", "stretch"])
def test_a_fixed_bound_a_flip_or_the_stretch_limits_still_fail(case):
    prob, u = _problem(), _stretched_map()
    bound, stretch = ("auto", None)
    if case == "fixed":
        bound = 2.0
    elif case == "flipped":
        u = u.conjugate()                   # a mirror: both faces flipped
    else:
        stretch = 1.5                       # its singular values, area kept: sqrt(3), 1/sqrt(3)
    r = finish(prob, u, 2.0, bound, "conformal", [], time.perf_counter(), stretch)
    assert r.status == "failed" and r.uv is None
    assert "bound_measured" not in (r.flags or ())
