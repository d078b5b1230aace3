"""FBX (and the other formats only Blender reads) through scripts/bd_uv_batch.py: Blender's own
importer and exporter around the unwrap. The FBX is exported here, run through the script and
read back; the UVs read back are checked independently (SVD per triangle)."""
import hashlib
import json
import subprocess
import sys

import numpy as np
import pytest

from conftest import REPO_ROOT, add_grid, loop_uv_array, triangle_distortion

bpy = pytest.importorskip("bpy")

SCRIPT = REPO_ROOT / "scripts" / "bd_uv_batch.py"


def _figures(obj):
    """Per loop triangle: distortion and det of the active UV map, with the object's scale."""
    mesh = obj.data
    mesh.calc_loop_triangles()
    n = len(mesh.loop_triangles)
    verts, loops = np.empty(3 * n, np.int32), np.empty(3 * n, np.int32)
    mesh.loop_triangles.foreach_get("vertices", verts)
    mesh.loop_triangles.foreach_get("loops", loops)
    co = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", co)
    V = co.reshape(-1, 3).astype(np.float64) * np.abs(np.array(obj.scale))
    uv = loop_uv_array(mesh)
    return triangle_distortion(V, verts.reshape(-1, 3), uv[loops.reshape(-1, 3)].astype(float))


@pytest.fixture
def scene_fbx(tmp_path, empty_scene):
    a = add_grid(7, 6)
    a.name = "Sheet"
    b = add_grid(5, 4, size=1.0)
    b.name = "Tile"
    b.location = (3, 0, 0)
    b.scale = (1.0, 1.7, 1.0)
    path = tmp_path / "in" / "props.fbx"
    path.parent.mkdir()
    assert bpy.ops.export_scene.fbx(filepath=str(path)) == {'FINISHED'}
    return path


def test_fbx_through_the_script_and_back(scene_fbx, tmp_path):
    digest = hashlib.sha256(scene_fbx.read_bytes()).hexdigest()
    out, report = tmp_path / "out" / "props.fbx", tmp_path / "r.json"
    proc = subprocess.run([sys.executable, str(SCRIPT), str(scene_fbx), "--", "--bound", "2",
                           "--output", str(out), "--report", str(report)],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert hashlib.sha256(scene_fbx.read_bytes()).hexdigest() == digest     # input untouched
    items = {e["object"]: e for e in json.loads(report.read_text())["items"]}
    assert set(items) == {"Sheet", "Tile"}
    bpy.ops.wm.read_factory_settings(use_empty=True)
    assert bpy.ops.import_scene.fbx(filepath=str(out)) == {'FINISHED'}
    for name, entry in items.items():
        assert entry["status"] == "certified" and entry["output"] == str(out)
        D, det = _figures(bpy.data.objects[name])
        assert (det > 0).all()
        assert D.max() <= entry["bound_certified"] * (1 + 1e-6)
        assert entry["bound_certified"] <= 2.0


def test_stl_has_no_uvs_and_bad_outputs_are_refused(scene_fbx, tmp_path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    add_grid()
    stl = tmp_path / "g.stl"
    assert bpy.ops.wm.stl_export(filepath=str(stl)) == {'FINISHED'}
    proc = subprocess.run([sys.executable, str(SCRIPT), str(stl), "--", "--output",
                           str(tmp_path / "o.stl")], capture_output=True, text=True)
    assert proc.returncode == 2 and "STL stores no UVs" in proc.stderr
    proc = subprocess.run([sys.executable, str(SCRIPT), str(stl), "--", "--output",
                           str(tmp_path / "o.blend"), "--report", str(tmp_path / "r.json")],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "o.blend").is_file()
    proc = subprocess.run([sys.executable, str(SCRIPT), str(scene_fbx), "--"],
                          capture_output=True, text=True)
    assert proc.returncode == 2 and "pass --output" in proc.stderr


def test_folder_batch_runs_fbx_through_the_script(scene_fbx, tmp_path):
    out = tmp_path / "batch"
    proc = subprocess.run([sys.executable, "-m", "bd_uv", "batch", str(scene_fbx.parent), "-o",
                           str(out), "--bound", "2", "--jobs", "1"], capture_output=True,
                          text=True, cwd=REPO_ROOT)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    items = json.loads((out / "report.json").read_text())["items"]
    assert {e["object"] for e in items} == {"Sheet", "Tile"}
    assert all(e["output"] == str(out / "props.fbx") for e in items)
    assert (out / "props.fbx").is_file()
