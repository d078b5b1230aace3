"""The JSON reports hold plain Python values only, on numpy 1.26 and on numpy 2 (Blender 5.1+).

The standard json module writes ``np.float64`` (a float subclass) but raises on ``np.bool_`` and
``np.int64``, and numpy 2 reprs its scalars as ``np.float64(...)``: a numpy scalar left in a report
is a crash on one path or odd text on another. Each report is checked for exact types before it is
serialised, and a few of its figures are recomputed here from the written UVs.
"""
import json

import numpy as np

from bd_uv import cli
from bd_uv.layout import pack_summary
from bd_uv.packing import PackOptions, layout_certificate, pack_islands
from helpers import grid, reference_distortion

PLAIN = (str, int, float, bool, type(None))


def non_plain(obj, path="$"):
    """Where ``obj`` holds a value whose type is not exactly one the json module maps (numpy
    scalars and arrays included, though ``np.float64`` is a float): a list of paths and types."""
    t = type(obj)
    if t in PLAIN:
        return []
    if t in (list, tuple):
        return [p for i, x in enumerate(obj) for p in non_plain(x, f"{path}[{i}]")]
    if t is dict:
        return ([f"{path} key {k!r}: {type(k).__name__}" for k in obj if type(k) is not str]
                + [p for k, v in obj.items() for p in non_plain(v, f"{path}.{k}")])
    return [f"{path}: {t.__name__}"]


def bent_grids():
    """Three separate curved grids (one island each, of different sizes), (V, F)."""
    Vs, Fs, n = [], [], 0
    for k, (nx, ny) in enumerate(((7, 5), (5, 6), (9, 3))):
        V, F = grid(nx, ny, z=lambda x, y, k=k: 0.2 * np.sin(3 * x + k) * np.cos(2 * y))
        Vs.append(V * (1 + 0.4 * k) + [3.0 * k, 0, 0])
        Fs.append(F + n)
        n += len(V)
    return np.concatenate(Vs), np.concatenate(Fs)


def read_obj(path):
    """(V, F, corner_uv) of an OBJ with ``f v/vt`` faces, parsed here (not by bd_uv)."""
    v, vt, fv, ft = [], [], [], []
    for line in path.read_text().splitlines():
        p = line.split()
        if p and p[0] == "v":
            v.append([float(x) for x in p[1:4]])
        elif p and p[0] == "vt":
            vt.append([float(x) for x in p[1:3]])
        elif p and p[0] == "f":
            fv.append([int(t.split("/")[0]) - 1 for t in p[1:]])
            ft.append([int(t.split("/")[1]) - 1 for t in p[1:]])
    return np.array(v), np.array(fv), np.array(vt)[np.array(ft)]


def test_unwrap_report_is_plain_json_and_its_figures_are_the_written_uvs(tmp_path, monkeypatch):
    V, F = bent_grids()
    src, out, rep = tmp_path / "g.obj", tmp_path / "out.obj", tmp_path / "g.json"
    src.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in V.tolist())
                   + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F.tolist()))
    dumped = []
    real_dump = json.dump

    def dump(obj, fh, **kw):
        dumped.append(obj)
        return real_dump(obj, fh, **kw)

    monkeypatch.setattr(json, "dump", dump)
    code = cli.main(["unwrap", str(src), "-o", str(out), "--seams", "none", "--bound", "3",
                     "--resolution", "512", "--padding", "4", "--rotate", "90",
                     "--pack-seconds", "0", "--report", str(rep), "-q"])
    assert code == 0
    (report,) = dumped
    assert non_plain(report) == []
    # the standard module writes it whole (no NaN or inf either) and the file is that text
    text = json.dumps(report, allow_nan=False)
    assert json.loads(text) == json.loads(rep.read_text())
    islands, pack = report["islands"], report["pack"]
    assert [e["status"] for e in islands] == ["certified"] * 3
    # recomputed from the OBJ as written: faces, the worst distortion, no flip, the coverage
    V2, F2, uv = read_obj(out)
    assert np.array_equal(F2, F) and np.allclose(V2, V, rtol=0, atol=1e-15)
    assert sum(e["faces"] for e in islands) == len(F)
    D, flipped = reference_distortion(V, F, uv)
    assert not flipped.any()
    worst = max(e["max_distortion"] for e in islands)
    assert abs(worst - D.max()) <= 1e-9 * D.max()
    assert D.max() <= 3.0 * (1 + 1e-6)
    e1, e2 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    signed = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    assert (signed > 0).all() and pack["flipped_faces"] == 0
    assert pack["tiles"] == [1001] and ((uv >= 0) & (uv <= 1)).all()
    assert abs(pack["coverage"] - signed.sum()) <= 1e-5
    assert pack["resolution"] == 512 and pack["padding_px"] == 4.0


def test_pack_report_is_plain_json_and_its_figures_are_the_packed_uvs():
    V, F = bent_grids()
    # each grid's own xy as its chart (counter-clockwise, flip-free), labels by grid
    sizes = [2 * (nx - 1) * (ny - 1) for nx, ny in ((7, 5), (5, 6), (9, 3))]
    lab = np.repeat(np.arange(3), sizes)
    uv = V[F][:, :, :2].copy()
    options = PackOptions(resolution=256, padding_px=3.0, rotate="90", solve_seconds=0)
    packed = pack_islands(V, F, uv, lab, options)
    stored = packed.corner_uv.astype(np.float32)
    cert = layout_certificate(V, F, stored, packed.face_island, packed.tile, options.resolution,
                              options.padding_px)
    summary = pack_summary(packed, cert)
    assert non_plain(summary) == []
    again = json.loads(json.dumps(summary, allow_nan=False))
    assert again == json.loads(json.dumps(summary))
    assert summary["certified"] is True and summary["overlapping_pairs"] == 0
    # recomputed from the stored UVs: coverage (UV area over one tile) and the one texel density
    P = stored.astype(np.float64)
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    auv = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    assert (auv > 0).all() and summary["tiles"] == [1001]
    assert abs(summary["coverage"] - auv.sum()) <= 1e-5
    T = V[F]
    a3 = 0.5 * np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    own = packed.face_island
    density = np.sqrt(np.bincount(own, auv) / np.bincount(own, a3)) * options.resolution
    assert np.allclose(density, summary["texel_density"], rtol=1e-5)
