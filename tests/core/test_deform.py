"""Planar deformation with handles (Lipman 2012, section 6.1), checked by SVD of each face's map."""
import json
import subprocess
import sys

import numpy as np
import pytest

import bd_uv
from bd_uv.deform import deform
from bd_uv.frames import _solve_fixed
from bd_uv.energies import energy, jacobian_operators
from bd_uv.geometry import local_coordinates

from planar import (boundary_edges, circle, mesh_polygon, overlapping_pairs, square,
                     svd_of_maps)


@pytest.fixture(scope="module")
def annulus():
    """A square with a round hole; handles: the whole outer boundary (fixed) and the hole's
    boundary moved by (0.3, 0.15) and turned by 45 degrees."""
    V, F = mesh_polygon(square(6), [circle(16, 0.3)[::-1]], [[0.0, 0.0]], area=0.006)
    b = np.unique(boundary_edges(F))
    inner = b[np.linalg.norm(V[b], axis=1) < 0.5]
    outer = np.setdiff1d(b, inner)
    t = np.deg2rad(45)
    R = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    H = np.concatenate([outer, inner])
    P = np.concatenate([V[outer], V[inner] @ R.T + [0.3, 0.15]])
    return V, F, H, P


def test_plain_harmonic_folds_on_the_annulus(annulus):
    V, F, H, P = annulus
    ops = jacobian_operators(local_coordinates(np.column_stack([V, 0 * V[:, 0]]), F), F, len(V))
    Q, _, _ = energy("dirichlet", ops, np.ones(len(F)))
    u = _solve_fixed(Q, len(V), H, P[:, 0] + 1j * P[:, 1])
    _, det = svd_of_maps(V, np.column_stack([u.real, u.imag]), F)
    assert (det <= 0).sum() > 0


@pytest.mark.parametrize("method", ["arap", "dirichlet"])
def test_bd_deformation_has_no_flip_and_meets_handles(annulus, method):
    V, F, H, P = annulus
    res = deform(V, F, H, P, method=method, bound=5.0)
    assert np.array_equal(res.uv[H], P)
    s, det = svd_of_maps(V, res.uv, F)
    assert np.all(det > 0)
    assert np.max(s[:, 0] / s[:, 1]) <= 5.0 * (1 + 1e-6)
    assert overlapping_pairs(res.uv, F) == 0


def test_bd_biharmonic_square_with_one_interior_handle_is_bijective():
    """The paper's Figure 4 setting: boundary fixed, one interior point moved, C = 5."""
    V, F = mesh_polygon(square(8), area=0.01)
    b = np.unique(boundary_edges(F))
    c = int(np.argmin(np.linalg.norm(V - [-0.3, 0.0], axis=1)))
    H = np.concatenate([b, [c]])
    P = np.concatenate([V[b], V[[c]] + [0.9, 0.0]])
    ops = jacobian_operators(local_coordinates(np.column_stack([V, 0 * V[:, 0]]), F), F, len(V))
    Q, _, _ = energy("biharmonic", ops, np.ones(len(F)))
    u = _solve_fixed(Q, len(V), H, P[:, 0] + 1j * P[:, 1])
    assert (svd_of_maps(V, np.column_stack([u.real, u.imag]), F)[1] <= 0).sum() > 0  # plain folds
    res = deform(V, F, H, P, method="biharmonic", bound=5.0)
    s, det = svd_of_maps(V, res.uv, F)
    assert np.all(det > 0) and np.max(s[:, 0] / s[:, 1]) <= 5.0 * (1 + 1e-6)
    assert np.array_equal(res.uv[H], P)
    assert overlapping_pairs(res.uv, F) == 0


def test_steps_with_previous_frames_reach_what_one_step_cannot(annulus):
    """Turning the hole by 90 degrees: rest frames admit no map within C = 5 (faces would turn
    beyond 90 degrees from their frames); three steps, each from the previous result, do."""
    V, F, _, _ = annulus
    b = np.unique(boundary_edges(F))
    inner = b[np.linalg.norm(V[b], axis=1) < 0.5]
    outer = np.setdiff1d(b, inner)

    def targets(deg, shift):
        t = np.deg2rad(deg)
        R = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
        return np.concatenate([V[outer], V[inner] @ R.T + [shift, 0.0]])
    Hs = np.concatenate([outer, inner])
    with pytest.raises(bd_uv.InfeasibleError):
        deform(V, F, Hs, targets(90, 0.1), method="arap", bound=5.0)
    prev = None
    for k in (1, 2, 3):
        res = deform(V, F, Hs, targets(30 * k, 0.1 * k / 3), method="arap", bound=5.0,
                     frames="previous", previous=prev)
        prev = res.uv
    s, det = svd_of_maps(V, res.uv, F)
    assert np.all(det > 0) and np.max(s[:, 0] / s[:, 1]) <= 5.0 * (1 + 1e-6)
    assert np.array_equal(res.uv[Hs], targets(90, 0.1 * 3 / 3))
    assert overlapping_pairs(res.uv, F) == 0


