"""``--group material|object`` on the command line and the batch: the OBJ's ``usemtl`` and ``o``
give each face's group; the written UVs (read back) keep each group's charts in one region that
no other group's chart enters, checked here with shapely on the file's UVs."""
import json

import numpy as np
import pytest
import shapely

from bd_uv import cli
from bd_uv.meshio import load_mesh
from packing_sets import least_gap
from test_packing_cli import grids

SIZES = ((5, 3), (8, 2), (3, 3), (6, 6), (2, 9), (4, 1), (3, 5), (7, 2))


def grouped_obj(tmp_path, key):
    """The grids as an OBJ whose grids alternate between three materials (``usemtl``) or three
    objects (``o``). Returns the path and each face's group."""
    src, V, F = grids(tmp_path, SIZES)
    per = [2 * a * b for a, b in SIZES]
    group = np.repeat(np.arange(len(SIZES)) % 3, per)
    path = tmp_path / "grouped.obj"
    with open(path, "w") as fh:
        fh.writelines(f"v {x!r} {y!r} {z!r}\n" for x, y, z in V.tolist())
        last = None
        for f, g in zip(F, group):
            if g != last:
                fh.write(f"{key} part{g}\n")
                last = g
            fh.write(f"f {f[0] + 1} {f[1] + 1} {f[2] + 1}\n")
    return path, group


def assert_one_region_per_group(uv, group, pad_uv):
    names = np.unique(group)
    hulls = [shapely.convex_hull(shapely.multipoints(uv[group == g].reshape(-1, 2)))
             for g in names]
    assert len(names) >= 2
    for a, g in enumerate(names):
        for b in range(a + 1, len(hulls)):
            assert hulls[a].distance(hulls[b]) >= pad_uv * (1 - 1e-4)
        others = shapely.polygons(uv[group != g])
        assert not shapely.intersects(hulls[a], others).any()


@pytest.mark.parametrize("key, name", [("usemtl", "material"), ("o", "object")])
def test_unwrap_groups_charts_by_the_obj_material_or_object(tmp_path, key, name):
    src, group = grouped_obj(tmp_path, key)
    out, rep = tmp_path / "g.obj", tmp_path / "g.json"
    code = cli.main(["unwrap", str(src), "-o", str(out), "--seams", "none", "--bound", "3",
                     "--resolution", "512", "--padding", "6", "--group", name,
                     "--pack-seconds", "1", "--report", str(rep)])
    assert code == 0
    pack = json.loads(rep.read_text())["pack"]
    assert pack["certified"] and pack["group"] == name
    uv = load_mesh(out).corner_uv
    assert_one_region_per_group(uv, group, 6 / 512)
    lab = np.repeat(np.arange(len(SIZES)), [2 * a * b for a, b in SIZES])
    assert least_gap(uv, lab, reach=12 / 512) * 512 >= 6 * (1 - 1e-6)
    assert uv.min() >= 3 / 512 * (1 - 1e-6) and uv.max() <= 1 - 3 / 512 * (1 - 1e-6)


def test_group_of_a_format_without_it_is_a_clear_failure(tmp_path, capsys):
    src, _, _ = grids(tmp_path)                 # OFF: no materials, no objects
    out = tmp_path / "g.obj"
    code = cli.main(["unwrap", str(src), "-o", str(out), "--seams", "none", "--bound", "3",
                     "--group", "material"])
    assert code != 0
    assert "needs each face's material" in capsys.readouterr().err
    assert not out.exists()
    assert cli.main(["unwrap", str(src), "-o", str(out), "--no-pack", "--group", "object"]) == 2


def test_batch_groups_by_material(tmp_path):
    src, group = grouped_obj(tmp_path, "usemtl")
    outdir = tmp_path / "out"
    code = cli.main(["batch", str(src), "-o", str(outdir), "--seams", "none", "--bound", "3",
                     "--group", "material", "--pack-seconds", "0.5", "--jobs", "1"])
    assert code == 0
    entry = json.loads((outdir / "report.json").read_text())["items"][0]
    assert entry["pack"]["certified"] and entry["pack"]["group"] == "material"
    assert json.loads((outdir / "report.json").read_text())["options"]["group"] == "material"
    written = sorted(outdir.glob("*.obj"))
    assert len(written) == 1
    assert_one_region_per_group(load_mesh(written[0]).corner_uv, group, 4 / 1024)


