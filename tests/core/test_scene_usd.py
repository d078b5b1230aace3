"""USD stages in and out whole: every authored value of the composed input survives, the new
``primvars:st`` (texCoord2f[], faceVarying, indexed) is certified from the file as written, the
input layers are untouched, references resolve from another output folder."""
import hashlib
import json
import os
import re

import numpy as np
import pytest

from pxr import Sdf, Usd, UsdGeom, UsdShade, Vt  # usd-core: requirements-dev.txt

from bd_uv.cli import main
from bd_uv.errors import SceneFileError
from bd_uv.scenes import read_scene
from helpers import float32_flat, reference_distortion, relpath_across_drives
from overlap_shapes import overlapping_triangle_pairs
from usd_build import build_stage, quad_grid

NEW = ("primvars:st", "primvars:st:indices")


def _tree_digest(folder):
    out = {}
    for root, _, files in os.walk(folder):
        for f in files:
            p = os.path.join(root, f)
            out[os.path.relpath(p, folder)] = hashlib.sha256(open(p, "rb").read()).hexdigest()
    return out


def _values(attr):
    vals = [attr.Get(Usd.TimeCode.Default())] + [attr.Get(t) for t in attr.GetTimeSamples()]
    if attr.GetTypeName() == Sdf.ValueTypeNames.Asset:
        return [None if v is None else os.path.realpath(v.resolvedPath) for v in vals]
    return [None if v is None else (np.asarray(v).tolist() if hasattr(v, "__len__") else v)
            for v in vals], attr.GetTimeSamples()


def _check_everything_kept(stage_in, stage_out):
    n = 0
    for prim in stage_in.Traverse():
        other = stage_out.GetPrimAtPath(prim.GetPath())
        assert other, prim.GetPath()
        assert other.GetTypeName() == prim.GetTypeName()
        assert other.GetCustomData() == prim.GetCustomData()
        assert other.GetAppliedSchemas() == prim.GetAppliedSchemas()
        assert other.GetVariantSets().GetNames() == prim.GetVariantSets().GetNames()
        for attr in prim.GetAttributes():
            if attr.GetName() in NEW or not attr.HasAuthoredValue():
                continue
            assert _values(other.GetAttribute(attr.GetName())) == _values(attr), attr.GetPath()
            n += 1
        for rel in prim.GetRelationships():
            assert other.GetRelationship(rel.GetName()).GetTargets() == rel.GetTargets()
    return n


def _check_st(stage, path, bound, name="st", time=None):
    """Certify the stored primvar from the file, with this test's own fan triangulation (the
    mesh's points and topology at ``time``, default: their default values)."""
    time = Usd.TimeCode.Default() if time is None else time
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath(path))
    pv = UsdGeom.PrimvarsAPI(mesh.GetPrim()).GetPrimvar(name)
    assert pv.GetTypeName() == Sdf.ValueTypeNames.TexCoord2fArray
    assert pv.GetInterpolation() == UsdGeom.Tokens.faceVarying and pv.IsIndexed()
    assert pv.GetAttr().GetNumTimeSamples() == 0
    uv = np.asarray(pv.Get(), np.float64)[np.asarray(pv.GetIndices())]   # per face-vertex
    P = np.asarray(mesh.GetPointsAttr().Get(time), np.float64)
    counts = np.asarray(mesh.GetFaceVertexCountsAttr().Get(time))
    idx = np.asarray(mesh.GetFaceVertexIndicesAttr().Get(time))
    tris, s = [], 0
    for c in counts:
        tris += [(s, s + i, s + i + 1) for i in range(1, c - 1)]
        s += c
    T = np.array(tris)
    D, flipped = reference_distortion(P, idx[T], uv[T])
    assert not flipped.any()
    assert D.max() <= bound * (1 + 1e-9)
    assert len(overlapping_triangle_pairs(uv[T])) == 0
    return uv


@pytest.mark.parametrize("out_name", ["shot_uv.usda", "shot_uv.usdc", "shot_uv.usd"])
def test_round_trip_keeps_every_value(tmp_path, out_name):
    src = tmp_path / "in"
    shot, asset = build_stage(str(src))
    before = _tree_digest(src)
    out = tmp_path / "elsewhere" / "deeper" / out_name
    assert main(["unwrap", shot, "-o", str(out), "--bound", "3",
                 "--report", str(tmp_path / "r.json")]) == 0
    assert _tree_digest(src) == before                     # the input layers are untouched
    entries = {e["name"]: e for e in json.loads((tmp_path / "r.json").read_text())["meshes"]}
    assert set(entries) == {"/World/Panel", "/World/Prop/Geo/Rock"}        # prim paths
    assert all(e["status"] == "certified" for e in entries.values())
    stage_in, stage_out = Usd.Stage.Open(shot), Usd.Stage.Open(str(out))
    assert _check_everything_kept(stage_in, stage_out) > 10
    # the texture still resolves from the output folder, to the same file
    tex = stage_out.GetPrimAtPath("/World/Looks/Wood/Tex").GetAttribute("inputs:file").Get()
    assert os.path.samefile(tex.resolvedPath, src / "lib" / "tex" / "wood.png")
    binding = UsdShade.MaterialBindingAPI(stage_out.GetPrimAtPath("/World/Panel"))
    assert binding.ComputeBoundMaterial()[0].GetPath() == "/World/Looks/Wood"
    for path, e in entries.items():
        _check_st(stage_out, path, e["bound_certified"])
    # the referenced mesh got an over in the output layer; the asset layer holds no st
    layer = Sdf.Layer.FindOrOpen(str(out))
    spec = layer.GetPrimAtPath("/World/Prop/Geo/Rock")
    assert spec.specifier == Sdf.SpecifierOver and "primvars:st" in spec.attributes
    assert not Usd.Stage.Open(asset).GetPrimAtPath("/Asset/Geo/Rock").GetAttribute(
        "primvars:st").IsValid()
    # the rest pose was unwrapped; st is written once, for every time
    panel = UsdGeom.Mesh(stage_out.GetPrimAtPath("/World/Panel"))
    assert panel.GetPointsAttr().GetTimeSamples() == [10.0]


