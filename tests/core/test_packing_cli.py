"""The atlas packer from the command line and the batch: options, the report's ``pack`` object
and the PNG, checked against figures recomputed from the written OBJ."""
import json
from pathlib import Path

import numpy as np
import pytest

from bd_uv import cli
from bd_uv.meshio import load_mesh
from packing_sets import least_gap, texel_densities

DATA = Path(__file__).resolve().parents[1] / "data"


def grids(tmp_path, sizes=((5, 3), (8, 2), (3, 3), (6, 6), (2, 9), (4, 1))):
    """An OFF file of separate bent grids (one island each, scaled differently)."""
    Vs, Fs, n = [], [], 0
    for k, (a, b) in enumerate(sizes):
        x, y = np.meshgrid(np.linspace(0, a, a + 1), np.linspace(0, b, b + 1), indexing="ij")
        V = np.c_[x.ravel(), y.ravel(), 0.1 * np.sin(x.ravel())] * (1 + 0.3 * k)
        i = (np.arange(a)[:, None] * (b + 1) + np.arange(b)[None, :]).ravel()
        F = np.r_[np.c_[i, i + b + 1, i + b + 2], np.c_[i, i + b + 2, i + 1]]
        Vs.append(V)
        Fs.append(F + n)
        n += len(V)
    V, F = np.concatenate(Vs), np.concatenate(Fs)
    path = tmp_path / "grids.off"
    with open(path, "w") as fh:
        fh.write(f"OFF\n{len(V)} {len(F)} 0\n")
        fh.writelines(f"{x!r} {y!r} {z!r}\n" for x, y, z in V.tolist())
        fh.writelines(f"3 {a} {b} {c}\n" for a, b, c in F)
    return path, V, F


@pytest.mark.parametrize("seconds", ["auto", "0.5", "0"])
def test_unwrap_packs_with_the_options_and_reports_the_layout(tmp_path, capsys, seconds):
    src, V, F = grids(tmp_path)
    out, rep, png = tmp_path / "g.obj", tmp_path / "g.json", tmp_path / "g.png"
    code = cli.main(["unwrap", str(src), "-o", str(out), "--seams", "none", "--bound", "3",
                     "--resolution", "512", "--padding", "8", "--rotate", "90",
                     "--pack-seconds", seconds, "--report", str(rep), "--png", str(png)])
    assert code == 0
    assert "packed: coverage" in capsys.readouterr().out
    pack = json.loads(rep.read_text())["pack"]
    assert {"seconds", "coverage", "resolution", "padding_px", "least_gap_px",
            "tiles"} <= set(pack)
    assert pack["certified"] and pack["resolution"] == 512 and pack["padding_px"] == 8
    assert pack["tiles"] == [1001] and pack["rotate"] == "90" and pack["seconds"] > 0
    uv = load_mesh(out).corner_uv
    lab = np.repeat(np.arange(6), [2 * a * b for a, b in
                                   ((5, 3), (8, 2), (3, 3), (6, 6), (2, 9), (4, 1))])
    assert uv.min() >= 4 / 512 * (1 - 1e-6) and uv.max() <= 1 - 4 / 512 * (1 - 1e-6)
    e1, e2 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    area = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    assert (area > 0).all() and pack["coverage"] == pytest.approx(area.sum(), rel=1e-4)
    gap = least_gap(uv, lab, reach=20 / 512) * 512
    assert gap >= 8 * (1 - 1e-6) and pack["least_gap_px"] == pytest.approx(gap, rel=1e-4)
    d = texel_densities(V, F, uv, lab)
    assert np.allclose(d, d[0], rtol=1e-5)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("args, words", [
    (["--udim"], "UDIM tiles need a texel density"),
    (["--padding", "-2"], "padding must be"),
    (["--resolution", "4"], "resolution must be"),
    (["--pack-seconds", "-1"], "solve_seconds must be"),
])
def test_bad_packing_options_fail_before_solving(tmp_path, capsys, args, words):
    src, _, _ = grids(tmp_path)
    out = tmp_path / "g.obj"
    assert cli.main(["unwrap", str(src), "-o", str(out), "--seams", "none", *args]) == 2
    assert words in capsys.readouterr().err
    assert not out.exists()


def test_pack_seconds_takes_auto_or_a_number(tmp_path, capsys):
    src, _, _ = grids(tmp_path)
    out = tmp_path / "g.obj"
    with pytest.raises(SystemExit) as done:      # argparse's own exit for a value of bad type
        cli.main(["unwrap", str(src), "-o", str(out), "--pack-seconds", "soon"])
    assert done.value.code == 2
    assert "not a number of seconds nor auto: 'soon'" in capsys.readouterr().err
    assert not out.exists()


def test_batch_entry_carries_the_pack_object(tmp_path):
    src, _, _ = grids(tmp_path)
    outdir = tmp_path / "out"
    code = cli.main(["batch", str(src), "-o", str(outdir), "--seams", "none", "--bound", "3",
                     "--padding", "2", "--jobs", "1"])
    assert code == 0
    report = json.loads((outdir / "report.json").read_text())
    entry = report["items"][0]
    pack = entry["pack"]
    assert pack["certified"] and pack["padding_px"] == 2 and pack["least_gap_px"] >= 2


def test_a_texel_density_too_small_to_store_says_so_and_writes_nothing(tmp_path, capsys):
    """Found by the CLI fuzz contract: at 1e-9 texels per unit every chart is about 1e-11 of the
    square across; its stored UVs cannot be certified, and the message said only "loop(s) wound
    the wrong way". It now names the island's size and what to change."""
    src = tmp_path / "nefertiti.off"
    src.write_bytes((DATA / "nefertiti.off").read_bytes())
    out = tmp_path / "n.obj"
    before = src.read_bytes()
    rc = cli.main(["unwrap", str(src), "-o", str(out), "--seams", "none",
                   "--texel-density", "1e-9"])
    err = capsys.readouterr().err
    assert rc == 1 and not out.exists() and src.read_bytes() == before
    line = next(x for x in err.splitlines() if "island 0" in x)
    width = float(line.split("the island is ")[1].split(" ")[0])
    assert 0 < width < 1e-9 and "raise the texel density" in line
