"""The built linux-x64 zip installs in a fresh Blender, loads its bundled wheels, unwraps a mesh.

What a user does with Edit > Preferences > Get Extensions > Install from Disk, done headless through
the ``bpy`` module in a child process:

- ``BLENDER_USER_RESOURCES`` points at an empty directory, so Blender starts with a fresh user
  config and extension repositories, and nothing leaks into this test session.
- The child sees an environment like Blender's own Python: numpy yes, but none of the packages the
  zip bundles (scipy, clarabel, cffi, pycparser, trimesh, shapely, qdldl): they are hidden from its
  ``sys.path``.
  So the add-on can only work if Blender installed the zip's wheels into the extensions'
  ``.local/lib/python3.11/site-packages`` and the add-on imported them from there, which the child
  checks module by module.
- ``bpy.ops.extensions.package_install_files`` installs and enables the zip, then
  ``bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=1.6)`` unwraps a grid raised into a bump, in Edit
  Mode, where Blender's own conformal unwrap exceeds that bound. The written UVs are read back and
  their conformal distortion recomputed here from first principles.

The child runs this test's Python (bpy 5.0.1: Python 3.11, the zip for Blender 4.2 to 5.0). Other
Blender modules can be added through ``BD_UV_BPY_PYTHONS``, a ``os.pathsep``-separated list of
Python interpreters that each have a ``bpy`` (and numpy) installed, e.g. a Python 3.11 venv with
``bpy==4.2.0 numpy==1.24.3`` (the oldest supported Blender) or a Python 3.13 venv with
``bpy==5.1.2 numpy==2.3.4`` (which gets the py313 zip). Each runs the same checks with the zip for
its Python, and checks that the other Python's zip is refused.
"""
import json
import os
import pathlib
import platform
import subprocess
import sys
import zipfile

import numpy as np
import pytest

from conftest import triangle_distortion

pytestmark = pytest.mark.skipif(
    not (sys.platform.startswith("linux") and platform.machine() == "x86_64"),
    reason="the zip under test is linux-x64")

CHILD = r'''
import json, os, sys

# An environment like Blender's own Python: hide the bundled packages from sys.path by replacing
# each site-packages directory with a directory of links to everything else in it.
blocked = set(json.loads(os.environ["BD_UV_HIDE"]))
shim = os.environ["BD_UV_SHIM"]
os.makedirs(shim)
site_dirs = [p for p in sys.path if os.path.basename(p.rstrip(os.sep)) == "site-packages"]
def stem(name):
    return name.split(".")[0].split("-")[0].lower().replace("-", "_")
for site_dir in site_dirs:
    for name in os.listdir(site_dir):
        link = os.path.join(shim, name)
        if stem(name) not in blocked and not os.path.lexists(link):
            os.symlink(os.path.join(site_dir, name), link)
sys.path[:] = [p for p in sys.path if p not in site_dirs] + [shim]
for name in blocked:
    try:
        __import__(name)
    except ImportError:
        pass
    else:
        raise SystemExit(f"{name} is still importable before the install")

import bpy
import numpy as np

out = {"numpy": np.__file__}
result = bpy.ops.extensions.package_install_files(
    filepath=os.environ["BD_UV_ZIP"], repo="user_default", enable_on_install=True)
out["install"] = sorted(result)
out["addons"] = [a.module for a in bpy.context.preferences.addons]
out["site_packages"] = os.path.join(
    bpy.utils.user_resource("EXTENSIONS"), ".local", "lib",
    "python{}.{}".format(*sys.version_info[:2]), "site-packages")
out["modules"] = {}
for name in sorted(blocked):
    module = __import__(name)
    out["modules"][name] = [module.__file__, getattr(module, "__version__", None)]
out["operator"] = "bd_unwrap" in dir(bpy.ops.uv)

# A 7 x 6 grid raised into a bump (an open disk), first unwrapped by Blender's own conformal
# method, then by bd-uv with a bound C = 1.6 that Blender's map exceeds.
for obj in list(bpy.data.objects):
    bpy.data.objects.remove(obj)
bpy.ops.mesh.primitive_grid_add(x_subdivisions=7, y_subdivisions=6, size=2.0)
obj = bpy.context.active_object
mesh = obj.data
co = np.empty(len(mesh.vertices) * 3, np.float32)
mesh.vertices.foreach_get("co", co)
co = co.reshape(-1, 3)
co[:, 2] = 1.6 * np.exp(-2.0 * (co[:, 0] ** 2 + co[:, 1] ** 2))
mesh.vertices.foreach_set("co", co.ravel())
mesh.update()
def loop_uvs():
    uv = np.empty(len(mesh.loops) * 2, np.float32)
    mesh.uv_layers.active.uv.foreach_get("vector", uv)
    return uv.reshape(-1, 2)
bpy.ops.object.mode_set(mode="EDIT")
bpy.ops.mesh.select_all(action="SELECT")
bpy.ops.uv.unwrap(method="CONFORMAL", margin=0.0)
bpy.ops.object.mode_set(mode="OBJECT")
before = loop_uvs()
bpy.ops.object.mode_set(mode="EDIT")
out["unwrap"] = sorted(bpy.ops.uv.bd_unwrap("EXEC_DEFAULT", bound=1.6, pack=False))
bpy.ops.object.mode_set(mode="OBJECT")
after = loop_uvs()
mesh.calc_loop_triangles()
tri_loops = np.empty(len(mesh.loop_triangles) * 3, np.int32)
mesh.loop_triangles.foreach_get("loops", tri_loops)
tri_verts = np.empty(len(mesh.loop_triangles) * 3, np.int32)
mesh.loop_triangles.foreach_get("vertices", tri_verts)
co = np.empty(len(mesh.vertices) * 3, np.float32)
mesh.vertices.foreach_get("co", co)
last = bpy.context.window_manager.bd_uv_last_result
out["last"] = {k: getattr(last, k) for k in
               ("valid", "islands", "failed", "faces", "max_distortion", "flipped",
                "bound_certified")}
out["V"] = co.reshape(-1, 3).tolist()
out["tris"] = tri_verts.reshape(-1, 3).tolist()
out["tri_loops"] = tri_loops.reshape(-1, 3).tolist()
out["before"] = before.tolist()
out["after"] = after.tolist()
print("BD_UV_RESULT " + json.dumps(out))
'''