def test_seams_only_along_polygon_edges_on_a_closed_quad_mesh(tmp_path):
    """A closed box of quads needs seams: --seams auto cuts along quad edges only, and every
    quad is one piece of UV (its fan triangles agree on every face-vertex)."""
    n = 4
    g = np.linspace(-1, 1, n + 1)
    pts, polys = {}, []

    def vid(p):
        return pts.setdefault(tuple(np.round(p, 9)), len(pts))

    for axis in range(3):
        for sign in (-1, 1):
            for i in range(n):
                for j in range(n):
                    quad = []
                    for a, b in ((i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)):
                        p = np.zeros(3)
                        p[axis] = sign
                        p[(axis + 1) % 3], p[(axis + 2) % 3] = g[a], g[b]
                        quad.append(vid(p))
                    polys.append(quad if sign > 0 else quad[::-1])
    V = np.array(list(pts))
    stage = Usd.Stage.CreateNew(str(tmp_path / "box.usda"))
    m = UsdGeom.Mesh.Define(stage, "/Box")
    m.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(V.astype(np.float32)))
    m.CreateFaceVertexCountsAttr([4] * len(polys))
    m.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(np.concatenate(polys).astype(np.int32)))
    stage.GetRootLayer().Save()
    out = tmp_path / "box_uv.usda"
    assert main(["unwrap", str(tmp_path / "box.usda"), "-o", str(out), "--seams", "auto",
                 "--bound", "2", "--report", str(tmp_path / "r.json")]) == 0
    (e,) = json.loads((tmp_path / "r.json").read_text())["meshes"]
    assert len(e["islands"]) >= 2
    _check_st(Usd.Stage.Open(str(out)), "/Box", e["bound_certified"])


def test_zero_area_faces_do_not_refuse_their_mesh(tmp_path):
    """Production meshes carry faces of no area (OpenChessSet's bishops hold hundreds, most of
    them three points within one float32 step of a line). No map certifies them, and each refused
    its whole mesh: nothing written. Now the mesh is written when every face with an area is
    certified: the zero-area faces' corners take the UVs of the same vertices in neighbouring
    faces, and the report counts them. Here a quad grid is split along a row of points whose
    copies lie 1e-9 above them (the same float32 values): a strip of 4 quads, 8 triangles of no
    area, between the halves."""
    V, counts, idx = quad_grid(5, 4, bump=False)
    polys = [list(p) for p in np.split(idx, np.cumsum(counts)[:-1])]
    row = np.arange(5, 10)
    copy = {int(r): len(V) + i for i, r in enumerate(row)}
    V = np.vstack([V, V[row] + [0.0, 1e-9, 0.0]]).astype(np.float32)
    for p in polys[4:]:                          # the quads above the row use the copies
        p[:] = [copy.get(int(v), int(v)) for v in p]
    strip = [[int(row[i]), int(row[i + 1]), copy[int(row[i + 1])], copy[int(row[i])]]
             for i in range(4)]
    polys = polys[:4] + strip + polys[4:]
    counts = np.array([len(p) for p in polys])
    idx = np.concatenate(polys)
    stage = Usd.Stage.CreateNew(str(tmp_path / "strip.usda"))
    mesh = UsdGeom.Mesh.Define(stage, "/Strip")
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(V))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts.astype(np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(idx.astype(np.int32)))
    stage.GetRootLayer().Save()
    out = tmp_path / "strip_uv.usda"
    assert main(["unwrap", str(tmp_path / "strip.usda"), "-o", str(out),
                 "--report", str(tmp_path / "r.json")]) == 0
    (e,) = json.loads((tmp_path / "r.json").read_text())["meshes"]
    assert e["status"] == "certified" and e["zero_area_faces"] == 8
    assert any("zero area" in w for w in e["warnings"])
    stage_out = Usd.Stage.Open(str(out))
    pv = UsdGeom.PrimvarsAPI(stage_out.GetPrimAtPath("/Strip")).GetPrimvar("st")
    uv = np.asarray(pv.Get(), np.float64)[np.asarray(pv.GetIndices())]   # per face-vertex
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    T = np.array([(s, s + i, s + i + 1) for s, c in zip(start, counts) for i in range(1, c - 1)])
    P = V.astype(np.float64)
    flat = float32_flat(P, idx[T])
    assert np.flatnonzero(flat).tolist() == list(range(8, 16))   # the strip's triangles alone
    D, flipped = reference_distortion(P, idx[T[~flat]], uv[T[~flat]])
    assert not flipped.any() and D.max() <= e["bound_certified"] * (1 + 1e-9)
    assert len(overlapping_triangle_pairs(uv[T[~flat]])) == 0
    # each strip corner lies where a certified face puts that point
    fv_point = idx
    certified_fv = T[~flat].reshape(-1)
    for fv in T[flat].reshape(-1):
        same = certified_fv[fv_point[certified_fv] == fv_point[fv]]
        assert any(np.array_equal(uv[fv], uv[o]) for o in same)


def test_an_island_refused_whole_for_a_zero_area_face_is_not_written_as_certified(tmp_path):
    """``--seams none`` takes the islands as they are: one holding a zero-area face is refused
    whole (``DegenerateFacesError``), its faces with an area uncertified. Counting all of them as
    zero-area (left out) wrote this mesh as certified, 17 "zero-area" faces whose UVs were
    borrowed; now it is partial, nothing is written and the report names the one face."""
    V, counts, idx = quad_grid(5, 3, bump=False)
    polys = [list(p) for p in np.split(idx, np.cumsum(counts)[:-1])]
    n = len(V)
    V = np.vstack([V, V + [10.0, 0.0, 0.0], [[11.5, 0.0, V[1, 2] / 2 + V[2, 2] / 2]]])
    polys += [[v + n for v in p] for p in polys] + [[n + 2, n + 1, 2 * n]]
    V[2 * n] = V[n + 1]          # a corner on another: no area at any precision (a point on
    # the edge's middle keeps a float32 sliver, which a packed layout may store certified)
    counts = np.array([len(p) for p in polys])
    stage = Usd.Stage.CreateNew(str(tmp_path / "two.usda"))
    mesh = UsdGeom.Mesh.Define(stage, "/Two")
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(V.astype(np.float32)))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts.astype(np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(np.concatenate(polys).astype(np.int32)))
    stage.GetRootLayer().Save()
    out = tmp_path / "two_uv.usda"
    main(["unwrap", str(tmp_path / "two.usda"), "-o", str(out), "--seams", "none",
          "--report", str(tmp_path / "r.json"), "-q"])
    (e,) = json.loads((tmp_path / "r.json").read_text())["meshes"]
    assert e["status"] == "partial" and "zero_area_faces" not in e, e
    refused = [i for i in e["islands"] if i["status"] != "certified"]
    assert len(refused) == 1 and refused[0]["error"] == "DegenerateFacesError"
    assert refused[0]["faces"] == 17 and "1 zero-area face" in refused[0]["message"]
    assert not out.exists()


