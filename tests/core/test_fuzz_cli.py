"""Fuzzing the command-line contract (issue 22): ``python -m bd_uv unwrap`` with random option
combinations, bad values and bad paths, run in process through ``bd_uv.cli.main``.

For every example: ``main`` returns an exit code (argparse's usage errors exit 2) and nothing else
escapes; no traceback; a non-zero exit says why on stderr (one "error:" line for a usage or input
error, one per failed island for exit 1); the input file is byte-identical afterwards; nothing is
written outside ``-o``, ``--report`` and ``--png`` (no temporary file left either); a run that
fails (exit 2, or exit 1 with no island certified) leaves the file at ``-o`` as it was (absent,
or the old bytes); a written OBJ keeps the input's faces, and its certified islands are
re-verified from the stored UVs by independent code (numpy SVD distortion within the reported
bound, no flipped face from signed areas, no two UV triangles overlapping by an exact test).

CI-friendly: 25 examples; ``BD_UV_FUZZ_EXAMPLES=2000`` (or ``bash scripts/fuzz_deep.sh``) runs
deeper.
"""
import contextlib
import io
import os
import pathlib
import re

import numpy as np
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from artist_obj import artist_obj, read_faces, records
from bd_uv.cli import main
from overlap_shapes import overlapping_triangle_pairs
from unwrap_contract import (DATA, distortion_and_flips, in_fresh_dir, read_off, strict_json,
                             with_examples)

EXAMPLES = int(os.environ.get("BD_UV_FUZZ_EXAMPLES", "25"))
V3, F3 = read_off(DATA / "three_peaks.off")


def small_patch(n_faces=60):
    """A small disk cut from three_peaks: faces reached breadth-first, vertices renumbered."""
    used, inv = np.unique(F3[:n_faces], return_inverse=True)
    return V3[used], inv.reshape(-1, 3)


PATCH = small_patch()
PATCH32 = (PATCH[0].astype(np.float32).astype(np.float64), PATCH[1])   # as the PLY stores it
# the patch as a PLY or OFF written face by face (a triangle soup): every vertex split
SOUP = (PATCH32[0][PATCH[1]].reshape(-1, 3), np.arange(3 * len(PATCH[1])).reshape(-1, 3))


def _quad_first(F):
    """The patch with its first face and a neighbour across an edge written as one quad (a, b,
    d, c): the faces a binary PLY with triangles and quads gives (Rhino), fan-triangulated."""
    a, b, c = F[0]
    g = next(i for i in range(1, len(F)) for j in range(3)
             if (F[i][j], F[i][(j + 1) % 3]) == (c, b))
    d = next(v for v in F[g] if v not in (b, c))
    rest = [f for i, f in enumerate(F.tolist()) if i not in (0, g)]
    return [[a, b, d, c]] + rest


QUADS = _quad_first(PATCH[1])       # as the binary PLY holds the faces
_q = QUADS[0]
MIXED = (PATCH32[0], np.array([[_q[0], _q[1], _q[2]], [_q[0], _q[2], _q[3]]] + QUADS[1:]))
STRIPS = (PATCH32[0], PATCH32[1].copy())   # the patch as strips of one triangle each
NAN_PATCH = (np.concatenate([[[np.nan, *PATCH[0][0, :2]]], PATCH[0][1:]]), PATCH[1])  # "v nan x y z"
TETRA = (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float),
         np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]))


def _floats(V):
    """Rows of Python floats: their repr is the number on numpy 1.26 and 2 alike (numpy 2's
    scalars repr as ``np.float64(...)``, which no mesh reader parses)."""
    return np.asarray(V, dtype=np.float64).tolist()


def obj_text(V, F, with_uv=False):
    V = _floats(V)
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in V]
    if with_uv:   # the 3D x, y as UVs: a planar projection, one UV per vertex (no UV seams)
        lines += [f"vt {x!r} {y!r}" for x, y, _ in V]
        lines += [f"f {a + 1}/{a + 1} {b + 1}/{b + 1} {c + 1}/{c + 1}" for a, b, c in F]
    else:
        lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in F]
    return "\n".join(lines) + "\n"


def off_text(V, F):
    return "OFF\n%d %d 0\n" % (len(V), len(F)) \
        + "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in _floats(V)) \
        + "".join(f"3 {a} {b} {c}\n" for a, b, c in F)


