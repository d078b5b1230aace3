"""Fuzzing the polygon contract: polygon meshes in mesh and scene files through
``python -m bd_uv unwrap`` and ``batch``, run in process through ``bd_uv.cli.main``.

Each example builds a sheet of random polyomino polygons (concave, corners in a line along their
straight sides; flat, tilted, curved or folded; corners jittered off their lines or not) with
parts beside it (a random star-shaped n-gon, one with corners added on its sides, a corner
repeated, two corners at one place, a polygon of no area, a face of no area hanging on the sheet
or at a point, a self-crossing quad, a spiral polygon, two triangles), writes it as an OBJ
(mixed records, CRLF, negative indices, continued lines, tabs, a byte order mark, old ``vt``,
``vn``), a USD stage, a binary or ASCII PLY of polygons, a binary PLY of triangle strips
(degenerate joins, -1 restarts, short strips) or an ASCII or binary STL, damages it or not
(truncated, a flipped byte, an index out of range, a NaN), and runs ``unwrap`` or ``batch``
(``polygon_files.py`` builds them).

For every example: an exit code 0, 1 or 2 and no traceback; the input byte-identical; a run
that writes nothing exits non-zero and says why. A file written is certified again from the file
as written by this test's own code: each face with UVs turning the right way, its distortion
(numpy SVD) within the reported bound, no two UV triangles overlapping (an exact test), every
UV in the unit square; faces of no area counted by the report; each polygon of four or more
corners laid out as a disk (the triangles it is certified on use each of its sides once and each
diagonal twice, opposite ways), and, flat and simple in space, tiled by them (every triangle
turning with it, their areas its area). An undamaged file keeps its mesh: an OBJ written back
keeps every record but ``vt`` and ``f`` byte for byte and each face's vertex and normal indices
(a polygon whole, or as its triangles where the report says so); a stage its polygons; a PLY,
STL or strip file's triangles are the ones it holds (each polygon's ``n - 2``, strips as this
test reads them). Triangles of a polygon are the product's (``bd_uv.polygons.triangulate``);
this test checks they tile the polygon, rather than choosing its own.

CI-friendly: 12 examples; ``BD_UV_FUZZ_EXAMPLES=2000`` (or ``bash scripts/fuzz_deep.sh``) runs
deeper.
"""
import contextlib
import io
import os
import pathlib

import numpy as np
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from artist_obj import read_faces, records
from bd_uv.cli import main
from bd_uv.polygons import triangulate
from helpers import float32_flat, reference_distortion, reference_jacobians
from overlap_shapes import overlapping_triangle_pairs
from polygon_files import (EXTRAS, TRIANGLE_EXTRAS, build, obj_bytes, ply_ascii_faces,
                           ply_binary_faces, ply_strips, read_strips, stl_bytes, strips_of,
                           usda_write)
from unwrap_contract import in_fresh_dir, strict_json, with_examples

FLAT = 1e-3
EXAMPLES = int(os.environ.get("BD_UV_FUZZ_EXAMPLES", "12"))
FORMATS = ("obj", "obj", "usda", "ply", "ply ascii", "strips", "stl", "stl binary")
SUFFIX = {"obj": ".obj", "usda": ".usda", "ply": ".ply", "ply ascii": ".ply", "strips": ".ply",
          "stl": ".stl", "stl binary": ".stl"}
STYLE = ("crlf", "negative", "continued", "tabs", "bom", "old_vt", "vt_corner", "normals",
         "records", "comments")
DAMAGES = ("truncated", "flipped byte", "index out of range", "nan", "bad face")
BAD_FACES = (b"f 1 2", b"f 0 1 2", b"f 1 2 -99999", b"f 1/9999 2/9999 3/9999", b"f a b c",
             b"f 1 1 1", b"f 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 2 1", b"f",
             b"f 1//1 2//1 3//1", b"f 1/1 2 3")