def test_usdz_out(tmp_path):
    shot, _ = build_stage(str(tmp_path / "in"))
    out = tmp_path / "pkg" / "shot.usdz"
    assert main(["unwrap", shot, "-o", str(out), "--bound", "3"]) == 0
    stage = Usd.Stage.Open(str(out))
    assert stage.GetPrimAtPath("/World/Prop/Geo/Rock").IsValid()      # packaged with the asset
    _check_st(stage, "/World/Panel", 3.0)
    assert not [f for f in os.listdir(out.parent) if f.startswith(".")]


@pytest.mark.parametrize("out_name", ["out.usdz", "out.usda"])
def test_a_usdz_s_own_files_come_along(tmp_path, out_name):
    """A .usdz input whose texture and referenced asset live inside the package (as
    usd-wg/assets' CesiumMan.usdz): a .usdz output packages them at the same paths (it used to
    fail: "the .usdz package could not be written"), a .usda output reads them from the input
    package; every dependency resolves, to the same bytes."""
    import zipfile
    from pxr import UsdUtils
    shot, _ = build_stage(str(tmp_path / "src"))
    package = tmp_path / "in" / "shot.usdz"
    package.parent.mkdir()
    assert UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(shot), str(package))
    inside = dict((n, zipfile.ZipFile(package).read(n))
                  for n in zipfile.ZipFile(package).namelist())
    texture = next(n for n in inside if n.endswith("wood.png"))
    before = package.read_bytes()
    out = tmp_path / "out" / out_name
    assert main(["unwrap", str(package), "-o", str(out), "--bound", "3"]) == 0
    assert package.read_bytes() == before
    _, assets, unresolved = UsdUtils.ComputeAllDependencies(Sdf.AssetPath(str(out)))
    assert not unresolved
    stage = Usd.Stage.Open(str(out))
    assert stage.GetPrimAtPath("/World/Prop/Geo/Rock").IsValid()      # the referenced asset
    _check_st(stage, "/World/Panel", 3.0)
    tex = stage.GetPrimAtPath("/World/Looks/Wood/Tex").GetAttribute("inputs:file").Get()
    where = tex.resolvedPath
    assert where.endswith(f"[{texture}]")
    pkg = where[:where.index("[")]
    assert zipfile.ZipFile(pkg).read(texture) == inside[texture]
    if out_name.endswith(".usdz"):
        assert os.path.samefile(pkg, out)
        assert not [f for f in os.listdir(out.parent) if f.startswith(".")]
    else:
        assert os.path.samefile(pkg, package)


def test_malformed_stage_names_the_prim(tmp_path, capsys):
    stage = Usd.Stage.CreateNew(str(tmp_path / "bad.usda"))
    V, counts, idx = quad_grid(4, 3, bump=False)
    m = UsdGeom.Mesh.Define(stage, "/Geo/Broken")
    m.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(V.astype(np.float32)))
    m.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy((counts + 1).astype(np.int32)))
    m.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(idx.astype(np.int32)))
    stage.GetRootLayer().Save()
    scene = read_scene(str(tmp_path / "bad.usda"))
    assert [(m.name, m.mesh) for m in scene.meshes] == [("/Geo/Broken", None)]
    assert "faceVertexCounts sum" in scene.meshes[0].refused
    assert main(["unwrap", str(tmp_path / "bad.usda"), "-o", str(tmp_path / "o.usda")]) == 1
    assert "/Geo/Broken" in capsys.readouterr().err
    assert not (tmp_path / "o.usda").exists()     # its only mesh refused: nothing written
    (tmp_path / "junk.usda").write_text("this is not usd")
    with pytest.raises(SceneFileError, match="junk.usda"):
        read_scene(str(tmp_path / "junk.usda"))


@pytest.mark.parametrize("attr, line", [
    ("points", "pointz3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]"),
    ("faceVertexIndices", "int[] faceVertexCounts = [3, 3]\n        "
                          "intz[] faceVertexIndices = [0, 1, 2, 0, 2, 3]"),
    ("primvars:st", "texCoord2z[] primvars:st = [(0, 0), (1, 0), (1, 1), (0, 1)] (\n"
                    "            interpolation = \"vertex\"\n        )")])
def test_a_value_of_an_unknown_type_is_a_scene_error(tmp_path, capsys, attr, line):
    """Issue 22 (scene contract): a damaged .usda whose type name no longer reads (a corrupted
    byte: ``point3f[]`` became something else) holds an ``Sdf.UnregisteredValue`` where numbers
    belong; numpy raised TypeError out of read_scene. Now a SceneFileError naming the prim."""
    body = {"points": "point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]",
            "faceVertexIndices": "int[] faceVertexCounts = [3, 3]\n        "
                                 "int[] faceVertexIndices = [0, 1, 2, 0, 2, 3]"}
    body[attr] = line                     # the damaged line, in place of the good one
    path = tmp_path / "damaged.usda"
    path.write_text('#usda 1.0\n\ndef Mesh "Panel"\n{\n        '
                    + "\n        ".join(body.values()) + "\n}\n")
    raw = path.read_bytes()
    mesh = read_scene(str(path)).meshes[0]
    assert mesh.name == "/Panel" and mesh.mesh is None
    assert re.search(f"{attr}.*not an array of numbers", mesh.refused), mesh.refused
    assert main(["unwrap", str(path), "-o", str(tmp_path / "o.usda")]) == 1
    err = capsys.readouterr().err
    assert "/Panel" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o.usda").exists() and path.read_bytes() == raw