def ply_text(V, F):
    head = ("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
            "property float z\nelement face %d\nproperty list uchar int vertex_indices\n"
            "end_header\n" % (len(V), len(F)))
    return head + "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in _floats(V)) \
        + "".join(f"3 {a} {b} {c}\n" for a, b, c in F)


def stl_text(V, F):
    """An ASCII STL: every face's three corners written out."""
    rows = ["solid fuzz"]
    for f in F:
        rows += ["facet normal 0 0 1", "outer loop"]
        rows += [f"vertex {x!r} {y!r} {z!r}" for x, y, z in _floats(V[f])]
        rows += ["endloop", "endfacet"]
    return "\n".join(rows + ["endsolid fuzz"]) + "\n"


def binary_ply(V, faces):
    """A binary little-endian PLY, its face list of any lengths."""
    import struct
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nelement face %d\n"
            "property list uchar int vertex_indices\nend_header\n" % (len(V), len(faces)))
    return head.encode() + b"".join(struct.pack("<3f", *v) for v in _floats(V)) + b"".join(
        struct.pack("<B%di" % len(f), len(f), *f) for f in faces)


def strips_ply(V, F):
    """A binary PLY of triangle strips (a ``tristrips`` element, Cyberware's igea.ply): each
    face a strip of its own, ended by -1, so the triangles read are ``F`` as they are."""
    import struct
    ids = np.column_stack([F, np.full(len(F), -1)]).ravel().tolist()
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nelement tristrips 1\n"
            "property list int int vertex_indices\nend_header\n" % len(V))
    return head.encode() + b"".join(struct.pack("<3f", *v) for v in _floats(V)) + \
        struct.pack("<i%di" % len(ids), len(ids), *ids)


def spiral_part(first):
    """An object of one polygon, its fan from its first corner turning 900 degrees round it (a
    helix): cut through at a low bound, so the OBJ written holds it as its triangles. Its
    vertices are numbered from ``first`` (1-based)."""
    t = np.radians(np.arange(16) * 60.0)
    P = [[0.0, 0.0, 0.0]] + np.column_stack([np.cos(t), np.sin(t), 0.1 * np.arange(16)]).tolist()
    return ("o spiral\r\n" + "".join(f"v {x!r} {y!r} {z!r}\r\n" for x, y, z in P)
            + "f " + " ".join(str(first + i) for i in range(17)) + " # spiral\r\n").encode()


# An artist's OBJ (tests/core/artist_obj.py: quads, a pentagon, materials, objects, groups,
# smoothing, normals, comments, negative indices, a continued face, a split vertex, old vt, CRLF)
# with a spiral polygon after it: written back as its own text with only its UVs replaced
ARTIST, _ = artist_obj(*PATCH)
ARTIST += spiral_part(len(PATCH[0]) + 2)     # its vertices after the patch's and the copy


INPUTS = {   # name -> (file name, bytes or None for "no such file", or "dir")
    "patch.obj": ("in.obj", obj_text(*PATCH).encode()),
    "patch.obj with vt": ("in.obj", obj_text(*PATCH, with_uv=True).encode()),
    "artist.obj": ("in.obj", ARTIST),
    "patch.off": ("in.off", off_text(*PATCH).encode()),
    "patch.ply": ("in.ply", ply_text(*PATCH).encode()),
    "closed tetra.obj": ("in.obj", obj_text(*TETRA).encode()),
    "soup.ply": ("in.ply", ply_text(*SOUP).encode()),
    "strips binary.ply": ("in.ply", strips_ply(*PATCH32)),
    "soup.off": ("in.off", off_text(*SOUP).encode()),
    "nan vertex.obj": ("in.obj", obj_text(*PATCH).replace("v ", "v nan ", 1).encode()),
    "index out of range.obj": ("in.obj", (obj_text(*PATCH) + "f 1 2 9999\n").encode()),
    "truncated.obj": ("in.obj", obj_text(*PATCH).encode()[:700]),
    "truncated.ply": ("in.ply", ply_text(*PATCH).encode()[:400]),
    "garbage.off": ("in.off", bytes(range(256)) * 4),
    "empty.obj": ("in.obj", b""),
    "no faces.off": ("in.off", b"OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"),
    "soup.stl": ("in.stl", stl_text(*SOUP).encode()),
    "quads binary.ply": ("in.ply", binary_ply(PATCH32[0], QUADS)),
    "empty.stl": ("in.stl", b"solid x\nendsolid x\n"),
    "unknown suffix": ("in.xyz", b"solid x\nendsolid x\n"),
    "missing file": ("missing.obj", None),
    "a directory": ("adir.obj", "dir"),
}