@st.composite
def scenarios(draw):
    fmt = draw(st.sampled_from(FORMATS))
    triangles = fmt in ("strips", "stl", "stl binary")
    nx, ny = draw(st.integers(1, 5)), draw(st.integers(1, 4))
    style = {k: draw(st.booleans()) for k in STYLE} if fmt == "obj" else None
    seams = ["needed", "needed", "none", "auto"] + (["uv"] if style and style["old_vt"] else [])
    return dict(
        fmt=fmt, seed=draw(st.integers(0, 2 ** 32 - 1)),
        sheet=(nx, ny, draw(st.integers(0, 3 * nx * ny))),
        shape=draw(st.sampled_from(["flat", "flat", "tilted", "curved", "folded"])),
        jitter=draw(st.sampled_from([0.0, 0.0, 0.05, 0.2])),
        extras=draw(st.lists(st.sampled_from(TRIANGLE_EXTRAS if triangles else EXTRAS),
                             max_size=3, unique=True)),
        style=style, joins=draw(st.sampled_from(["degenerate", "restart"])),
        big=draw(st.booleans()),
        runner=draw(st.sampled_from(["unwrap", "unwrap", "batch"] if fmt[:3] != "stl"
                                    else ["unwrap", "batch"])),
        seams=draw(st.sampled_from(seams)),
        bound=draw(st.sampled_from([None, None, "1.5", "3"])),
        overlap=draw(st.sampled_from(["cut", "cut", "fail"])),
        damage=draw(st.sampled_from([None] * 8 + list(DAMAGES))),
        at=draw(st.floats(0.0, 0.999)))


def make_input(sc, path):
    """Write the scenario's file at ``path``: returns (the ``Part``, the triangles a strip file
    draws or None)."""
    rng = np.random.default_rng(sc["seed"])
    fmt = sc["fmt"]
    m = build(rng, sc["sheet"], sc["shape"], sc["extras"], sc["jitter"],
              triangles=fmt in ("strips", "stl", "stl binary"))
    drawn = None
    if fmt == "obj":
        data = obj_bytes(m, rng, sc["style"])
    elif fmt == "usda":
        usda_write(path, m)
        data = path.read_bytes()
    elif fmt == "ply":
        data = ply_binary_faces(m.V, m.polys, big=sc["big"])
    elif fmt == "ply ascii":
        data = ply_ascii_faces(m.V, m.polys)
    elif fmt == "strips":
        nx, ny, _ = sc["sheet"]
        strips, _ = strips_of(nx, ny, rng, sc["joins"])
        grid = 2 * nx * ny
        for p in m.polys[grid:]:                  # the extras: a strip of one triangle each
            strips.append(list(p) + ([-1] if rng.random() < 0.5 else []))
        drawn = read_strips(strips)
        data = ply_strips(m.V, strips)
    else:
        data = stl_bytes(m.V, np.array(m.polys), binary=fmt == "stl binary")
    data = damage(sc, data)
    path.write_bytes(data)
    return m, drawn


def damage(sc, data):
    kind, at = sc["damage"], sc["at"]
    if kind == "truncated":
        return data[:int(at * len(data))]
    if kind == "flipped byte" and data:
        b = bytearray(data)
        b[int(at * len(b))] ^= 0x5A
        return bytes(b)
    if kind == "index out of range":
        if sc["fmt"] == "obj":
            return data + b"f 1 2 99999\n"
        if sc["fmt"] == "usda":
            return data.replace(b"faceVertexIndices = [0,", b"faceVertexIndices = [99999,", 1)
        if sc["fmt"] in ("ply", "strips") and len(data) >= 4:
            # the last int of the file: a vertex id of the last face or strip
            return data[:-4] + (b"\x00\x00\x01\x7f" if sc.get("big") and sc["fmt"] == "ply"
                                else b"\x7f\x01\x00\x00")
        if sc["fmt"] == "ply ascii":
            return data.rstrip(b"\n") + b"0\n"          # the last corner id x 10 (+ 0)
    if kind == "bad face" and sc["fmt"] == "obj":   # a record the exporter got wrong
        return data + b"\n" + BAD_FACES[int(at * len(BAD_FACES))] + b"\n"
    if kind == "nan":
        if sc["fmt"] in ("obj", "ply ascii", "stl"):
            i = data.find(b"0.0")
            return data if i < 0 else data[:i] + b"nan" + data[i + 3:]
        if sc["fmt"] == "usda":
            return data.replace(b"points = [(0,", b"points = [(nan,", 1)
    return data