def test_a_malformed_mesh_leaves_the_stage_s_others_unwrapped(tmp_path, capsys):
    """A stage with one broken mesh is not refused whole: the broken prim is named and left as
    read, the good one certified and written (exit 1: not every mesh certified)."""
    stage = Usd.Stage.CreateNew(str(tmp_path / "two.usda"))
    V, counts, idx = quad_grid(4, 3, bump=False)
    for path, c in (("/Geo/Good", counts), ("/Geo/Broken", counts + 1)):
        m = UsdGeom.Mesh.Define(stage, path)
        m.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(V.astype(np.float32)))
        m.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(c.astype(np.int32)))
        m.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(idx.astype(np.int32)))
    stage.GetRootLayer().Save()
    raw = (tmp_path / "two.usda").read_bytes()
    out, rep = tmp_path / "o.usda", tmp_path / "r.json"
    assert main(["unwrap", str(tmp_path / "two.usda"), "-o", str(out), "--report",
                 str(rep)]) == 1
    err = capsys.readouterr().err
    assert "/Geo/Broken" in err and "faceVertexCounts sum" in err and "/Geo/Good" not in err
    assert (tmp_path / "two.usda").read_bytes() == raw
    entries = {e["name"]: e for e in json.loads(rep.read_text())["meshes"]}
    assert entries["/Geo/Broken"]["status"] == "failed"
    assert entries["/Geo/Good"]["status"] == "certified"
    written = Usd.Stage.Open(str(out))
    assert not UsdGeom.PrimvarsAPI(written.GetPrimAtPath("/Geo/Broken")).HasPrimvar("st")
    good = UsdGeom.PrimvarsAPI(written.GetPrimAtPath("/Geo/Good")).GetPrimvar("st")
    uv = np.asarray(good.ComputeFlattened(), dtype=np.float64).reshape(-1, 2)
    fan = np.concatenate([[[s, s + k, s + k + 1] for k in range(1, n - 1)]
                          for s, n in zip(np.cumsum(counts) - counts, counts)])
    P = V.astype(np.float32).astype(np.float64)[np.asarray(idx)[fan]]
    Fw = np.arange(3 * len(fan)).reshape(-1, 3)
    D, flipped = reference_distortion(P.reshape(-1, 3), Fw, uv[fan])
    assert not flipped.any() and D.max() <= entries["/Geo/Good"]["bound_certified"] * (1 + 1e-9)
    assert len(overlapping_triangle_pairs(uv[fan])) == 0


def test_holes_instances_and_points_only_time_sampled(tmp_path):
    """A hole is not unwrapped (its corners get one value); a mesh inside an instanceable prim is
    unwrapped once on its prototype, its UVs on a class the instance inherits
    (``test_instanced_meshes_are_unwrapped_once_per_prototype``); points with time samples only
    are unwrapped at the first sample."""
    stage = Usd.Stage.CreateNew(str(tmp_path / "a.usda"))
    V, counts, idx = quad_grid(5, 4, bump=False)
    m = UsdGeom.Mesh.Define(stage, "/Holed")
    m.CreatePointsAttr().Set(Vt.Vec3fArray.FromNumpy(V.astype(np.float32)), 1.0)
    m.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy((2 * V).astype(np.float32)), 5.0)
    m.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts.astype(np.int32)))
    m.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(idx.astype(np.int32)))
    m.CreateHoleIndicesAttr([5])                       # an interior quad
    proto = stage.CreateClassPrim("/Proto")              # abstract: only its instance is seen
    leaf = UsdGeom.Mesh.Define(stage, "/Proto/Leaf")
    leaf.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(V.astype(np.float32)))
    leaf.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts.astype(np.int32)))
    leaf.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(idx.astype(np.int32)))
    inst = stage.DefinePrim("/Inst")
    inst.GetReferences().AddInternalReference("/Proto")
    inst.SetInstanceable(True)
    stage.GetRootLayer().Save()
    assert proto
    out = tmp_path / "b.usda"
    assert main(["unwrap", str(tmp_path / "a.usda"), "-o", str(out), "--bound", "3",
                 "--report", str(tmp_path / "r.json")]) == 0
    entries = {e["name"]: e for e in json.loads((tmp_path / "r.json").read_text())["meshes"]}
    holed = entries["/Holed"]
    assert holed["status"] == "certified" and holed["faces"] == 2 * (len(counts) - 1)
    assert any("time 1" in w for w in holed["warnings"])
    inst_entry = entries["/Inst/Leaf"]
    assert inst_entry["status"] == "certified" and inst_entry["instances"] == 1
    stage_out = Usd.Stage.Open(str(out))
    leaf = stage_out.GetPrimAtPath("/Inst/Leaf")
    assert leaf.IsInstanceProxy() and UsdGeom.PrimvarsAPI(leaf).GetPrimvar("st").HasValue()
    pv = UsdGeom.PrimvarsAPI(stage_out.GetPrimAtPath("/Holed")).GetPrimvar("st")
    fv = np.asarray(pv.GetIndices()).reshape(-1, 4)
    assert len(set(fv[5].tolist())) == 1                                 # the hole's corners
    keep = np.ones(len(counts), bool)
    keep[5] = False
    uv = np.asarray(pv.Get(), np.float64)[fv[keep]]                      # (q,4,2) quads
    P = np.asarray(V, np.float64)[idx.reshape(-1, 4)[keep]]
    T = np.array([[0, 1, 2], [0, 2, 3]])
    tri_uv = uv[:, T].reshape(-1, 3, 2)
    D, flipped = reference_distortion(P[:, T].reshape(-1, 3), np.arange(3 * len(tri_uv))
                                      .reshape(-1, 3), tri_uv)
    assert not flipped.any() and D.max() <= holed["bound_certified"] * (1 + 1e-9)


def test_never_overwrites_a_layer_the_input_uses(tmp_path, capsys):
    shot, asset = build_stage(str(tmp_path))
    before = _tree_digest(tmp_path)
    assert main(["unwrap", shot, "-o", asset]) == 2
    assert "would overwrite a layer" in capsys.readouterr().err
    assert _tree_digest(tmp_path) == before


def test_uv_name_writes_another_primvar_and_keeps_st(tmp_path):
    shot, _ = build_stage(str(tmp_path / "in"))
    out = tmp_path / "o.usda"
    assert main(["unwrap", shot, "-o", str(out), "--bound", "3", "--uv-name", "lightmap"]) == 0
    s_in, s_out = Usd.Stage.Open(shot), Usd.Stage.Open(str(out))
    p_in = UsdGeom.PrimvarsAPI(s_in.GetPrimAtPath("/World/Panel"))
    p_out = UsdGeom.PrimvarsAPI(s_out.GetPrimAtPath("/World/Panel"))
    assert np.array_equal(np.asarray(p_in.GetPrimvar("st").Get()),
                          np.asarray(p_out.GetPrimvar("st").Get()))
    assert p_out.GetPrimvar("st").GetInterpolation() == UsdGeom.Tokens.vertex
    lm = p_out.GetPrimvar("lightmap")
    assert lm.GetInterpolation() == UsdGeom.Tokens.faceVarying and lm.IsIndexed()