BAD_NUMBERS = ["nan", "inf", "-inf", "-1", "0", "abc", "", "1e400"]


@st.composite
def command_lines(draw):
    """(input name, output kind, argv tail) of one run."""
    opts = []
    # Half the runs are clean (valid input, paths and values), so that results get written and
    # re-verified too; in the others anything goes, bad values in a third of them.
    clean = draw(st.booleans())
    kinds = ["absent", "absent", "good"] + (["bad"] if not clean and draw(st.integers(0, 2)) == 0
                                            else [])

    def maybe(flag, good, bad=BAD_NUMBERS):
        kind = draw(st.sampled_from(kinds))
        if kind != "absent":
            opts.extend([flag, draw(st.sampled_from(good if kind == "good" else bad))])

    maybe("--method", ["lscm", "arap", "dirichlet", "biharmonic", "stretch-l1"], ["LSCM", "x"])
    # 1.0001: its solve bound is clamped to 1 (a crash in the projection before issue 22's fix)
    maybe("--bound", ["1.5", "2", "5", "auto", "1", "1.0001"], BAD_NUMBERS + ["0.5", "Auto"])
    maybe("--frames", ["auto", "harmonic", "conformal", "input-uv", "constant"], ["uv"])
    # the input first: "--seams uv" is a valid value only for an input with UVs (for the others
    # it is a refusal, drawn as a bad value)
    valid = ["patch.obj", "patch.obj with vt", "artist.obj", "patch.off", "patch.ply",
             "closed tetra.obj",
             "soup.ply", "soup.off", "soup.stl", "quads binary.ply", "strips binary.ply"]
    source = draw(st.sampled_from(valid) if clean else
                  st.sampled_from(valid) | st.sampled_from(sorted(INPUTS)))
    has_uv = source == "patch.obj with vt"
    maybe("--seams", ["needed", "none", "auto"] + ["uv"] * has_uv, ["marked"] + ["uv"] * (not has_uv))
    maybe("--stretch", ["1.5", "2", "3", "10"], BAD_NUMBERS + ["1.0"])
    maybe("--bound-limit", ["10", "1000"], BAD_NUMBERS)
    maybe("--cone", ["soc", "linf"], ["l2"])
    maybe("--time-budget", ["5", "1"], BAD_NUMBERS)
    maybe("--overlap", ["cut", "fail"], ["merge"])
    maybe("--boundary", ["free", "circle", "rectangle", "pinned"], ["square"])
    # packing (the atlas packer), in a third of the runs: with --no-pack any of these is refused
    # (never ignored), so that flag and --udim come in a quarter of the runs each
    if draw(st.integers(0, 2)) == 0:
        maybe("--resolution", ["64", "256", "1024", "16384"], BAD_NUMBERS + ["7", "1e9", "65537"])
        maybe("--padding", ["0", "4", "16", "64"], BAD_NUMBERS + ["1e9", "200"])
        maybe("--texel-density", ["1", "50", "400", "1e4"], BAD_NUMBERS + ["1e-9", "1e9"])
        maybe("--rotate", ["none", "90", "any"], ["45"])
        maybe("--pack-seconds", ["0", "1"], BAD_NUMBERS)
    # --no-pack with a packing option is a refusal: drawn so in runs with bad values only
    packing = {"--resolution", "--padding", "--texel-density", "--rotate", "--pack-seconds"}
    if draw(st.integers(0, 3)) == 0 and ("bad" in kinds or not packing & set(opts)):
        opts.append("--no-pack")
    if draw(st.integers(0, 3)) == 0 and ("--texel-density" in opts or not clean and
                                         draw(st.integers(0, 2)) == 0):   # needs a density
        opts.append("--udim")
    for flag in ("--no-raise", "-q"):
        if draw(st.booleans()):
            opts.append(flag)
    if "bad" in kinds and draw(st.integers(0, 9)) == 0:
        opts.append(draw(st.sampled_from(["--unknown", "-x", "--bound"])))  # unknown, or no value
    return dict(input=source,
                # bad paths (a folder, under a file, the input, another output, empty) in
                # about a third of the runs, so that most reach the unwrap
                output=draw(st.sampled_from(["new", "existing file", "in a new folder"]) if clean
                            else st.sampled_from(["new"] * 12 + [
                                "existing file", "in a new folder", "no suffix", "a directory",
                                "the input", "empty", "another format"])),
                report=draw(st.sampled_from([None, "report.json"] if clean else [None] * 8 + [
                    "report.json"] * 4 + ["adir.obj/r.json", "existing.txt/r.json", "the input",
                                          "-o"])),
                png=draw(st.sampled_from([None] * 4 + ["pic.png"] if clean else [None] * 10 + [
                    "pic.png"] * 2 + ["existing.txt/p.png", "the input", "-o"])),
                opts=opts)


