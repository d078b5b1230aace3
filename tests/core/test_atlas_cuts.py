"""Issue 18: the atlas cuts as an option (``UnwrapOptions.atlas_cuts``, ``--no-atlas-cuts``).

By default the seam search may cut one of its own charts in two where it alone caps the atlas's
coverage (a torus's band); ``atlas_cuts=False`` keeps the minimal seams. Every entry point takes
the option and reports which seams are for the atlas. The charts are counted, the atlas seams
checked against the seams added and their length recomputed from the positions here.
"""
import json

import numpy as np
import pytest

import bd_uv
from bd_uv.arguments import unwrap_options_of
from bd_uv.batch import JobOptions
from bd_uv.batch.files import _script_options
from bd_uv.cli import build_parser, main
from bd_uv.errors import OptionError
from bd_uv.meshio import write_obj
from bd_uv.options import UnwrapOptions

from seams_helpers import torus


def _keys(pairs):
    return set(map(tuple, np.sort(np.asarray(pairs, np.int64).reshape(-1, 2), axis=1).tolist()))


def _length(V, pairs):
    pairs = np.asarray(pairs, np.int64).reshape(-1, 2)
    return float(np.linalg.norm(V[pairs[:, 0]] - V[pairs[:, 1]], axis=1).sum())


def test_the_option_is_checked():
    assert UnwrapOptions().atlas_cuts is True
    assert UnwrapOptions(seams_mode="auto", atlas_cuts=False).atlas_cuts is False
    with pytest.raises(OptionError, match="atlas_cuts must be True or False"):
        UnwrapOptions(seams_mode="auto", atlas_cuts=0)
    # The marked seams add none: no atlas cut to turn off, so the option is refused there.
    with pytest.raises(OptionError, match="applies where seams are added"):
        UnwrapOptions(seams_mode="marked", atlas_cuts=False)


@pytest.mark.parametrize("mode", ["auto", "needed"])
def test_unwrap_cuts_the_torus_band_for_the_atlas_unless_told_not_to(mode):
    V, F, _, _ = torus()
    on = bd_uv.unwrap(V, F, seams=mode, bound=2.0)
    off = bd_uv.unwrap(V, F, seams=mode, bound=2.0, atlas_cuts=False)
    assert on.certified and off.certified
    assert (len(on.islands), len(off.islands)) == (2, 1)
    a = on.atlas_cuts
    assert a["cuts"] == 1 and len(a["seams"])
    assert _keys(a["seams"]) == _keys(on.seams_added) - _keys(off.seams_added)
    assert np.isclose(a["length"], _length(V, a["seams"]))
    assert off.atlas_cuts["cuts"] == 0 and len(off.atlas_cuts["seams"]) == 0
    report = on.report()["atlas_cuts"]
    assert report["cuts"] == 1 and _keys(report["seams"]) == _keys(a["seams"])


def test_the_command_line_and_the_blender_script_flags(tmp_path, capsys):
    for command in (["unwrap", "x.obj", "-o", "y.obj"], ["batch", "x", "-o", "y"]):
        assert unwrap_options_of(build_parser().parse_args(command)).atlas_cuts is True
        args = build_parser().parse_args(command + ["--no-atlas-cuts"])
        assert unwrap_options_of(args).atlas_cuts is False
    # A .blend's Blender script gets the flag from the batch's options.
    off = JobOptions(UnwrapOptions(seams_mode="needed", atlas_cuts=False))
    assert "--no-atlas-cuts" in _script_options(off)
    assert "--no-atlas-cuts" not in _script_options(JobOptions(UnwrapOptions(seams_mode="needed")))
    # With marked seams there is nothing to turn off: an error, not an ignored flag.
    V, F, _, _ = torus(nu=24, nv=10)
    src = tmp_path / "torus.obj"
    write_obj(str(src), V, F)
    assert main(["unwrap", str(src), "-o", str(tmp_path / "o.obj"), "--seams", "none",
                 "--no-atlas-cuts"]) == 2
    assert "atlas_cuts" in capsys.readouterr().err


@pytest.mark.parametrize("flags", [[], ["--no-atlas-cuts"]])
def test_unwrap_and_batch_report_the_atlas_cuts(tmp_path, flags):
    V, F, _, _ = torus()
    src = tmp_path / "torus.obj"
    write_obj(str(src), V, F)
    rep = tmp_path / "r.json"
    assert main(["unwrap", str(src), "-o", str(tmp_path / "o.obj"), "--seams", "auto",
                 "--bound", "2", "--report", str(rep), "-q", *flags]) == 0
    r = json.loads(rep.read_text())
    cuts = 0 if flags else 1
    assert r["atlas_cuts"]["cuts"] == cuts and len(r["islands"]) == 1 + cuts
    assert _keys(r["atlas_cuts"]["seams"]) <= _keys(r["seams_added"])
    assert np.isclose(r["atlas_cuts"]["length"], _length(V, r["atlas_cuts"]["seams"]))
    out = tmp_path / "batch"
    assert main(["batch", str(src), "-o", str(out), "--jobs", "1", "--bound", "2",
                 *flags]) == 0
    (item,) = json.loads((out / "report.json").read_text())["items"]
    assert item["atlas_cuts"]["cuts"] == cuts
    assert _keys(item["atlas_cuts"]["seams"]) <= _keys(item["seams_added"])