def test_bad_options():
    V, F = mesh_polygon(square(4), area=0.1)
    with pytest.raises(ValueError):
        deform(V, F, [0, 1], [[0, 0], [1, 1]], method="nope")
    with pytest.raises(ValueError):
        deform(V, F[:, ::-1], [0, 1], V[[0, 1]])
    with pytest.raises(ValueError, match="sqrt"):
        deform(V, F, [0, 1], V[[0, 1]], bound=4.0, stretch=1.5)
    with pytest.raises(bd_uv.InfeasibleError):
        b = np.unique(boundary_edges(F))
        deform(V, F, b, V[b][::-1], bound=2.0)


def test_cli_deform(tmp_path, annulus):
    V, F, H, P = annulus
    src = tmp_path / "in.obj"
    bd_uv.write_obj(str(src), np.column_stack([V, 0 * V[:, 0]]), F)
    hj = tmp_path / "handles.json"
    hj.write_text(json.dumps({"vertices": H.tolist(), "positions": P.tolist()}))
    out = tmp_path / "out.obj"
    r = subprocess.run([sys.executable, "-m", "bd_uv", "deform", str(src), "-o", str(out),
                        "--handles", str(hj), "--method", "arap", "--bound", "5"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    m = bd_uv.load_mesh(str(out))
    assert np.array_equal(m.F, F)
    assert np.allclose(m.V[:, 2], 0)
    s, det = svd_of_maps(V, m.V[:, :2], F)
    assert np.all(det > 0)
    assert np.max(np.abs(m.V[H, :2] - P)) < 1e-12
    hj.write_text(json.dumps({"vertices": [0]}))
    r = subprocess.run([sys.executable, "-m", "bd_uv", "deform", str(src), "-o", str(out),
                        "--handles", str(hj)], capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.startswith("error:")


def _u_shape():
    """A U (two arms 1 wide and 1.5 long on a 3 x 0.5 base) and its arms' tips."""
    outline = np.array([(0, 0), (3, 0), (3, 2), (2, 2), (2, 0.5), (1, 0.5), (1, 2), (0, 2)],
                       float)
    V, F = mesh_polygon(outline, area=0.01)

    def near(p):
        return int(np.argmin(np.linalg.norm(V - p, axis=1)))
    return V, F, near


@pytest.mark.parametrize("method", ["arap", "lscm"])
def test_a_deformation_that_would_overlap_is_mended_in_certified_steps(method):
    """The left tip pulled past the right one: the direct solve lays the arms over each other
    (free boundary, two handles); the result is found by dragging there instead."""
    V, F, near = _u_shape()
    H = np.array([near([0.5, 2.0]), near([2.5, 2.0])])
    P = np.array([[3.0, 2.0], [2.5, 2.0]])
    res = deform(V, F, H, P, method=method, bound=5.0)
    assert res.mended and res.overlap_free
    assert np.array_equal(res.uv[H], P)
    s, det = svd_of_maps(V, res.uv, F)
    assert np.all(det > 0) and np.max(s[:, 0] / s[:, 1]) <= 5.0
    assert overlapping_pairs(res.uv, F) == 0


def test_a_deformation_that_would_overlap_and_cannot_be_mended_is_refused():
    V, F, near = _u_shape()
    H = np.array([near([0.5, 2.0]), near([2.5, 2.0])])
    with pytest.raises(bd_uv.OverlapError, match="over itself"):
        deform(V, F, H, np.array([[3.0, 2.0], [2.5, 2.0]]), method="biharmonic", bound=5.0)
    H3 = np.array([near([0.5, 2.0]), near([2.5, 2.0]), near([1.5, 0.0])])
    P3 = np.array([[2.7, 2.0], [0.3, 2.0], V[H3[2]]])       # the arms swapped, base held
    with pytest.raises(bd_uv.OverlapError, match="no overlap-free map"):
        deform(V, F, H3, P3, method="arap", bound=5.0)


def test_every_result_carries_its_overlap_test(annulus):
    V, F, H, P = annulus
    res = deform(V, F, H, P, method="arap", bound=5.0)
    assert res.overlap_free and not res.mended


def test_cli_deform_refusing_an_overlap_exits_1_with_one_line(tmp_path):
    V, F, near = _u_shape()
    src = tmp_path / "u.obj"
    bd_uv.write_obj(str(src), np.column_stack([V, 0 * V[:, 0]]), F)
    hj = tmp_path / "handles.json"
    H = [near([0.5, 2.0]), near([2.5, 2.0])]
    hj.write_text(json.dumps({"vertices": H, "positions": [[3.0, 2.0], [2.5, 2.0]]}))
    r = subprocess.run([sys.executable, "-m", "bd_uv", "deform", str(src), "-o",
                        str(tmp_path / "out.obj"), "--handles", str(hj), "--method",
                        "biharmonic", "--bound", "5"], capture_output=True, text=True)
    assert r.returncode == 1
    assert r.stderr.startswith("error: the deformation would lay the island over itself")
    assert not (tmp_path / "out.obj").exists()
