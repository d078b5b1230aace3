"""The write paths (``python -m bd_uv unwrap`` and the batch's per-file path) store only islands
certified as stored: overlapping islands cut, packed into the unit square, report = measurement."""
import json

import numpy as np
import pytest

from bd_uv import batch, cli
from bd_uv.meshio import load_mesh, write_obj
from helpers import same_certificate
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
    # the mesh's own islands (no seams added: with the default, --seams needed, the search
    # gives the ribbon charts instead, below)
    assert cli.main(["unwrap", str(src), "-o", str(out), "--report", str(rep),
                     "--seams", "none"]) == 0
    stdout = capsys.readouterr().out
    assert "1 overlapping (1 cut along" in stdout and "0 overlapping island pair(s)" in stdout
    # unwrap() cut the ribbon: its pieces are islands of their own, naming the cut
    mesh = load_mesh(out)
    uv = mesh.corner_uv                                   # as the OBJ stores them
    assert uv is not None and np.isfinite(uv).all()
    assert uv.min() >= 0 and uv.max() <= 1
    assert len(overlapping_triangle_pairs(uv)) == 0
    D, flipped = distortion_and_flips(V, F, uv)
    report = json.loads(rep.read_text())
    pieces = report["islands"]
    assert len(pieces) >= 2
    assert all(p["status"] == "certified" and p["overlap_free"] is True for p in pieces)
    assert all("cut" in p["flags"] and p["cut_from"] == 0 for p in pieces)
    isl = pieces[0]
    assert len(isl["cut_edges"]) > 0
    assert not flipped.any()
    assert np.isclose(max(p["max_distortion"] for p in pieces), D.max(), rtol=1e-9)
    assert report["summary"]["layout_overlaps"] == 0 and report["layout_overlaps"] == []
    # the cut edges are where the stored UVs are discontinuous
    seams = {tuple(sorted(e)) for e in mesh.uv_seams().tolist()}
    assert {tuple(sorted(e)) for e in isl["cut_edges"]} <= seams


def test_cli_needed_gives_an_overlapping_island_the_searchs_charts(tmp_path, capsys):
    """The default seams (needed): the ribbon, whose map lies over itself at C = 5, goes to the
    seam search rather than being cut along whatever edges separate the overlap: charts at
    C = 2 with seams added, none flagged cut, overlap-free as stored."""
    src, V, F = helicoid_obj(tmp_path)
    out, rep = tmp_path / "o.obj", tmp_path / "r.json"
    assert cli.main(["unwrap", str(src), "-o", str(out), "--report", str(rep)]) == 0
    report = json.loads(rep.read_text())
    assert len(report["seams_added"]) > 0 and len(report["islands"]) >= 2
    assert all(p["status"] == "certified" and "cut" not in p["flags"]
               for p in report["islands"])
    uv = load_mesh(out).corner_uv
    assert len(overlapping_triangle_pairs(uv)) == 0
    D, flipped = distortion_and_flips(V, F, uv)
    assert not flipped.any() and D.max() <= 2.0 * (1 + 1e-6)


def test_cli_no_pack_and_overlap_fail(tmp_path, capsys):
    src, V, F = helicoid_obj(tmp_path)
    out = tmp_path / "o.obj"
    assert cli.main(["unwrap", str(src), "-o", str(out), "--no-pack"]) == 0
    uv = load_mesh(out).corner_uv
    assert np.isclose(uv.reshape(-1, 2).min(axis=0), 0).all()    # pieces at (0, 0), overlapping
    assert "(not packed)" in capsys.readouterr().out
    before = out.read_bytes()
    assert cli.main(["unwrap", str(src), "-o", str(out), "--overlap", "fail"]) == 1
    err = capsys.readouterr().err
    assert "lie over themselves" in err and "crosses itself" in err
    assert out.read_bytes() == before        # nothing certified: the file at -o is left as it was
    fresh = tmp_path / "fresh.obj"
    assert cli.main(["unwrap", str(src), "-o", str(fresh), "--overlap", "fail"]) == 1
    assert not fresh.exists()                                   # nothing stored


def test_batch_entry_and_caption_come_from_the_stored_uvs(tmp_path):
    V, F = helicoid_ribbon()
    options = {**cli.solver_kwargs(cli.build_parser().parse_args(["batch", "x", "-o", "y"])),
               "pack": True, "cut": True, "margin": 0.01}
    res = batch.unwrap_job(batch.Job("helicoid", V, F), options)
    e = res.entry
    assert e["status"] == "certified" and len(e["islands"]) >= 2   # unwrap() cut the ribbon
    D, flipped = distortion_and_flips(V, F, res.corner_uv)
    assert np.isclose(e["max_distortion"], D.max(), rtol=1e-9) and not flipped.any()
    # refusing the cut: the overlapping island fails and nothing is stored
    refused = batch.unwrap_job(batch.Job("helicoid", V, F), {**options, "cut": False})
    assert refused.entry["status"] == "failed" and "lie over themselves" in str(refused.entry)
    assert np.isnan(refused.corner_uv).all()