def expect_certified(sc):
    """Whether the scenario's file must be certified whole (exit 0): undamaged, at the default
    bound, overlaps cut, seams added where needed or searched. Not a stage holding the spiral:
    the cut that lays it flat runs through the polygon, and one UV per face-vertex cannot
    hold it (a limit of the format, said as the islands failing as stored)."""
    return (sc["damage"] is None and sc["bound"] is None and sc["overlap"] == "cut"
            and sc["seams"] in ("needed", "auto")
            and not (sc["fmt"] == "usda" and "spiral" in sc["extras"]))


def tree(root):
    return {str(p.relative_to(root)): "dir" if p.is_dir() else p.read_bytes()
            for p in sorted(pathlib.Path(root).rglob("*"))}


def run(sc, root):
    """Run the scenario's command on the file at ``root/in/``: (exit, stdout, stderr, output
    path, report path)."""
    inp = root / "in" / ("in" + SUFFIX[sc["fmt"]])
    out_suffix = ".usda" if sc["fmt"] == "usda" else ".obj"
    rep = root / "r.json"
    if sc["runner"] == "unwrap":
        out = root / "o" / ("out" + out_suffix)
        argv = ["unwrap", str(inp), "-o", str(out), "--report", str(rep)]
    else:
        out = root / "o" / ("in" + out_suffix)
        argv = ["batch", str(inp), "-o", str(root / "o"), "--report", str(rep), "--jobs", "1"]
    if sc["seams"] != "needed":
        argv += ["--seams", sc["seams"]]
    if sc["bound"]:
        argv += ["--bound", sc["bound"]]
    if sc["overlap"] != "cut":
        argv += ["--overlap", sc["overlap"]]
    so, se = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(so), contextlib.redirect_stderr(se):
        try:
            rc = main(argv)
        except SystemExit as exc:
            rc = exc.code
    return argv, rc, so.getvalue(), se.getvalue(), inp, out, rep


def report_of(sc, rep):
    """(bound, zero-area faces counted, polygons said to be written as triangles, whether every
    island or mesh certified) from the report."""
    r = strict_json(rep.read_text())
    if sc["runner"] == "batch":
        entries = r["items"]
    elif sc["fmt"] == "usda":
        entries = r["meshes"]
    else:
        entries = [dict(r, output=True, bound_certified=max(
            [i["bound_certified"] for i in r["islands"] if i["status"] == "certified"],
            default=np.nan))]
    bound = max((e["bound_certified"] for e in entries if e.get("output")), default=np.nan)
    zero = sum(e.get("zero_area_faces", 0) for e in entries)
    split = sum(e.get("polygons_as_triangles", 0) for e in entries)
    return bound, zero, split


# ---------------------------------------------------------------------------------------------
# the file as written, read by this test

def unmarked(data):
    """OBJ bytes without a UTF-8 byte order mark (``read_faces`` reads records from byte 0)."""
    return data[3:] if data.startswith(b"\xef\xbb\xbf") else data


def obj_polygons(data):
    """(V, VT, [corner list of (v, vt or None)] per ``f`` record) of OBJ bytes."""
    V, VT, faces = read_faces(unmarked(data))
    return V, VT, [[(c[0], c[1]) for c in corners] for corners, _ in faces]


