"""method="stretch-l1" / --method stretch-l1: the L1 stretch energy sum_j (|alpha_j| + |beta_j|)
Area_j over F_C (Lipman 2012, section 6.1), free boundary (scale held) and fixed boundary. Its
value is recomputed here from numpy's SVD of each face's map (|alpha| + |beta| is the largest
singular value), and compared with the BD-Dirichlet optimum on the same space."""
import argparse
import json
import os

import numpy as np
import pytest

import bd_uv
from bd_uv import batch
from bd_uv.cli import main
from bd_uv.frames import frames_from_map
from bd_uv.unwrapping.problem import IslandProblem
from helpers import DATA, load_off, reference_distortion, reference_jacobians
from overlap_shapes import overlapping_triangle_pairs
from test_unwrap_boundary import batch_read_uv

NEFERTITI = os.path.join(DATA, "nefertiti.off")


def l1_energy(V, F, corner_uv, own_scale=True):
    """sum A_j sigma_1,j / sum A_j, at the island's own scale (UV area = 3D area) or as given."""
    J = reference_jacobians(V, F, corner_uv)
    s = np.linalg.svd(J, compute_uv=False)
    P = V[F]
    A = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    k = np.sqrt(A.sum() / np.sum(np.linalg.det(J) * A)) if own_scale else 1.0
    return float(np.sum(A * s[:, 0]) * k / A.sum())


def check_certified(V, F, corner_uv, C):
    D, flipped = reference_distortion(V, F, corner_uv)
    assert flipped.sum() == 0 and D.max() <= C * (1 + 1e-6)


@pytest.fixture(scope="module")
def nefertiti():
    return load_off("nefertiti.off")


def test_optimum_not_above_dirichlet_on_the_same_space(nefertiti):
    """One island problem, one formulation (anchor vertex and held scale), the same frames and C:
    the L1 optimum's L1 energy is no higher than at the BD-Dirichlet optimum."""
    V, F = nefertiti
    isl = bd_uv.islands(V, F)[0]
    pins = (np.zeros(0, np.int64), np.zeros((0, 2)))
    maps = {}
    for method in ("stretch-l1", "dirichlet"):
        prob = IslandProblem(isl, V, pins, method, "soc", None)
        u0 = prob.fallback_map()
        w = frames_from_map(prob.alpha(u0))
        prob.hold_scale(u0)
        u, outcome = prob.solve(w, 3.0)
        assert outcome == "solved"
        uv = np.column_stack([u.real, u.imag])[isl.tris]
        check_certified(prob.Vn, isl.tris, uv, 3.0)
        maps[method] = uv
    e = {m: l1_energy(V[isl.vertices], isl.tris, uv, own_scale=False)
         for m, uv in maps.items()}
    assert e["stretch-l1"] <= e["dirichlet"] * (1 + 1e-6)
    assert e["stretch-l1"] < 0.99 * e["dirichlet"]   # and not equal by accident


@pytest.mark.parametrize("kwargs", [dict(bound=3.0), dict(boundary="circle", bound=4.0),
                                    dict(boundary="rectangle", bound=8.0)])
def test_unwrap_stretch_l1_certifies_and_beats_dirichlet(nefertiti, kwargs):
    V, F = nefertiti
    res = {m: bd_uv.unwrap(V, F, method=m, **kwargs) for m in ("stretch-l1", "dirichlet")}
    for r in res.values():
        (isl,) = r.islands
        assert isl.status == "certified", isl.message
        check_certified(V, F, r.corner_uv, kwargs["bound"])
        assert len(overlapping_triangle_pairs(r.corner_uv)) == 0
        if "boundary" in kwargs:
            assert isl.bijective is True
    own = "boundary" not in kwargs   # a fixed boundary gives the scale
    e = {m: l1_energy(V, F, r.corner_uv, own) for m, r in res.items()}
    assert e["stretch-l1"] <= e["dirichlet"] * (1 + 1e-6)


def test_free_boundary_keeps_its_scale(nefertiti):
    """Without the held scale the L1 energy would shrink the island to a point."""
    V, F = nefertiti
    r = bd_uv.unwrap(V, F, method="stretch-l1", bound=3.0, overlap="fail")
    J = reference_jacobians(V, F, r.corner_uv)
    s = np.linalg.svd(J, compute_uv=False)
    assert 0.2 < s[:, 1].min() and s[:, 0].max() < 5.0  # UV area = 3D area, no collapse


def test_cli_and_batch(tmp_path, nefertiti):
    V0, F0 = nefertiti
    out, rep = tmp_path / "n.obj", tmp_path / "n.json"
    assert main(["unwrap", NEFERTITI, "-o", str(out), "--method", "stretch-l1", "--bound", "3",
                 "--report", str(rep)]) == 0
    check_certified(V0, F0, batch_read_uv(out, F0), 3.0)
    assert json.loads(rep.read_text())["islands"][0]["status"] == "certified"
    parser = argparse.ArgumentParser()
    batch.add_batch_parser(parser.add_subparsers())
    args = parser.parse_args(["batch", NEFERTITI, "-o", str(tmp_path / "b"), "--jobs", "1",
                              "--method", "stretch-l1", "--boundary", "circle"])
    assert args.func(args) == 0
    item = json.loads((tmp_path / "b" / "report.json").read_text())["items"][0]
    assert item["status"] == "certified" and item["islands"][0]["bijective"] is True
    check_certified(V0, F0, batch_read_uv(tmp_path / "b" / "nefertiti.obj", F0), 5.0)