def _bumpy_grids(n=9, copies=2):
    """``copies`` bumpy n x n grids side by side: that many disk islands."""
    g = np.linspace(0.0, 1.0, n)
    x, y = np.meshgrid(g, g)
    V0 = np.c_[x.ravel(), y.ravel(), 0.2 * np.sin(3 * x.ravel()) * np.cos(2 * y.ravel())]
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1))
    a = (j * n + i).ravel()
    F0 = np.r_[np.c_[a, a + 1, a + n + 1], np.c_[a, a + n + 1, a + n]]
    V = np.concatenate([V0 + [2.0 * c, 0, 0] for c in range(copies)])
    F = np.concatenate([F0 + c * len(V0) for c in range(copies)]).astype(np.int64)
    return V, F


def test_stored_layout_reuses_the_unwraps_certificates_and_they_are_the_measured_ones():
    """The unwrap keeps the certificates its overlap check measured on the UVs it returns; the
    layout takes them instead of measuring the same UVs again, with the same outcome."""
    import dataclasses

    import bd_uv
    from bd_uv.certificate import certify_islands
    from bd_uv.layout import stored_layout

    V, F = _bumpy_grids()
    res = bd_uv.unwrap(V, F, bound=5.0)
    assert res.certified and res.certificates is not None
    assert len(res.certificates) == len(res.islands) == 2
    again = certify_islands(V, F, res.corner_uv, res.face_island,
                            [r.bound_certified for r in res.islands])
    D, flipped = distortion_and_flips(V, F, res.corner_uv)
    for kept, measured, r in zip(res.certificates, again, res.islands):
        assert same_certificate(kept, measured)
        assert kept.overlap_free and kept.certified and kept.flipped == 0
        assert kept.max_distortion == pytest.approx(D[r.faces].max(), rel=1e-9)
    assert not flipped.any()
    reused = stored_layout(V, F, res, pack=True, dtype=np.float32)
    fresh = stored_layout(V, F, dataclasses.replace(res, certificates=None), pack=True,
                          dtype=np.float32)
    for got, want in ((reused.unwrapped, fresh.unwrapped),
                      (reused.certificates, fresh.certificates)):
        assert len(got) == len(want) and all(map(same_certificate, got, want))
    assert np.array_equal(reused.corner_uv, fresh.corner_uv)


def test_an_unwrap_that_cut_an_island_keeps_no_certificates():
    V, F = helicoid_ribbon()
    import bd_uv

    res = bd_uv.unwrap(V, F)
    assert any("cut" in r.flags for r in res.islands)
    assert res.certificates is None


def test_uvs_stored_with_v_down_keep_1_minus_v_exact_in_float32():
    """``layout.as_stored``: for a format storing 1 - v (glTF) in float32, v is put on float32's
    grid in [0.5, 1), so the file's 1 - v is exact and the UVs certified are the file's; u, and
    every coordinate without ``v_down``, are float32's own rounding."""
    from bd_uv.layout import as_stored
    rng = np.random.default_rng(3)
    uv = rng.random((1000, 3, 2)) * [1.0, 1.0]
    uv[:10, :, 1] = rng.random((10, 3)) * 1e-6            # near v = 0: float32 is finer there
    uv[10:20, :, 1] += 1.0                                 # a UDIM row above
    s = as_stored(uv, np.float32, v_down=True)
    assert np.array_equal(s[..., 0], uv[..., 0].astype(np.float32))
    v32 = s[..., 1].astype(np.float32)
    assert np.array_equal(v32.astype(np.float64), s[..., 1])              # float32 values
    flipped = (1.0 - v32.astype(np.float64)).astype(np.float32)           # what glTF holds
    assert np.array_equal(1.0 - flipped.astype(np.float64), s[..., 1])   # read back exactly
    assert np.abs(s[:10] - uv[:10]).max() <= 2.0 ** -25        # half a grid step near 0
    assert np.abs(s - uv).max() <= 2.0 ** -23                  # float32 steps in [1, 2)
    plain = uv.astype(np.float32).astype(np.float64)
    assert np.array_equal(as_stored(uv, np.float32), plain)
    assert not np.array_equal(1.0 - (1.0 - plain[..., 1]).astype(np.float32), plain[..., 1])
    assert np.array_equal(as_stored(uv, np.float64, v_down=True), uv)


@pytest.mark.parametrize("seed", range(4))
def test_island_pairs_meeting_are_found_in_bounded_chunks(seed):
    # segments of 25 groups, short and long, some sharing ends or lying along each other, asked
    # of the tree a few at a time (chunk 50 candidates): the same pairs of groups as every
    # pair of segments tested by GEOS
    import shapely
    from bd_uv.segments import group_pairs_touching
    rng = np.random.default_rng(seed)
    p = rng.random((400, 2)) * 4
    q = p + rng.normal(scale=rng.choice([0.05, 0.4], 400)[:, None], size=(400, 2))
    q[:40] = p[40:80]                            # shared ends
    p[80:100], q[80:100] = p[100:120], p[100:120] + 0.5 * (q[100:120] - p[100:120])
    group = rng.integers(0, 25, 400)
    lines = shapely.linestrings(np.stack([p, q], axis=1))
    i, j = np.triu_indices(400, 1)
    meet = shapely.intersects(lines[i], lines[j]) & (group[i] != group[j])
    a, b = group[i[meet]], group[j[meet]]
    want = np.unique(np.stack([np.minimum(a, b), np.maximum(a, b)], 1), axis=0)
    for chunk in (50, 10 ** 6):
        got = group_pairs_touching(p, q, group, chunk=chunk)
        assert np.array_equal(got, want)