def _grid_stage(path, primvars, reads=None):
    """One quad grid at /World/Grid holding faceVarying texCoord2f[] ``primvars`` (name: UVs
    per face-vertex, two islands: the grid's halves apart), bound to a material whose
    UsdPrimvarReader_float2 reads ``reads`` through an input of the material (as Maya's and
    Houdini's exports connect it), or no material."""
    V, counts, idx = quad_grid()
    stage = Usd.Stage.CreateNew(path)
    mesh = UsdGeom.Mesh.Define(stage, "/World/Grid")
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(V.astype(np.float32)))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts.astype(np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(idx.astype(np.int32)))
    uv = V[idx, :2].astype(np.float32)
    poly = np.repeat(np.arange(len(counts)), counts)
    right = np.bincount(poly, V[idx, 0]) / counts > 0.5
    uv[right[poly], 0] += 3.0                  # the right half's polygons apart: a seam
    for name in primvars:
        pv = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(name, Sdf.ValueTypeNames.TexCoord2fArray,
                                                      UsdGeom.Tokens.faceVarying)
        pv.Set(Vt.Vec2fArray.FromNumpy(uv))
    if reads:
        mat = UsdShade.Material.Define(stage, "/World/Looks/Wood")
        frame = mat.CreateInput("frame:stPrimvarName", Sdf.ValueTypeNames.Token)
        frame.Set(reads)
        reader = UsdShade.Shader.Define(stage, "/World/Looks/Wood/uv")
        reader.CreateIdAttr("UsdPrimvarReader_float2")
        reader.CreateInput("varname", Sdf.ValueTypeNames.Token).ConnectToSource(frame)
        UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(mat)
    stage.GetRootLayer().Save()
    return uv


@pytest.mark.parametrize("primvars,reads,written", [
    (["map1"], None, "map1"),                 # a Maya export: its one UV primvar
    (["st", "uvA"], "uvA", "uvA"),            # the primvar its material reads
    (["map1"], "st0", "st0"),                 # what the material reads, though not held yet
])
def test_new_uvs_go_where_the_mesh_keeps_and_its_material_reads_them(tmp_path, primvars,
                                                                      reads, written):
    src, out, rep = str(tmp_path / "in.usda"), str(tmp_path / "o.usda"), tmp_path / "r.json"
    old = _grid_stage(src, primvars, reads)
    before = _tree_digest(tmp_path)
    assert main(["unwrap", src, "-o", out, "--report", str(rep)]) == 0
    assert _tree_digest(tmp_path) == {**before, **{k: v for k, v in _tree_digest(tmp_path)
                                                   .items() if k not in before}}
    (entry,) = json.loads(rep.read_text())["meshes"]
    assert entry["uv_name"] == written
    stage = Usd.Stage.Open(out)
    _check_st(stage, "/World/Grid", entry["bound_certified"], written)
    api = UsdGeom.PrimvarsAPI(stage.GetPrimAtPath("/World/Grid"))
    for name in set(primvars) - {written}:        # the others keep their values, none is added
        assert np.array_equal(np.asarray(api.GetPrimvar(name).Get()), old)
    assert sorted(pv.GetPrimvarName() for pv in api.GetPrimvarsWithValues()) == sorted(
        set(primvars) | {written})
    # the file's own UVs (the grid's two halves apart) gave the seams: two islands
    assert len(entry["islands"]) == (2 if written in primvars else 1)


def test_seams_uv_reads_a_maya_map1(tmp_path, capsys):
    src, out = str(tmp_path / "in.usda"), str(tmp_path / "o.usda")
    _grid_stage(src, ["map1"])
    assert main(["unwrap", src, "-o", out, "--seams", "uv", "--report",
                 str(tmp_path / "r.json")]) == 0
    (entry,) = json.loads((tmp_path / "r.json").read_text())["meshes"]
    assert entry["uv_name"] == "map1" and len(entry["islands"]) == 2
    # named explicitly, a primvar the mesh lacks still means no UVs to cut along
    assert main(["unwrap", src, "-o", str(tmp_path / "p.usda"), "--seams", "uv",
                 "--uv-name", "st"]) == 1
    assert "no UVs" in capsys.readouterr().err


def test_several_uv_primvars_and_no_material_write_st_and_say_so(tmp_path):
    src, out, rep = str(tmp_path / "in.usda"), str(tmp_path / "o.usda"), tmp_path / "r.json"
    _grid_stage(src, ["uvA", "uvB"])
    assert main(["unwrap", src, "-o", out, "--report", str(rep)]) == 0
    (entry,) = json.loads(rep.read_text())["meshes"]
    assert entry["uv_name"] == "st"
    assert any("uvA, uvB" in w and "--uv-name" in w for w in entry["warnings"])
    _check_st(Usd.Stage.Open(out), "/World/Grid", entry["bound_certified"])


def test_an_empty_mesh_prim_is_skipped_and_the_others_unwrapped(tmp_path, capsys):
    # a placeholder `def Mesh` with nothing authored (StandardShaderBall's layers hold one a
    # variant fills) had the whole stage refused as "a mesh without points"
    src, out, rep = str(tmp_path / "in.usda"), str(tmp_path / "o.usda"), tmp_path / "r.json"
    _grid_stage(src, ["st"])
    stage = Usd.Stage.Open(src)
    UsdGeom.Mesh.Define(stage, "/World/Placeholder")
    empty = UsdGeom.Mesh.Define(stage, "/World/Emptied")   # authored, but empty
    empty.CreatePointsAttr([])
    empty.CreateFaceVertexCountsAttr([])
    empty.CreateFaceVertexIndicesAttr([])
    stage.GetRootLayer().Save()
    assert main(["unwrap", src, "-o", out, "--report", str(rep)]) == 0
    (entry,) = json.loads(rep.read_text())["meshes"]
    assert entry["name"] == "/World/Grid" and entry["status"] == "certified"
    _check_st(Usd.Stage.Open(out), "/World/Grid", entry["bound_certified"])
    written = Usd.Stage.Open(out)
    for path in ("/World/Placeholder", "/World/Emptied"):
        assert not UsdGeom.PrimvarsAPI(written.GetPrimAtPath(path)).GetPrimvar("st")
    # a stage of empty meshes alone has nothing to unwrap, and says so
    only = Usd.Stage.CreateNew(str(tmp_path / "only.usda"))
    UsdGeom.Mesh.Define(only, "/Placeholder")
    only.GetRootLayer().Save()
    assert main(["unwrap", str(tmp_path / "only.usda"), "-o", str(tmp_path / "p.usda")]) == 2
    assert "holds no triangle or polygon mesh" in capsys.readouterr().err


