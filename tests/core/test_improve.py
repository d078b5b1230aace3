"""2D mesh improvement (Lipman 2012, section 6.6) on meshes from Shewchuk's Triangle."""
import json
import subprocess
import sys

import numpy as np
import pytest

import bd_uv
from bd_uv.improve import improve
from planar import boundary_edges, circle, mesh_polygon, overlapping_pairs, square

EQ = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, np.sqrt(3) / 2]])


def distortion_vs_equilateral(X, F):
    """max singular value / min singular value of the affine map equilateral -> each face (SVD)."""
    T = X[F]
    E1 = np.stack([T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]], 2)
    E0 = np.stack([EQ[1] - EQ[0], EQ[2] - EQ[0]], 1)
    J = E1 @ np.linalg.inv(E0)
    s = np.linalg.svd(J, compute_uv=False)
    return s[:, 0] / s[:, 1], np.linalg.det(J)


STAR = np.array([[np.cos(t) * (1 if k % 2 == 0 else 0.45), np.sin(t) * (1 if k % 2 == 0 else 0.45)]
                 for k, t in enumerate(np.linspace(0, 2 * np.pi, 10, endpoint=False))])
L_SHAPE = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], float)
_t = np.linspace(0, 2 * np.pi, 120, endpoint=False)
_r = 1 + 0.25 * np.sin(5 * _t) + 0.1 * np.sin(17 * _t) + 0.05 * np.cos(41 * _t)
COAST = np.stack([_r * np.cos(_t), 1.4 * _r * np.sin(_t)], 1)
POLYGONS = {
    "square": (square(8), [], []),
    "star": (STAR, [], []),
    "L-with-hole": (L_SHAPE, [circle(10, 0.25, (0.5, 0.5))[::-1]], [[0.5, 0.5]]),
    # a jagged coast (like the paper's Greenland) with a hole: Triangle leaves faces with all
    # three corners on the boundary, which no interior move can change
    "coast-with-hole": (COAST, [circle(14, 0.2, (0.1, 0.2))[::-1]], [[0.1, 0.2]]),
}


@pytest.mark.parametrize("name", sorted(POLYGONS))
def test_improve_reduces_max_distortion_by_20_percent(name):
    outer, holes, hp = POLYGONS[name]
    V, F = mesh_polygon(outer, holes, hp, area=0.01)
    res = improve(V, F)
    before, _ = distortion_vs_equilateral(V, F)
    after, det = distortion_vs_equilateral(res.V2, F)
    assert np.all(det > 0)
    b = np.unique(boundary_edges(F))
    movable = ~np.all(np.isin(F, b), axis=1)
    assert after[movable].max() <= 0.8 * before[movable].max()
    assert after[movable].max() <= res.bound * (1 + 1e-9)
    assert np.array_equal(after[~movable], before[~movable])
    if name != "coast-with-hole":
        assert after.max() <= 0.8 * before.max()
    assert np.isclose(res.max_before, before.max()) and np.isclose(res.max_after, after.max())
    assert V[b].tobytes() == res.V2[b].tobytes()
    assert overlapping_pairs(res.V2, F) == 0


def test_cli_improve(tmp_path):
    V, F = mesh_polygon(STAR, area=0.01)
    src, out = tmp_path / "star.obj", tmp_path / "better.obj"
    bd_uv.write_obj(str(src), np.column_stack([V, np.zeros(len(V))]), F)
    rep = tmp_path / "report.json"
    r = subprocess.run([sys.executable, "-m", "bd_uv", "improve", str(src), "-o", str(out),
                        "--report", str(rep)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "max distortion vs equilateral" in r.stdout
    m = bd_uv.load_mesh(str(out))
    assert np.array_equal(m.F, F)
    b = np.unique(boundary_edges(F))
    assert m.V[b, :2].tobytes() == V[b].tobytes()
    after, det = distortion_vs_equilateral(m.V[:, :2], F)
    assert np.all(det > 0) and after.max() <= 0.8 * distortion_vs_equilateral(V, F)[0].max()
    report = json.loads(rep.read_text())
    assert np.isclose(report["max_distortion_before"], distortion_vs_equilateral(V, F)[0].max())
    assert np.isclose(report["max_distortion_after"], after.max())
