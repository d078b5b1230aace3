"""The write paths (``python -m bd_uv unwrap`` and the batch's per-file path) store only islands
certified as stored: overlapping islands cut, packed into the unit square, report = measurement."""
import json

import numpy as np

from bd_uv import batch, cli
from bd_uv.meshio import load_mesh, write_obj
from overlap_shapes import helicoid_ribbon, overlapping_triangle_pairs
from unwrap_contract import distortion_and_flips


def helicoid_obj(tmp_path):
    V, F = helicoid_ribbon()
    path = tmp_path / "helicoid.obj"
    write_obj(path, V, F)
    return path, V, F


def test_cli_cuts_packs_and_writes_only_what_it_certified(tmp_path, capsys):
    src, V, F = helicoid_obj(tmp_path)
    out, rep = tmp_path / "o.obj", tmp_path / "r.json"
    assert cli.main(["unwrap", str(src), "-o", str(out), "--report", str(rep)]) == 0
    stdout = capsys.readouterr().out
    assert "1 overlapping (1 cut along" in stdout and "0 overlapping island pair(s)" in stdout
    mesh = load_mesh(out)
    uv = mesh.corner_uv                                   # as the OBJ stores them
    assert uv is not None and np.isfinite(uv).all()
    assert uv.min() >= 0 and uv.max() <= 1
    assert len(overlapping_triangle_pairs(uv)) == 0
    D, flipped = distortion_and_flips(V, F, uv)
    report = json.loads(rep.read_text())
    (isl,) = report["islands"]
    assert isl["status"] == "certified" and isl["overlap_free"] is True and isl["pieces"] >= 2
    assert isl["crossings"] > 0 and len(isl["cut_edges"]) == report["summary"]["cut_edges"]
    assert not flipped.any() and np.isclose(isl["max_distortion"], D.max(), rtol=1e-9)
    assert report["summary"]["layout_overlaps"] == 0 and report["layout_overlaps"] == []
    # the cut edges are where the stored UVs are discontinuous
    seams = {tuple(sorted(e)) for e in mesh.uv_seams().tolist()}
    assert {tuple(sorted(e)) for e in isl["cut_edges"]} <= seams


def test_cli_no_pack_and_overlap_fail(tmp_path, capsys):
    src, V, F = helicoid_obj(tmp_path)
    out = tmp_path / "o.obj"
    assert cli.main(["unwrap", str(src), "-o", str(out), "--no-pack"]) == 0
    uv = load_mesh(out).corner_uv
    assert np.isclose(uv.reshape(-1, 2).min(axis=0), 0).all()    # pieces at (0, 0), overlapping
    assert "(not packed)" in capsys.readouterr().out
    assert cli.main(["unwrap", str(src), "-o", str(out), "--overlap", "fail"]) == 1
    err = capsys.readouterr().err
    assert "not written" in err and "crosses itself" in err
    assert load_mesh(out).corner_uv is None                     # nothing stored


def test_batch_entry_and_caption_come_from_the_stored_uvs(tmp_path):
    V, F = helicoid_ribbon()
    options = {**cli.solver_kwargs(cli.build_parser().parse_args(["batch", "x", "-o", "y"])),
               "pack": True, "cut": True, "margin": 0.01}
    res = batch.unwrap_job(batch.Job("helicoid", V, F), options)
    e = res.entry
    assert e["status"] == "certified" and e["overlapping"] == 1 and e["cut_edges"] > 0
    D, flipped = distortion_and_flips(V, F, res.corner_uv)
    assert np.isclose(e["max_distortion"], D.max(), rtol=1e-9) and not flipped.any()
    assert "overlapping island(s) cut" in batch.caption(e, options)
    # without layout options (the Blender script packs itself): nothing cut, the overlap fails
    plain = batch.unwrap_job(batch.Job("helicoid", V, F), cli.solver_kwargs(
        cli.build_parser().parse_args(["batch", "x", "-o", "y"])))
    assert plain.entry["status"] == "failed" and "crosses itself" in plain.entry["message"]
    assert np.isnan(plain.corner_uv).all()