def test_gltf_primitive_materials_group_the_charts(tmp_path):
    """A glTF mesh of three separate grids in three primitives (materials 1, 0 and none): each
    face's material is its primitive's, and ``--group material`` packs the mesh certified."""
    from gltf_build import Builder
    from helpers import grid
    from bd_uv.scenes import read_scene
    b = Builder()
    prims, group = [], []
    for j, material in enumerate((1, 0, None)):
        V, F = grid(5 + j, 4, z=lambda x, y: 0.2 * x * y)
        V = V + [2.0 * j, 0, 0]
        p = {"attributes": {"POSITION": b.accessor(V.astype(np.float32), 5126, "VEC3",
                                                   minmax=True)},
             "indices": b.accessor(F.reshape(-1), 5125, "SCALAR"), "mode": 4}
        if material is not None:
            p["material"] = material
        prims.append(p)
        group.append(np.full(len(F), -1 if material is None else material))
    b.doc.update(meshes=[{"primitives": prims}], nodes=[{"mesh": 0}], scenes=[{"nodes": [0]}],
                 scene=0, materials=[{"name": "a"}, {"name": "b"}])
    path = tmp_path / "three.gltf"
    b.write(str(path))
    mesh = read_scene(str(path)).meshes[0].mesh
    assert np.array_equal(mesh.labels["material"], np.concatenate(group))
    assert np.array_equal(mesh.labels["object"], np.zeros(len(mesh.F)))
    out, rep = tmp_path / "out.gltf", tmp_path / "r.json"
    code = cli.main(["unwrap", str(path), "-o", str(out), "--seams", "none", "--bound", "3",
                     "--group", "material", "--pack-seconds", "0.5", "--report", str(rep)])
    assert code == 0
    entry = json.loads(rep.read_text())["meshes"][0]
    assert entry["status"] == "certified" and len(entry["islands"]) == 3
    assert entry["pack"]["certified"] and entry["pack"]["group"] == "material"
    back = read_scene(str(out)).meshes[0].mesh          # float32 as the file stores
    assert_one_region_per_group(back.corner_uv, back.labels["material"], 4 / 1024)


def test_usd_material_subsets_group_the_charts(tmp_path):
    """A USD mesh of three separate grids: the faces of the first two in two "materialBind"
    GeomSubsets (one material each), the third in none. Each face's material is its subset's,
    and ``--group material`` writes each material's charts in a region of their own."""
    from pxr import Usd, UsdGeom, UsdShade, Vt
    from bd_uv.scenes import read_scene
    from usd_build import quad_grid
    grids = [quad_grid(6, 5, bump=False), quad_grid(5, 4, bump=False), quad_grid(4, 4, False)]
    V = np.vstack([g[0] + [3.0 * j, 0, 0] for j, g in enumerate(grids)])
    first = np.cumsum([0] + [len(g[0]) for g in grids])
    counts = np.concatenate([g[1] for g in grids])
    idx = np.concatenate([g[2] + first[j] for j, g in enumerate(grids)])
    face_of = np.repeat(np.arange(3), [len(g[1]) for g in grids])
    path = str(tmp_path / "three.usda")
    stage = Usd.Stage.CreateNew(path)
    mesh = UsdGeom.Mesh.Define(stage, "/Three")
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(V.astype(np.float32)))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts.astype(np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(idx.astype(np.int32)))
    binding = UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim())
    for j in range(2):
        mat = UsdShade.Material.Define(stage, f"/Looks/M{j}")
        faces = np.flatnonzero(face_of == j)
        subset = binding.CreateMaterialBindSubset(f"part{j}", Vt.IntArray(faces.tolist()))
        UsdShade.MaterialBindingAPI.Apply(subset.GetPrim()).Bind(mat)
    stage.GetRootLayer().Save()
    m = read_scene(path).meshes[0].mesh
    per_triangle = np.repeat(np.where(face_of < 2, face_of, -1), counts - 2)   # quads: 2 each
    assert np.array_equal(m.labels["material"], per_triangle)
    out, rep = tmp_path / "out.usda", tmp_path / "r.json"
    code = cli.main(["unwrap", path, "-o", str(out), "--seams", "none", "--bound", "3",
                     "--group", "material", "--pack-seconds", "0.5", "--report", str(rep)])
    assert code == 0
    entry = json.loads(rep.read_text())["meshes"][0]
    assert entry["pack"]["certified"] and entry["pack"]["group"] == "material"
    back = read_scene(str(out)).meshes[0].mesh
    assert_one_region_per_group(back.corner_uv, back.labels["material"], 4 / 1024)