def tree(root):
    """{relative path: bytes or 'dir'} of everything under root."""
    out = {}
    for p in sorted(pathlib.Path(root).rglob("*")):
        out[str(p.relative_to(root))] = "dir" if p.is_dir() else p.read_bytes()
    return out


def read_obj(path):
    """V, VT, and the faces' fans from their first corners: vertex and vt ids (-1: none)."""
    V, VT, faces = read_faces(pathlib.Path(path).read_bytes())
    F, FT = [], []
    for corners, _ in faces:
        for j in range(1, len(corners) - 1):
            c = (corners[0], corners[j], corners[j + 1])
            F.append([x[0] for x in c])
            FT.append([-1 if x[1] is None else x[1] for x in c])
    return V, VT, np.array(F).reshape(-1, 3), np.array(FT).reshape(-1, 3)


def check_patched(inp, out, stdout):
    """The OBJ written from an OBJ is its text with only the UVs replaced: every record but vt
    and f as it was, in order; each face with its vertex and normal indices as written, as one
    polygon or (as many as the command line says) as its fan's triangles."""
    a, b = inp.read_bytes(), out.read_bytes()
    assert [r for k, r in records(a) if k not in ("vt", "f")] == \
        [r for k, r in records(b) if k not in ("vt", "f")]
    said = re.search(r"(\d+) polygon\(s\) written as their triangles", stdout)
    split, rest = 0, read_faces(b)[2]
    for corners, text in read_faces(a)[2]:
        got, rest = rest[0], rest[1:]
        if got[1] == text:
            continue
        split += 1
        fan = [[text[0], text[j], text[j + 1]] for j in range(1, len(text) - 1)]
        got = [got] + rest[:len(fan) - 1]
        rest = rest[len(fan) - 1:]
        assert [g[1] for g in got] == fan, "a face's vertex or normal indices changed"
    assert not rest
    assert split == (int(said.group(1)) if said else 0), stdout


def run(sc, root):
    """Lay out the files of a scenario under root and run ``main`` on them: (argv, exit code,
    stdout, stderr, input path, -o path, the output paths named, the tree before the run)."""
    root = pathlib.Path(root)
    (root / "adir.obj").mkdir()
    (root / "existing.txt").write_bytes(b"not a folder\n")
    name, data = INPUTS[sc["input"]]
    inp = root / name
    if isinstance(data, bytes):
        inp.write_bytes(data)
    out = {"new": root / "out.obj", "existing file": root / "old.obj",
           "in a new folder": root / "sub" / "out.obj", "a directory": root / "adir.obj",
           "no suffix": root / "out", "the input": inp, "empty": None,
           "another format": root / "out.glb"}[sc["output"]]
    if sc["output"] == "existing file":
        out.write_bytes(b"# a previous result, to be kept unless replaced by a certified one\n")
    argv = ["unwrap", str(inp), "-o", "" if out is None else str(out)]
    named = {out} if out is not None else set()
    for flag in ("--report", "--png"):
        path = sc[flag[2:]]
        if path:   # a file under root, the input itself, or the -o path again
            path = {"the input": inp, "-o": out}.get(path, root / path)
            argv += [flag, "" if path is None else str(path)]
            if path is not None:
                named.add(path)
    argv += sc["opts"]
    before = tree(root)
    so, se = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(so), contextlib.redirect_stderr(se):
        try:
            rc = main(argv)
        except SystemExit as exc:           # argparse: usage errors
            rc = exc.code
    return argv, rc, so.getvalue(), se.getvalue(), inp, out, named, before