def usd_polygons(path):
    """(V, [(v, uv row)] per polygon, uv per face-vertex or None) of the stage's one mesh."""
    from pxr import Usd, UsdGeom
    stage = Usd.Stage.Open(str(path))
    meshes = [p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    assert len(meshes) == 1
    mesh = UsdGeom.Mesh(meshes[0])
    V = np.asarray(mesh.GetPointsAttr().Get(), np.float64)
    counts = np.asarray(mesh.GetFaceVertexCountsAttr().Get(), np.int64)
    idx = np.asarray(mesh.GetFaceVertexIndicesAttr().Get(), np.int64)
    pv = UsdGeom.PrimvarsAPI(meshes[0]).GetPrimvar("st")
    uv = None
    if pv and pv.HasValue():
        assert pv.GetInterpolation() == UsdGeom.Tokens.faceVarying
        uv = np.asarray(pv.Get(), np.float64)
        if pv.IsIndexed():
            uv = uv[np.asarray(pv.GetIndices())]
        assert len(uv) == len(idx)
    start = np.concatenate([[0], np.cumsum(counts)])
    polys = [[(int(idx[k]), k if uv is not None else None) for k in range(a, b)]
             for a, b in zip(start[:-1], start[1:])]
    return V, uv, polys


def check_certified(V, UV, polys, bound, zero, packed=True, flat_simple=None, precision=None):
    """The polygons (lists of (vertex, uv row or None)) with UVs certified as written: see the
    module's docstring. ``flat_simple``: per polygon, whether it is flat and simple in space (its
    triangles must tile it there); None: unknown. ``precision``: the points' (a stage's
    float32), which the product triangulates at. Returns whether every face has UVs."""
    polys = [p for p in polys if len(p) >= 3]
    counts = np.array([len(p) for p in polys], np.int64)
    vids = np.array([v for p in polys for v, _ in p], np.int64)
    uvid = np.array([-1 if t is None else t for p in polys for _, t in p], np.int64)
    if not len(polys):
        return True
    T, poly, _ = triangulate(V, counts, vids, precision=precision)
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    tv, tt = vids[T], uvid[T]
    has = (tt >= 0).all(axis=1)
    # a polygon has UVs at all its corners or at none
    whole = np.bincount(poly, has, len(polys))
    assert ((whole == 0) | (whole == counts - 2)).all()
    if not has.any():
        return False
    uv = UV[tt[has]]
    assert np.isfinite(uv).all()
    flat = float32_flat(V, tv[has])
    with np.errstate(all="ignore"):   # a face of no area has no finite Jacobian
        P = V[tv[has]]
        twice = np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
        longest = np.max(np.sum((P - np.roll(P, -1, axis=1)) ** 2, axis=2), axis=1)
        fine = twice > 1e-14 * longest         # else no 2D frame to measure it in
        fine[fine] = np.isfinite(reference_jacobians(V, tv[has][fine], uv[fine])).all(
            axis=(1, 2))
        D, flipped = np.full(len(P), np.inf), np.ones(len(P), bool)
        D[fine], flipped[fine] = reference_distortion(V, tv[has][fine], uv[fine])
    bad = flipped | ~(D <= bound * (1 + 1e-9))
    assert not (bad & ~flat).any(), (D[~flat].max(), flipped[~flat].sum(), bound)
    assert bad[flat].sum() <= zero, (bad[flat].sum(), zero)
    # a face on the same three vertices in the same turn as an earlier one (a damaged file's
    # indices can make one) is a duplicate: it takes its twin's UVs (the repair's rule), lying
    # on it. The same three the other way round is no duplicate (two bent polygons' fans can
    # both hold the sliver of their shared side): both are measured
    tri = tv[has]
    r = np.argmin(tri, axis=1)
    turned = np.take_along_axis(tri, (r[:, None] + np.arange(3)) % 3, axis=1)
    _, first, inv = np.unique(turned, axis=0, return_index=True, return_inverse=True)
    twin = first[inv.ravel()]
    dup = twin != np.arange(len(tri))
    for f, g in zip(np.flatnonzero(dup).tolist(), twin[dup].tolist()):
        at = {v: k for k, v in enumerate(tri[g].tolist())}
        assert np.array_equal(uv[f], uv[g][[at[v] for v in tri[f].tolist()]]), (f, g)
    if (~flat & ~dup).any():
        assert len(overlapping_triangle_pairs(uv[~flat & ~dup])) == 0
    if packed:
        assert uv.min() >= -1e-9 and uv.max() <= 1 + 1e-9, (uv.min(), uv.max())
    # each polygon of 4+ distinct corners: its triangles a disk of its sides and diagonals
    for p in np.flatnonzero(counts >= 4):
        n = int(counts[p])
        if len(set(vids[start[p]:start[p] + n].tolist())) < n:
            continue
        places = T[poly == p] - start[p]
        assert len(places) == n - 2
        edges = {}
        for a, b, c in places.tolist():
            for e in ((a, b), (b, c), (c, a)):
                edges[e] = edges.get(e, 0) + 1
        for (a, b), k in edges.items():
            assert k == 1, (p, places)
            side = (b - a) % n == 1
            assert side or edges.get((b, a)) == 1, (p, places)
        assert all(edges.get((i, (i + 1) % n)) == 1 for i in range(n)), (p, places)
        if flat_simple is not None and flat_simple[p]:
            Q = V[vids[start[p]:start[p] + n]]
            normal = np.cross(Q, np.roll(Q, -1, axis=0)).sum(axis=0)
            P = Q[places]
            twice = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]) @ normal
            nn = normal @ normal
            # a fan triangle may turn against its polygon by up to FLAT of its area (the
            # tolerance polygons.py documents: a corner float32 or a jitter moved a little off
            # its line keeps the fan; found by this contract, left so)
            assert (twice > -FLAT * nn).all(), (p, twice / nn)
            assert abs(twice.sum() - nn) <= 1e-6 * nn   # their areas add up to the polygon's
    return bool(has.all())