REFUSE_CHILD = r'''
import json, os, sys
import bpy
result = bpy.ops.extensions.package_install_files(
    filepath=os.environ["BD_UV_ZIP"], repo="user_default", enable_on_install=True)
repo = os.path.join(bpy.utils.user_resource("EXTENSIONS"), "user_default")
installed = sorted(os.listdir(repo)) if os.path.isdir(repo) else []
print("BD_UV_RESULT " + json.dumps({
    "addons": [a.module for a in bpy.context.preferences.addons],
    "installed": [n for n in installed if not n.startswith(".")],
    "site_packages": os.path.isdir(os.path.join(bpy.utils.user_resource("EXTENSIONS"), ".local")),
}))
'''


def run_child(interpreter, script, env_extra, tmp):
    env = dict(os.environ)
    env.update(BLENDER_USER_RESOURCES=str(tmp / "user"), PYTHONNOUSERSITE="1", **env_extra)
    env.pop("PYTHONPATH", None)
    env.pop("PYENV_VERSION", None)
    proc = subprocess.run([interpreter, "-c", script], env=env, capture_output=True, text=True,
                          cwd=tmp)
    lines = [l for l in proc.stdout.splitlines() if l.startswith("BD_UV_RESULT ")]
    assert proc.returncode == 0 and lines, \
        f"child failed:\n{proc.stdout[-4000:]}\n{proc.stderr[-4000:]}"
    return json.loads(lines[-1][len("BD_UV_RESULT "):]), proc.stdout + proc.stderr


def hidden_packages(zip_path):
    """Top-level import names inside the zip's wheels (scipy, _cffi_backend, cffi, ...)."""
    names = set()
    with zipfile.ZipFile(zip_path) as outer:
        for wheel in (n for n in outer.namelist() if n.startswith("wheels/") and n != "wheels/"):
            with outer.open(wheel) as fh, zipfile.ZipFile(fh) as inner:
                for entry in inner.namelist():
                    top = entry.split("/", 1)[0]
                    if not top.endswith((".dist-info", ".libs", ".data")):
                        names.add(top.split(".")[0])
    return sorted(names)


def interpreters():
    """This test's Python, then those in ``BD_UV_BPY_PYTHONS``."""
    extra = [p for p in os.environ.get("BD_UV_BPY_PYTHONS", "").split(os.pathsep) if p]
    return [sys.executable] + extra


def python_version(interpreter):
    out = subprocess.run([interpreter, "-c", "import sys; print('%d.%d' % sys.version_info[:2])"],
                         capture_output=True, text=True, check=True)
    return out.stdout.strip()


@pytest.fixture(scope="module", params=interpreters(),
                ids=lambda p: "this-python" if p == sys.executable else p)
def interpreter(request):
    return request.param


@pytest.fixture(scope="module")
def installed(interpreter, linux_extension_zips, tmp_path_factory):
    """Output of the child process that installs the zip and runs the operator."""
    python = python_version(interpreter)
    zip_path = linux_extension_zips[python]
    tmp = tmp_path_factory.mktemp("blender_user")
    result, log = run_child(interpreter, CHILD, {
        "BD_UV_ZIP": str(zip_path), "BD_UV_SHIM": str(tmp / "site"),
        "BD_UV_HIDE": json.dumps(hidden_packages(zip_path))}, tmp)
    result["python"] = python
    result["log"] = log
    return result