def certified_bounds(stdout):
    return [float(x) for x in re.findall(r"certified C = ([0-9.eE+-]+),", stdout)]


def check_written(inp_mesh, out, report, stdout, packed, inp=None):
    """The OBJ's certified faces re-verified from the stored UVs (independent code)."""
    V, VT, F, FT = read_obj(out)
    V0, F0 = inp_mesh
    assert np.array_equal(F, F0)
    stored32 = any(inp_mesh is m for m in (PATCH32, SOUP, MIXED, STRIPS))   # PLY, OFF: float32
    assert np.allclose(V, V0, rtol=1e-6 if stored32 else 1e-12, equal_nan=True)
    has = (FT >= 0).all(axis=1)
    assert has.any(), "an OBJ was written with no certified island"
    uv = VT[FT[has]]
    D, flipped = distortion_and_flips(V, F[has], uv)
    assert not flipped.any()
    if report is not None and report.exists():
        rep = strict_json(report.read_text())
        bound = max(e["bound_certified"] for e in rep["islands"] if e["status"] == "certified")
        slack = 2e-6
    else:                                   # the report line prints 4 significant digits
        bound, slack = max(certified_bounds(stdout)), 5e-4
    assert D.max() <= bound * (1 + slack), (D.max(), bound)
    pairs = overlapping_triangle_pairs(uv)
    if not packed:                          # islands all start at (0, 0): only within one
        isl = uv_islands(FT[has])
        pairs = pairs[isl[pairs[:, 0]] == isl[pairs[:, 1]]]
    assert len(pairs) == 0, pairs[:5]
    if inp_mesh is ARTIST_MESH:
        check_patched(inp, out, stdout)
    if inp_mesh is SOUP:     # welded for the unwrap (its islands the patch's: test_mesh_file_weld)
        assert "of the file's vertices lie where another does" in stdout, stdout


def uv_islands(FT):
    """Island of each face: faces joined through shared UV (vt) indices."""
    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import connected_components
    k = len(FT)
    rows = np.repeat(np.arange(k), 3)
    g = coo_array((np.ones(3 * k), (rows, k + FT.ravel())), shape=(k + FT.max() + 1,) * 2)
    return connected_components(g, directed=False)[1][:k]


def _fan_mesh(data):
    """(V, fan triangles) of OBJ bytes, by the independent reader."""
    V, _, faces = read_faces(data)
    return V, np.array([[c[0][0], c[j][0], c[j + 1][0]] for c, _ in faces
                        for j in range(1, len(c) - 1)])


ARTIST_MESH = _fan_mesh(ARTIST)


def mesh_of(sc):
    """The (V, F) the input holds when it is a valid mesh, else None."""
    return {"patch.obj": PATCH, "patch.obj with vt": PATCH, "artist.obj": ARTIST_MESH,
            "patch.off": PATCH,
            "patch.ply": PATCH32, "closed tetra.obj": TETRA, "soup.ply": SOUP, "soup.off": SOUP,
            "soup.stl": SOUP, "quads binary.ply": MIXED, "strips binary.ply": STRIPS,
            "nan vertex.obj": NAN_PATCH}.get(sc["input"])