def assert_polygon_triangles(faces, polys):
    """The triangles ``faces`` are the polygons' ``polys``, ``n - 2`` each, each of its
    polygon's corners (in any order: trimesh writes a file's quads' first triangles, then
    their second ones): a perfect matching of triangles to polygons' places."""
    from scipy.sparse import csr_array
    from scipy.sparse.csgraph import maximum_bipartite_matching
    slots = [(p, k) for p, q in enumerate(polys) for k in range(len(q) - 2)]
    assert len(faces) == len(slots), (len(faces), len(slots))
    first = np.concatenate([[0], np.cumsum([len(q) - 2 for q in polys])])
    rows, cols = [], []
    for i, f in enumerate(faces):
        for p, q in enumerate(polys):
            if set(f) <= set(q):
                rows += [i] * (len(q) - 2)
                cols += range(first[p], first[p + 1])
    g = csr_array((np.ones(len(rows)), (rows, cols)), shape=(len(faces), len(slots)))
    match = maximum_bipartite_matching(g, perm_type="column")
    assert (match >= 0).all(), "a triangle of no polygon of the file"
    return np.searchsorted(first, match, side="right") - 1      # each triangle's polygon


def assert_tiles_in_space(V, faces, owner, polys, flat):
    """Each flat simple polygon's triangles (``owner``: each face's polygon) tile it: none
    turning against it by more than FLAT of its area, their areas its area."""
    faces = np.asarray(faces).reshape(-1, 3)
    for p, q in enumerate(polys):
        if not flat[p] or len(q) < 4:
            continue
        Q = V[q]
        normal = np.cross(Q, np.roll(Q, -1, axis=0)).sum(axis=0)
        P = V[faces[owner == p]]
        twice = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]) @ normal
        nn = normal @ normal
        assert (twice > -FLAT * nn).all(), (q, twice / nn)
        assert abs(twice.sum() - nn) <= 1e-6 * nn, (q, twice / nn)