def test_a_stage_without_a_shown_mesh_says_what_it_holds(tmp_path, capsys):
    # usd-wg/assets: CompositionPuzzles hold a Sphere prim; StandardShaderBall's
    # material_surface_geo/subdiv.usda defines its Mesh under an `over` only another layer defines
    src = tmp_path / "shapes.usda"
    stage = Usd.Stage.CreateNew(str(src))
    UsdGeom.Sphere.Define(stage, "/World/Ball")
    UsdGeom.Cube.Define(stage, "/World/Box")
    UsdGeom.Cube.Define(stage, "/World/Box2")
    over = Sdf.CreatePrimInLayer(stage.GetRootLayer(), "/Ball")   # an `over` (not defined)
    geo = Sdf.PrimSpec(over, "geo", Sdf.SpecifierDef, "Mesh")     # its child a `def Mesh`
    Sdf.AttributeSpec(geo, "points", Sdf.ValueTypeNames.Point3fArray).default = [
        (0, 0, 0), (1, 0, 0), (0, 1, 0)]
    Sdf.AttributeSpec(geo, "faceVertexCounts", Sdf.ValueTypeNames.IntArray).default = [3]
    Sdf.AttributeSpec(geo, "faceVertexIndices", Sdf.ValueTypeNames.IntArray).default = [0, 1, 2]
    assert over.specifier == Sdf.SpecifierOver
    hidden = UsdGeom.Mesh.Define(stage, "/World/Hidden")
    hidden.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    hidden.CreateFaceVertexCountsAttr([3])
    hidden.CreateFaceVertexIndicesAttr([0, 1, 2])
    hidden.GetPrim().SetActive(False)
    stage.GetRootLayer().Save()
    before = src.read_bytes()
    assert main(["unwrap", str(src), "-o", str(tmp_path / "o.usda")]) == 2
    err = capsys.readouterr().err
    assert "holds no triangle or polygon mesh" in err
    assert "2 Cube, 1 Sphere prim(s), which are not polygon meshes" in err
    assert "/Ball/geo" in err and "/World/Hidden" in err and "not part of the composed" in err
    assert not (tmp_path / "o.usda").exists() and src.read_bytes() == before
    # faces without points is not empty: still refused by name
    bad = Usd.Stage.CreateNew(str(tmp_path / "bad.usda"))
    UsdGeom.Mesh.Define(bad, "/Broken").CreateFaceVertexCountsAttr([3])
    bad.GetRootLayer().Save()
    # refused by name (exit 1); its only mesh, so nothing is written
    assert main(["unwrap", str(tmp_path / "bad.usda"), "-o", str(tmp_path / "q.usda")]) == 1
    assert "/Broken" in capsys.readouterr().err
    assert not (tmp_path / "q.usda").exists()


def test_topology_at_one_time_sample_and_no_default_is_read(tmp_path):
    """Houdini's exports and OpenUSD's animatedTop tutorial (top.geom.usd) author points,
    faceVertexCounts and faceVertexIndices at one time code, no default. The points were read
    at it; the topology was not, and such a mesh was refused as "a mesh without points,
    faceVertexCounts or faceVertexIndices"."""
    src, out = str(tmp_path / "in.usda"), str(tmp_path / "o.usda")
    _grid_stage(src, [])
    stage = Usd.Stage.Open(src)
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Grid"))
    for attr in (mesh.GetPointsAttr(), mesh.GetFaceVertexCountsAttr(),
                 mesh.GetFaceVertexIndicesAttr()):
        value = attr.Get()
        attr.Clear()
        attr.Set(value, 48)
    stage.GetRootLayer().Save()
    assert main(["unwrap", src, "-o", out, "-q"]) == 0
    _check_st(Usd.Stage.Open(out), "/World/Grid", 5.0, time=48)


def test_topology_only_time_sampled_is_named_as_changing(tmp_path, capsys):
    """OpenUSD's meshVaryingTopologyWithSharing.usda: faceVertexCounts and faceVertexIndices
    only as time samples, no default. It was refused as "a mesh without points,
    faceVertexCounts or faceVertexIndices", which it has; now its changing topology is named,
    and the stage's other mesh is unwrapped."""
    src, out = str(tmp_path / "in.usda"), str(tmp_path / "o.usda")
    _grid_stage(src, ["st"])
    stage = Usd.Stage.Open(src)
    m = UsdGeom.Mesh.Define(stage, "/World/Morphing")
    m.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)])
    for t, (counts, idx) in {1: ([3], [0, 1, 2]), 2: ([3, 3], [0, 1, 2, 0, 2, 3])}.items():
        m.CreateFaceVertexCountsAttr().Set(counts, t)
        m.CreateFaceVertexIndicesAttr().Set(idx, t)
    stage.GetRootLayer().Save()
    assert main(["unwrap", src, "-o", out]) == 1
    err = capsys.readouterr().err
    assert "/World/Morphing: faceVertexCounts is time-sampled (changing topology)" in err
    assert "without points" not in err
    _check_st(Usd.Stage.Open(out), "/World/Grid", 5.0)


def _textured_grid(layer, asset):
    """A grid stage at ``layer`` whose mesh names ``asset`` (an asset path attribute)."""
    _grid_stage(str(layer), ["st"])
    stage = Usd.Stage.Open(str(layer))
    stage.GetPrimAtPath("/World/Grid").CreateAttribute(
        "info:texture", Sdf.ValueTypeNames.Asset).Set(Sdf.AssetPath(asset))
    stage.GetRootLayer().Save()


def _package(path, files):
    """A .usdz of ``files`` {path inside: file}, the first its root layer, as USD writes one."""
    z = Sdf.ZipFileWriter.CreateNew(str(path))
    for inside, f in files.items():
        z.AddFile(str(f), inside)
    z.Save()