def test_zip_installs_and_enables(installed):
    assert installed["install"] == ["FINISHED"]
    assert "bl_ext.user_default.bd_uv" in installed["addons"]
    assert installed["operator"]


def test_bundled_wheels_are_the_ones_imported(installed):
    site = pathlib.Path(installed["site_packages"])
    assert set(installed["modules"]) == {"scipy", "clarabel", "cffi", "_cffi_backend", "pycparser",
                                         "trimesh", "shapely", "qdldl", "spyrrow"}
    for name, (path, _version) in installed["modules"].items():
        assert pathlib.Path(path).is_relative_to(site), (name, path)
    # scipy built for this Python; numpy is Blender's (here: the environment's).
    # requirements.txt pins scipy per Python (1.15.3 for 3.11, 1.17.1 for 3.13: numpy < 2.7)
    pins = (pathlib.Path(__file__).resolve().parents[2] / "requirements.txt").read_text()
    want = "1.17.1" if installed["python"] == "3.13" else "1.15.3"
    assert f"scipy=={want}" in pins
    assert installed["modules"]["scipy"][1] == want
    tag = installed["python"].replace(".", "")
    assert site.parts[-2] == f"python{installed['python']}"
    assert list((site / "scipy" / "_lib").glob(f"*.cpython-{tag}-*.so"))
    so_files = list((site / "scipy" / "_lib").glob("*.so"))
    assert [p for p in so_files if f"cpython-{tag}-" not in p.name] == []
    assert not (site / "numpy").exists()
    assert not pathlib.Path(installed["numpy"]).is_relative_to(site)


def test_bundled_wheels_import_without_warnings(installed):
    # scipy 1.15.3 under numpy 2.5 (Blender 5.2) printed "A NumPy version >=1.23.5 and <2.5.0
    # is required for this version of SciPy": each zip's scipy must accept Blender's numpy.
    assert "NumPy version" not in installed["log"], installed["log"][-2000:]
    assert "UserWarning" not in installed["log"], installed["log"][-2000:]


def test_operator_from_the_zip_writes_certified_uvs(installed):
    assert installed["unwrap"] == ["FINISHED"]
    V = np.array(installed["V"])
    tris = np.array(installed["tris"])
    tri_loops = np.array(installed["tri_loops"])
    conformal = np.array(installed["before"])
    after = np.array(installed["after"])
    assert tris.shape == (2 * 7 * 6, 3)
    assert np.isfinite(after).all()
    # Blender's own conformal unwrap of this bump goes past C = 1.6 somewhere, so the bound matters.
    D_blender, _ = triangle_distortion(V, tris, conformal[tri_loops])
    assert D_blender.max() > 1.6 * 1.05
    # bd-uv's UVs, as Blender stored them (float32): no flip, every face within C = 1.6.
    D, det = triangle_distortion(V, tris, after[tri_loops])
    assert (det > 0).all(), "flipped faces"
    assert 1.0 <= D.max() <= 1.6 * (1 + 1e-4)
    last = installed["last"]
    assert last["valid"] and last["islands"] == 1 and last["failed"] == 0 and last["flipped"] == 0
    assert last["faces"] == 7 * 6  # polygons, as the user counts faces
    assert last["bound_certified"] == pytest.approx(1.6)  # certified at the bound asked, not raised
    # The add-on's own max distortion figure matches the recomputation from the stored UVs.
    assert D.max() == pytest.approx(last["max_distortion"], rel=1e-3)


def test_zip_for_the_other_python_is_refused(interpreter, linux_extension_zips, tmp_path):
    # Each zip names the Blender versions that run its Python: Blender 5.0 (Python 3.11) refuses
    # the Blender 5.1+ zip (blender_version_min = "5.1.0"), Blender 5.1 the 4.2-5.0 one
    # (blender_version_max = "5.1.0"), rather than install wheels it cannot load.
    python = python_version(interpreter)
    other = {"3.11": "3.13", "3.13": "3.11"}[python]
    result, log = run_child(interpreter, REFUSE_CHILD,
                            {"BD_UV_ZIP": str(linux_extension_zips[other])}, tmp_path)
    expected = {"3.11": "doesn't meet the minimum supported version (5.1.0)",
                "3.13": "must be less than the maximum version (5.1.0)"}[python]
    assert expected in log
    assert result["installed"] == []
    assert "bl_ext.user_default.bd_uv" not in result["addons"]
    assert not result["site_packages"]