def check_obj_kept(src, out, m, split):
    """An OBJ written back: every record but vt and f as it was, in order; each face's vertex
    and normal indices as written, the polygon whole or (``split`` of them) as its triangles."""
    a, b = src.read_bytes(), out.read_bytes()
    assert [r for k, r in records(a) if k not in ("vt", "f")] == \
        [r for k, r in records(b) if k not in ("vt", "f")]
    rest = read_faces(unmarked(b))[2]
    said = 0
    for (corners, text), poly in zip(read_faces(unmarked(a))[2], m.polys):
        assert [c[0] for c in corners] == poly
        got, rest = rest[0], rest[1:]
        if got[1] == text:
            continue
        said += 1
        n = len(text)
        tris = [got] + rest[:n - 3]
        rest = rest[n - 3:]
        assert all(len(t[1]) == 3 and set(t[1]) <= set(text) for t in tris), (text, tris)
    assert not rest and said == split


def check(sc, root):
    (root / "in").mkdir()
    (root / "o").mkdir()
    m, drawn = make_input(sc, root / "in" / ("in" + SUFFIX[sc["fmt"]]))
    before = tree(root / "in")
    argv, rc, stdout, stderr, inp, out, rep = run(sc, root)
    event(f"{sc['fmt']} {sc['damage'] or 'clean'}: exit {rc}")
    if rc and sc["damage"] is None:
        event(f"clean, exit {rc}: " + (stderr.strip().splitlines() or ["?"])[-1][:120])
    assert rc in (0, 1, 2), (rc, argv, stderr)
    assert "Traceback" not in stderr + stdout, stderr + stdout
    assert tree(root / "in") == before, "the input changed"
    if sc["runner"] == "unwrap":
        errors = [ln for ln in stderr.splitlines() if "error:" in ln]
        if rc == 2:
            assert len(errors) == 1, stderr
        elif rc == 1:
            assert errors, stderr
    if sc["damage"] is None:    # a valid file is never refused as a bad one
        assert rc != 2, (argv, stderr, stdout[-2000:])
    if expect_certified(sc):
        assert rc == 0, (argv, stderr, stdout[-2000:])
    written = out.exists()
    if not written:
        assert rc != 0, (argv, "exit 0 and nothing written")
        if sc["runner"] == "batch" and rep.exists():
            entry = strict_json(rep.read_text())["items"][0]
            # failed, or partial with the mesh kept as it was: says why
            assert entry["status"] != "certified" and not entry["output"], entry
            assert entry["error"] or entry["message"], entry
        return
    assert rc in (0, 1), (rc, stderr)
    bound, zero, split = report_of(sc, rep)
    clean = sc["damage"] is None
    if sc["fmt"] == "usda":
        V, UV, polys = usd_polygons(out)
        if clean:
            assert [[v for v, _ in p] for p in polys] == m.polys
    else:
        V, VT, polys = obj_polygons(out.read_bytes())
        UV = VT
        if clean:
            tol = 1e-12 if sc["fmt"] == "obj" else 1e-6
            if sc["fmt"][:3] != "stl":
                assert np.allclose(V, m.V, rtol=tol, atol=tol)
            faces = [[v for v, _ in p] for p in polys]
            if sc["fmt"] == "obj":
                check_obj_kept(inp, out, m, split)
            elif sc["fmt"] == "strips":
                assert faces == drawn.tolist()
            elif sc["fmt"][:3] == "stl":
                P = np.asarray(m.V, np.float32).astype(np.float64)[np.array(m.polys)]
                assert np.allclose(V[np.array(faces)], P, atol=1e-6)
            else:   # a PLY's polygons: triangles of each, tiling it
                owner = assert_polygon_triangles(faces, m.polys)
                assert_tiles_in_space(V, faces, owner, m.polys, m.flat)
    flat_simple = None
    if clean and len(polys) == len(m.polys) and all(len(p) == len(q) for p, q in
                                                    zip(polys, m.polys)):
        flat_simple = m.flat
    every = check_certified(V, UV, polys, bound, zero, flat_simple=flat_simple,
                            precision=np.float32 if sc["fmt"] == "usda" else None)
    if rc == 0:
        assert every, "exit 0 but faces written without UVs"