def test_a_package_whose_root_layer_is_in_a_folder_keeps_its_texture(tmp_path):
    """OpenUSD's nestedUsdz/simpleMaterial.usdz holds simpleMaterial.usdz_FILES/simpleMaterial.usdc
    and simpleMaterial.usdz_FILES/0/USDLogoLrg.png, which the layer names "0/USDLogoLrg.png".
    The texture was unpacked at its path from the package's top, where the new layer did not
    find it: "the .usdz package could not be written", nothing written."""
    (tmp_path / "FILES" / "0").mkdir(parents=True)
    layer, tex = tmp_path / "FILES" / "pkg.usdc", tmp_path / "FILES" / "0" / "tex.png"
    tex.write_bytes(b"\x89PNG not really")
    _textured_grid(layer, "0/tex.png")
    src, out = tmp_path / "pkg.usdz", tmp_path / "o" / "out.usdz"
    _package(src, {"pkg.usdz_FILES/pkg.usdc": layer, "pkg.usdz_FILES/0/tex.png": tex})
    assert main(["unwrap", str(src), "-o", str(out), "-q"]) == 0
    import zipfile
    with zipfile.ZipFile(out) as z:
        assert z.read("0/tex.png") == tex.read_bytes()
    _check_st(Usd.Stage.Open(str(out)), "/World/Grid", 5.0)


def test_a_package_of_packages_in_a_folder_is_written(tmp_path):
    """OpenUSD's nestedUsdz/combined.usdz: combined.usdz_FILES/combined.usda references
    simpleMesh.usdz beside it in the package. Main ended in a traceback, "RuntimeError:
    Accessed schema on invalid prim" (the copied layer's reference found nothing)."""
    inner = tmp_path / "mesh.usdc"
    _grid_stage(str(inner), ["st"])
    grid = Usd.Stage.Open(str(inner))
    grid.SetDefaultPrim(grid.GetPrimAtPath("/World"))
    grid.GetRootLayer().Save()
    _package(tmp_path / "mesh.usdz", {"mesh.usdc": inner})
    root = tmp_path / "root.usda"
    stage = Usd.Stage.CreateNew(str(root))
    stage.DefinePrim("/Asset").GetReferences().AddReference("mesh.usdz")
    stage.GetRootLayer().Save()
    src, out = tmp_path / "pkg.usdz", tmp_path / "o" / "out.usdz"
    _package(src, {"pkg.usdz_FILES/root.usda": root,
                   "pkg.usdz_FILES/mesh.usdz": tmp_path / "mesh.usdz"})
    assert main(["unwrap", str(src), "-o", str(out), "-q"]) == 0
    _check_st(Usd.Stage.Open(str(out)), "/Asset/Grid", 5.0)


