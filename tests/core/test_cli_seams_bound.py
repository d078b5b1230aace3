"""``--bound auto`` with ``--seams auto`` cannot go together: the command line says so in its
own flags (it said "seams_mode='auto' needs a numeric bound C", the library's keyword), before
reading the mesh, and writes nothing. With ``--seams needed`` (also the default) it works: each
island and each chart the seam search cuts gets its least C, a closed mesh included."""
import json

import numpy as np
import pytest

from bd_uv.cli import main
from bd_uv.layout import stored_layout
from test_repair import DEFECTS, _check_certified, written_corner_uv


def test_bound_auto_with_seams_auto_is_said_in_flags(tmp_path, capsys):
    (tmp_path / "t.off").write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    out = tmp_path / "o.obj"
    assert main(["unwrap", str(tmp_path / "t.off"), "-o", str(out), "--bound", "auto",
                 "--seams", "auto"]) == 2
    err = capsys.readouterr().err
    assert "--seams auto" in err and "--bound" in err and "seams_mode" not in err
    assert not out.exists()


@pytest.mark.parametrize("seams", ["uv", "none"])
def test_bound_auto_takes_the_islands_as_they_are(tmp_path, seams):
    (tmp_path / "t.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                                    "f 1/1 2/2 3/3\n")
    args = ["unwrap", str(tmp_path / "t.obj"), "-o", str(tmp_path / "o.obj"), "--bound", "auto"]
    assert main(args + ["--seams", seams]) == 0
    assert (tmp_path / "o.obj").exists()


def _eight():
    from helpers import load_off
    return load_off("eight.off")          # CGAL's genus-2 closed mesh (tests/data)


def _check_least(V, F, res, uv):
    """Every island certified, each at its own C: its faces' distortion (recomputed by SVD
    from the UVs given) within it, none flipped, none overlapping another."""
    from helpers import reference_distortion
    assert all(r.status == "certified" for r in res.islands)
    for r in res.islands:
        D, flipped = reference_distortion(V, F[r.faces], uv[r.faces])
        assert not flipped.any() and D.max() <= r.bound_certified * (1 + 1e-6)
    _check_certified(V, F, uv, [])


def test_seams_needed_minimises_c_on_a_closed_mesh():
    """``bound="auto"`` with ``seams="needed"`` on a closed genus-2 mesh: seams added, every
    chart certified at its own least C, below the C = 2 the search certified it at and at least
    as low as the same call at C = 5 gives (recomputed as stored in float32)."""
    import bd_uv
    V, F = _eight()
    res = bd_uv.unwrap(V, F, seams="needed", bound="auto")
    five = bd_uv.unwrap(V, F, seams="needed", bound=5.0)
    assert len(res.seams_added) and all(r.bound_requested == "auto" for r in res.islands)
    uv = stored_layout(V, F, res, dtype=np.float32).corner_uv
    _check_least(V, F, res, uv)
    least = max(r.bound_certified for r in res.islands)
    assert least < 2.0 and least <= max(r.max_distortion for r in five.islands) * (1 + 1e-6)


def test_bound_auto_on_a_closed_mesh_from_the_command_line(tmp_path):
    """``--bound auto`` without ``--seams`` was "marked": a closed mesh was refused ("add
    seams"); now the default seams are added where needed and each island minimised."""
    V, F = _eight()
    src, out, rep = tmp_path / "eight.obj", tmp_path / "o.obj", tmp_path / "r.json"
    src.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in V.tolist())
                   + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F))
    assert main(["unwrap", str(src), "-o", str(out), "--report", str(rep), "--bound", "auto",
                 "--quiet"]) == 0
    report = json.loads(rep.read_text())
    assert report["seams_added"] and all(i["status"] == "certified" for i in report["islands"])
    assert all(i["bound_certified"] < 2.0 for i in report["islands"])
    _check_certified(V, F, written_corner_uv(out), [])


@pytest.mark.parametrize("make", DEFECTS, ids=lambda f: f.__name__)
def test_seams_needed_minimises_c_on_a_messy_mesh(make):
    """A bow-tie, an edge of three faces, parts wound against each other, a duplicate, a
    zero-area or a NaN face with ``bound="auto"``: repaired as at a number C, every face but the
    ones no map certifies at its island's least C (recomputed as stored in float32), within the
    default C = 5 (``needed.AUTO_LIMIT``)."""
    import bd_uv
    V, F, skip, words = make()
    res = bd_uv.unwrap(V, F, seams="needed", bound="auto")
    assert any(words in note for note in res.repair), res.repair
    uv = stored_layout(V, F, res, dtype=np.float32).corner_uv
    _check_certified(V, F, uv, skip)
    from helpers import reference_distortion
    for r in res.islands:
        if r.status == "certified":
            D, flipped = reference_distortion(V, F[r.faces], uv[r.faces])
            assert not flipped.any() and D.max() <= r.bound_certified * (1 + 1e-6) <= 5.0
    failed = [r for r in res.islands if r.status != "certified"]
    assert sorted(int(f) for r in failed for f in r.faces) == sorted(skip)