# Falsifying examples found on the way (issue 22), each kept; what each did before its fix:
FOUND = [
    # ValueError tracebacks from option checks in the core (now bd_uv.OptionError, exit 2)
    dict(input="closed tetra.obj", output="new", report=None, png=None,
         opts=["--bound", "auto", "--boundary", "circle"]),
    dict(input="patch.obj", output="new", report=None, png=None,
         opts=["--stretch", "3", "--bound-limit", "nan"]),
    dict(input="closed tetra.obj", output="new", report=None, png=None, opts=["--stretch", "nan"]),
    dict(input="closed tetra.obj", output="new", report=None, png=None, opts=["--stretch", "1.5"]),
    # --bound 1 with a stretch bound: ValueError from the projection iterations (need C > 1)
    dict(input="nan vertex.obj", output="new", report=None, png=None,
         opts=["--bound", "1", "--stretch", "1.5"]),
    # an OBJ with no certified island written at -o (exit 1): now nothing is written
    dict(input="closed tetra.obj", output="new", report=None, png=None, opts=[]),
    dict(input="nan vertex.obj", output="existing file", report="report.json", png="pic.png",
         opts=["--seams", "none"]),
    # OSError tracebacks: -o a folder, --report or --png under a file (now exit 2, one line)
    dict(input="patch.obj", output="a directory", report=None, png=None, opts=[]),
    dict(input="patch.obj", output="new", report="existing.txt/r.json", png=None, opts=[]),
    dict(input="patch.obj", output="new", report=None, png="existing.txt/p.png", opts=[]),
    # -o, --report or --png naming the input: it was overwritten (now exit 2, one line)
    dict(input="patch.obj", output="the input", report=None, png=None, opts=[]),
    dict(input="patch.off", output="new", report="the input", png=None, opts=[]),
    dict(input="patch.ply", output="new", report=None, png="the input", opts=[]),
    # two outputs on one path: the last written replaced the other (now exit 2)
    dict(input="patch.obj", output="new", report="-o", png=None, opts=[]),
    # -o "": the temporary file went to the folder above, the error named it (now exit 2)
    dict(input="patch.obj", output="empty", report=None, png=None, opts=[]),
    # -o out.glb (or .ply, .usd, ...) for a mesh: OBJ text was written there (now exit 2)
    dict(input="patch.obj", output="another format", report=None, png=None, opts=[]),
    # a packing option with --no-pack was accepted and ignored (now exit 2)
    dict(input="patch.obj", output="new", report=None, png=None,
         opts=["--no-pack", "--padding", "16"]),
    # --bound 1.0001: ValueError('C must be > 1') from the projection (solve bound clamped to 1)
    dict(input="patch.obj", output="new", report=None, png=None, opts=["--bound", "1.0001"]),
    dict(input="patch.obj", output="new", report=None, png=None,
         opts=["--bound", "1.0001", "--stretch", "1.5"]),
    # an artist's OBJ (polygons, materials, normals, comments, ...): it lost everything but
    # v, vt and triangles; written back whole now, its spiral polygon as triangles at C = 1.5
    dict(input="artist.obj", output="new", report="report.json", png=None, opts=["--bound", "1.5"]),
    dict(input="artist.obj", output="existing file", report=None, png=None,
         opts=["--seams", "auto"]),
    # a PLY of triangle strips (Cyberware's igea.ply): "the file holds no faces" (exit 2)
    dict(input="strips binary.ply", output="new", report="report.json", png=None, opts=[]),
]


@settings(max_examples=EXAMPLES, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(sc=command_lines())
@with_examples(FOUND)
def test_command_line_contract(sc):
    in_fresh_dir(check, sc, "bd-uv-cli-fuzz-")


def check(sc, root):
    argv, rc, stdout, stderr, inp, out, named, before = run(sc, root)
    after = tree(root)
    event(f"exit {rc}")
    assert isinstance(rc, int) and rc in (0, 1, 2), (rc, argv, stderr)
    assert "Traceback" not in stderr and "Traceback" not in stdout, stderr
    errors = [line for line in stderr.splitlines() if "error:" in line]
    if rc == 2:
        assert len(errors) == 1, (argv, stderr)
    elif rc == 1:
        assert errors, (argv, stderr)
    # The input is untouched (a folder stays a folder).
    rel = str(inp.relative_to(root))
    assert after.get(rel) == before.get(rel)
    # Nothing written outside -o, --report and --png (and the new folders they name).
    allowed = {str(p.relative_to(root)) for p in named}
    allowed |= {str(pathlib.Path(a).parent) for a in allowed}
    for path, content in after.items():
        if before.get(path) != content:
            assert path in allowed, (path, argv)
    if out is None or out == inp or sc["output"] == "another format":   # refused before work
        assert rc == 2 and after == before, (rc, argv, stderr)
        return
    orel = str(out.relative_to(root))
    if after.get(orel) != before.get(orel):      # written: a certified result, re-verified
        assert rc in (0, 1) and after.get(orel) != "dir", (rc, argv)
        report = next((p for p in named if p.suffix == ".json"), None)
        check_written(mesh_of(sc), out, report, stdout, "--no-pack" not in sc["opts"], inp)
    else:
        assert rc != 0, (argv, "exit 0 but nothing written at -o")