def test_a_package_naming_a_missing_asset_says_which(tmp_path, capsys):
    """OpenUSD's usdUdims.usdz names texture_<UDIM>.jpg, which it does not hold: no package can
    be written, and the message now names the asset instead of only "could not be written"."""
    layer = tmp_path / "pkg.usdc"
    _textured_grid(layer, "./gone.png")
    src, out = tmp_path / "pkg.usdz", tmp_path / "o" / "out.usdz"
    _package(src, {"pkg.usdc": layer})
    assert main(["unwrap", str(src), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert "could not be written: 1 asset(s) the scene references resolve to no file (gone.png)" \
        in err
    assert not out.exists()


def test_a_fan_diagonal_along_another_polygons_side_is_turned_away(tmp_path):
    # A cube whose last side is a non-planar pentagon through a ninth point: fanned from its
    # first corner, its diagonal 2-0 runs along the side 0-2 of the quad (0, 4, 6, 2), an edge of
    # three triangles, and the pentagon was split across islands (written UVs 33x off the
    # bound). Fanned from its second corner (3), no diagonal is an edge of the mesh.
    P = np.array([[-.5, -.5, -.5], [.5, -.5, -.5], [-.5, .5, -.5], [.5, .5, -.5], [-.5, -.5, .5],
                  [.5, -.5, .5], [-.5, .5, .5], [.5, .5, .5], [.7, .7, .7]])
    polys = [[0, 4, 6, 2], [0, 1, 5, 4], [4, 5, 7, 6], [3, 7, 5, 1], [6, 7, 3, 2],
             [2, 3, 1, 0, 8]]
    src, out, rep = str(tmp_path / "in.usda"), str(tmp_path / "o.usda"), tmp_path / "r.json"
    stage = Usd.Stage.CreateNew(src)
    mesh = UsdGeom.Mesh.Define(stage, "/Box")
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(P.astype(np.float32)))
    mesh.CreateFaceVertexCountsAttr([len(q) for q in polys])
    mesh.CreateFaceVertexIndicesAttr([v for q in polys for v in q])
    stage.GetRootLayer().Save()
    assert main(["unwrap", src, "-o", out, "--report", str(rep)]) == 0
    (entry,) = json.loads(rep.read_text())["meshes"]
    assert entry["status"] == "certified"
    written = Usd.Stage.Open(out)
    pv = UsdGeom.PrimvarsAPI(written.GetPrimAtPath("/Box")).GetPrimvar("st")
    uv = np.asarray(pv.Get(), np.float64)[np.asarray(pv.GetIndices())]      # per face-vertex
    # this test's own triangles in face-vertex ids: the quads fanned from their first corner,
    # the pentagon (face-vertices 20..24 = points 2, 3, 1, 0, 8) from its second
    T = [(4 * q, 4 * q + i, 4 * q + i + 1) for q in range(5) for i in (1, 2)]
    T += [(21, 22, 23), (21, 23, 24), (21, 24, 20)]
    T = np.array(T)
    idx = np.array([v for q in polys for v in q])
    D, flipped = reference_distortion(P, idx[T], uv[T])
    assert not flipped.any() and D.max() <= entry["bound_certified"] * (1 + 1e-9)
    assert len(overlapping_triangle_pairs(uv[T])) == 0


def _fan(counts):
    """This test's own fan triangulation: (t,3) face-vertex positions."""
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    return np.array([(s, s + i, s + i + 1) for s, c in zip(start, counts)
                     for i in range(1, c - 1)])


def test_instanced_meshes_are_unwrapped_once_per_prototype(tmp_path):
    """Production USD instances its assets (usd-wg's teapotScene: 524 instanceable teapots, 133
    prototypes, were refused). A prototype's mesh is unwrapped once; its UVs go on a class of the
    output layer that every instance inherits (USD allows no opinion on an instance proxy), an
    instance nested in another instanced prim through its place under the outer prototype's
    class: every proxy composes them, certified here from the written stage; the instances still
    share their prototypes; the asset file is untouched."""
    V, counts, idx = quad_grid(6, 5)
    asset = Usd.Stage.CreateNew(str(tmp_path / "rock.usda"))
    root = UsdGeom.Xform.Define(asset, "/Rock")
    asset.SetDefaultPrim(root.GetPrim())
    m = UsdGeom.Mesh.Define(asset, "/Rock/geo/body")
    m.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(V.astype(np.float32)))
    m.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts.astype(np.int32)))
    m.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(idx.astype(np.int32)))
    asset.GetRootLayer().Save()
    asset_bytes = (tmp_path / "rock.usda").read_bytes()
    stage = Usd.Stage.CreateNew(str(tmp_path / "shot.usda"))
    for i in range(4):
        p = UsdGeom.Xform.Define(stage, f"/World/Rock{i}").GetPrim()
        p.GetReferences().AddReference("./rock.usda")
        p.SetInstanceable(True)
        UsdGeom.XformCommonAPI(p).SetTranslate((3.0 * i, 0.0, 0.0))
    stage.DefinePrim("/Group")                       # instanced, and holding an instance
    inner = stage.DefinePrim("/Group/Inner")
    inner.GetReferences().AddReference("./rock.usda")
    inner.SetInstanceable(True)
    for i in range(2):
        p = stage.DefinePrim(f"/World/Group{i}")
        p.GetReferences().AddInternalReference("/Group")
        p.SetInstanceable(True)
    stage.GetRootLayer().Save()
    out, rep = tmp_path / "out" / "shot.usda", tmp_path / "r.json"
    assert main(["unwrap", str(tmp_path / "shot.usda"), "-o", str(out), "--report",
                 str(rep)]) == 0
    (done,) = json.loads(rep.read_text())["meshes"]
    assert done["status"] == "certified" and done["name"] == "/Group/Inner/geo/body"
    assert done["instances"] == 6          # /Group/Inner, 4 rocks, the one in Group's prototype
    assert (tmp_path / "rock.usda").read_bytes() == asset_bytes
    before = Usd.Stage.Open(str(tmp_path / "shot.usda"))
    written = Usd.Stage.Open(str(out))
    assert len(written.GetPrototypes()) == len(before.GetPrototypes())
    protos = {written.GetPrimAtPath(f"/World/Rock{i}").GetPrototype().GetPath()
              for i in range(4)}
    assert len(protos) == 1                                    # still one shared prototype
    T = _fan(counts)
    for path in [f"/World/Rock{i}/geo/body" for i in range(4)] + [
            "/Group/Inner/geo/body", "/World/Group0/Inner/geo/body",
            "/World/Group1/Inner/geo/body"]:
        proxy = written.GetPrimAtPath(path)
        assert proxy.IsInstanceProxy()
        pv = UsdGeom.PrimvarsAPI(proxy).GetPrimvar("st")
        assert pv.GetInterpolation() == UsdGeom.Tokens.faceVarying
        uv = np.asarray(pv.ComputeFlattened(), np.float64)
        P = V.astype(np.float32).astype(np.float64)[idx]
        D, flipped = reference_distortion(P, T, uv[T])
        assert not flipped.any() and D.max() <= done["bound_certified"] * (1 + 1e-9)
        assert len(overlapping_triangle_pairs(uv[T])) == 0


def test_an_instanced_asset_whose_uvs_have_another_type_keeps_them(tmp_path):
    """Outside an instance a primvar of another type is replaced (with a warning); in an instanced
    asset it cannot be removed, so the mesh is refused by name and nothing of it is written."""
    V, counts, idx = quad_grid(4, 3, bump=False)
    asset = Usd.Stage.CreateNew(str(tmp_path / "tile.usda"))
    asset.SetDefaultPrim(UsdGeom.Xform.Define(asset, "/Tile").GetPrim())
    m = UsdGeom.Mesh.Define(asset, "/Tile/body")
    m.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(V.astype(np.float32)))
    m.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts.astype(np.int32)))
    m.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(idx.astype(np.int32)))
    UsdGeom.PrimvarsAPI(m.GetPrim()).CreatePrimvar(
        "st", Sdf.ValueTypeNames.Float2Array, UsdGeom.Tokens.vertex).Set(
        Vt.Vec2fArray.FromNumpy(V[:, :2].astype(np.float32)))
    asset.GetRootLayer().Save()
    stage = Usd.Stage.CreateNew(str(tmp_path / "floor.usda"))
    for i in range(3):
        p = stage.DefinePrim(f"/Floor/Tile{i}")
        p.GetReferences().AddReference("./tile.usda")
        p.SetInstanceable(True)
    stage.GetRootLayer().Save()
    out, rep = tmp_path / "o.usda", tmp_path / "r.json"
    assert main(["unwrap", str(tmp_path / "floor.usda"), "-o", str(out), "--report", str(rep),
                 "--seams", "none"]) == 1
    (entry,) = json.loads(rep.read_text())["meshes"]
    assert entry["status"] == "failed" and "float2[]" in entry["message"]
    assert not out.exists()


def test_an_asset_on_another_drive_is_kept_by_its_absolute_path(tmp_path, monkeypatch):
    # Windows: os.path.relpath raises ValueError across drives; USD resolves absolute asset
    # paths, so the texture is re-anchored by its absolute path and still resolves
    src = tmp_path / "in"
    shot, asset = build_stage(str(src))
    monkeypatch.setattr(os.path, "relpath", relpath_across_drives("wood.png"))
    out = tmp_path / "elsewhere" / "shot_uv.usda"
    assert main(["unwrap", shot, "-o", str(out), "--bound", "3"]) == 0
    stage = Usd.Stage.Open(str(out))
    tex = stage.GetPrimAtPath("/World/Looks/Wood/Tex").GetAttribute("inputs:file").Get()
    assert os.path.isabs(tex.path)
    assert os.path.samefile(tex.resolvedPath, src / "lib" / "tex" / "wood.png")
