import json
import os
import subprocess
import sys

import numpy as np
import pytest

import bd_uv
from helpers import DATA, load_off, reference_distortion

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _run(*args):
    return subprocess.run([sys.executable, "-m", "bd_uv", *args], capture_output=True, text=True,
                          cwd=REPO)


def _read_obj(path):
    v, vt, fv, ft = [], [], [], []
    for line in open(path):
        p = line.split()
        if not p:
            continue
        if p[0] == "v":
            v.append([float(t) for t in p[1:4]])
        elif p[0] == "vt":
            vt.append([float(t) for t in p[1:3]])
        elif p[0] == "f":
            fv.append([int(t.split("/")[0]) - 1 for t in p[1:]])
            ft.append([int(t.split("/")[1]) - 1 if "/" in t else -1 for t in p[1:]])
    return np.array(v), np.array(vt), np.array(fv), np.array(ft)


def test_unwrap_writes_obj_report_and_png(tmp_path):
    out, rep, png = tmp_path / "n.obj", tmp_path / "n.json", tmp_path / "n.png"
    r = _run("unwrap", os.path.join(DATA, "nefertiti.off"), "-o", str(out), "--bound", "3",
             "--report", str(rep), "--png", str(png))
    assert r.returncode == 0, r.stderr
    assert "certified C = 3" in r.stdout
    V0, F0 = load_off("nefertiti.off")
    V, VT, FV, FT = _read_obj(out)
    np.testing.assert_allclose(V, V0, rtol=0, atol=0)      # input vertices, same order
    np.testing.assert_array_equal(FV, F0)                  # input faces, same order
    assert len(VT) == len(V0)                              # one vt per island vertex (a disk)
    D, flip = reference_distortion(V, FV, VT[FT])
    assert not flip.any() and D.max() <= 3.0 * (1 + 1e-6)
    data = json.loads(rep.read_text())
    assert data["method"] == "lscm" and data["input"].endswith("nefertiti.off")
    isl = data["islands"][0]
    assert isl["status"] == "certified" and isl["flipped"] == 0
    assert isl["bound_certified"] == 3.0
    assert isl["max_distortion"] == pytest.approx(D.max(), rel=1e-6)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_obj_uv_seams_define_the_islands(tmp_path):
    # Two quads sharing an edge, with a UV discontinuity along it: two islands.
    src = tmp_path / "two.obj"
    src.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n"
                   "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 5 0\nvt 6 0\nvt 6 1\nvt 5 1\n"
                   "f 1/1 2/2 3/3 4/4\nf 2/5 5/6 6/7 3/8\n")
    out = tmp_path / "o.obj"
    r = _run("unwrap", str(src), "-o", str(out), "--report", str(tmp_path / "r.json"))
    assert r.returncode == 0, r.stderr
    rep = json.loads((tmp_path / "r.json").read_text())
    assert len(rep["islands"]) == 2
    _, VT, FV, FT = _read_obj(out)
    assert len(VT) == 8  # the shared edge's two vertices are split
    r = _run("unwrap", str(src), "-o", str(out), "--seams", "none",
             "--report", str(tmp_path / "r.json"))
    assert len(json.loads((tmp_path / "r.json").read_text())["islands"]) == 1


def test_failed_island_gives_nonzero_exit_and_one_line(tmp_path):
    # A closed tetrahedron: no boundary, needs seams (with --seams none nothing adds them).
    src = tmp_path / "tet.off"
    src.write_text("OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n")
    out = tmp_path / "o.obj"
    assert _run("unwrap", str(src), "-o", str(out)).returncode == 0  # the default adds seams
    r = _run("unwrap", str(src), "-o", str(out), "--seams", "none")
    assert r.returncode == 1
    errs = [l for l in r.stderr.splitlines() if l.startswith("error:")]
    assert len(errs) == 1 and "closed" in errs[0] and "seams" in errs[0]


def test_bad_arguments_and_missing_files(tmp_path):
    assert _run("unwrap", "nope.off", "-o", str(tmp_path / "o.obj")).returncode == 2
    r = _run("unwrap", os.path.join(DATA, "nefertiti.off"), "-o", "x.obj", "--bound", "0.5")
    assert r.returncode == 2 and "bound" in r.stderr


def test_load_mesh_keeps_position_indices(tmp_path):
    src = tmp_path / "q.obj"
    src.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                   "f 1/1 2/2 3/3 4/4\n")
    m = bd_uv.load_mesh(str(src))
    assert m.V.shape == (4, 3)
    np.testing.assert_array_equal(m.F, [[0, 1, 2], [0, 2, 3]])
    np.testing.assert_array_equal(m.corner_uv[1], [[0, 0], [1, 1], [0, 1]])
    assert len(m.uv_seams()) == 0
