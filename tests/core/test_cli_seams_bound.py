"""``--bound auto`` with seams added (``--seams needed`` or ``auto``) cannot go together: the
command line says so in its own flags (it said "seams_mode='auto' needs a numeric bound C", the
library's keyword), before reading the mesh, and writes nothing."""
import pytest

from bd_uv.cli import main


@pytest.mark.parametrize("seams", ["needed", "auto"])
def test_bound_auto_with_added_seams_is_said_in_flags(tmp_path, capsys, seams):
    (tmp_path / "t.off").write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    out = tmp_path / "o.obj"
    assert main(["unwrap", str(tmp_path / "t.off"), "-o", str(out), "--bound", "auto",
                 "--seams", seams]) == 2
    err = capsys.readouterr().err
    assert f"--seams {seams}" in err and "--bound" in err and "seams_mode" not in err
    assert not out.exists()


@pytest.mark.parametrize("seams", ["uv", "none", None])
def test_bound_auto_takes_the_islands_as_they_are(tmp_path, seams):
    (tmp_path / "t.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                                    "f 1/1 2/2 3/3\n")
    args = ["unwrap", str(tmp_path / "t.obj"), "-o", str(tmp_path / "o.obj"), "--bound", "auto"]
    assert main(args + (["--seams", seams] if seams else [])) == 0
    assert (tmp_path / "o.obj").exists()