def scenario(**kw):
    """A scenario: a clean 2 x 2 flat sheet's OBJ through unwrap, with ``kw`` changed."""
    sc = dict(fmt="obj", seed=0, sheet=(2, 2, 0), shape="flat", jitter=0.0, extras=[],
              style=None, joins="degenerate", big=False, runner="unwrap", seams="needed",
              bound=None, overlap="cut", damage=None, at=0.0)
    sc.update(kw)
    if sc["fmt"] == "obj" and sc["style"] is None:
        sc["style"] = {k: False for k in STYLE}
    return sc


# Falsifying examples found by this contract, each kept; what each did before its fix:
FOUND = [
    # an ASCII PLY's concave polygon (an L of three cells) fanned by trimesh from its first
    # corner: a triangle outside the polygon (meshio now triangulates a PLY's polygons itself)
    scenario(fmt="ply ascii", seed=1, sheet=(2, 2, 4)),
    # a USD hexagon of two cells of a curved sheet, corners in a line that float32 moved off it:
    # its fan kept a triangle float32 cannot tell from a line, refused by the scene unwrap
    # (--seams none: the island failed, nothing written; polygons.triangulate's precision).
    # The contract lets --seams none fail an island with a face of no area, so this example
    # passed before the fix too: test_polygons' test_a_usd_polygon_has_no_triangle_float32_...
    # is its regression test
    scenario(fmt="usda", seed=7258, sheet=(1, 2, 1), shape="curved", extras=["star"],
             runner="batch", seams="none"),
    # a binary PLY of three quads, a hexagon and two triangles: as many bytes as six quads, so
    # trimesh read six quads of garbage ids without an error; refused as "vertex indices
    # outside 0..14" (meshio: a count other than its list's length goes to read_binary_ply)
    scenario(fmt="ply", seed=786366461, sheet=(5, 1, 1), shape="curved",
             extras=["zero-area point", "zero-area hanging"]),
    # a USD star with two corners at one place: the zero-area triangle between them left out,
    # the star fell into two islands meeting at a point, two UVs at one face-vertex: "fail as
    # stored", exit 1 (usd_mesh: such corners are one vertex for the unwrap)
    scenario(fmt="usda", seed=5, sheet=(1, 1, 0), extras=["same position"]),
    # a USD sheet with a face hanging on its side, float32 moving its third corner off the
    # side's line: --seams auto certified it in float64, the overlap cut made it a piece of its
    # own, which failed as stored: the mesh refused, exit 1 (seams.repaired: any such face is
    # left out at the stored precision, as --seams needed does)
    scenario(fmt="usda", seed=243337882, sheet=(5, 3, 5), shape="curved", jitter=0.2,
             extras=["zero-area hanging"], seams="auto"),
    # (the test's own) a flipped byte turned the byte order mark into a byte that is not UTF-8,
    # which the OBJ written keeps: artist_obj.records decoded record keys strictly
    scenario(style=dict({k: False for k in STYLE}, bom=True, records=True),
             damage="flipped byte"),
    # (the test's own) the first "v" flipped to ",": every positive index one vertex later, two
    # quads the same four vertices; the repair gives the duplicate its twin's UVs, which the
    # overlap test counted as an overlap
    scenario(sheet=(3, 1, 0), extras=["star"], damage="flipped byte",
             style=dict({k: False for k in STYLE}, negative=True)),
    # (the test's own) two bent polygons' fans both holding the sliver of their shared side:
    # the same three vertices the other way round, no duplicate
    scenario(seed=3, sheet=(3, 3, 5), shape="curved"),
    # (the test's own) an OBJ cut short inside a face's last normal index ("-11/-2/-"), which
    # bd-uv keeps as written (it reads no normals): artist_obj.read_faces read it as a number
    scenario(sheet=(2, 3, 2), damage="truncated", at=0.98828125,
             style=dict({k: False for k in STYLE}, negative=True, old_vt=True, vt_corner=True,
                        normals=True)),
]


@settings(max_examples=EXAMPLES, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(sc=scenarios())
@with_examples(FOUND)
def test_polygon_files_never_crash_or_write_an_uncertified_result(sc):
    in_fresh_dir(check, sc, "bd-uv-poly-fuzz-")
