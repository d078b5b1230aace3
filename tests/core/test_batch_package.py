"""The core as a package: ``pip wheel .`` holds bd_uv and its subpackages and nothing of the
Blender extension, and once installed ``bd-uv`` is the command line of ``python -m bd_uv``.

Offline and quick: the wheel is built with the backend already installed (flit_core, from
requirements-dev.txt) and installed without dependencies into a new venv that sees this
environment's packages through a .pth file (numpy, scipy, ... but not this checkout).
"""
import email.parser
import os
import pathlib
import site
import subprocess
import sys
import sysconfig
import zipfile

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    out = tmp_path_factory.mktemp("wheel")
    cmd = [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
           "--no-cache-dir", "-w", str(out), str(REPO)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    (path,) = out.glob("bd_uv-*.whl")
    return path


def test_wheel_holds_the_core_and_nothing_of_the_extension(wheel):
    from bd_uv import __version__
    assert wheel.name == f"bd_uv-{__version__}-py3-none-any.whl"
    names = zipfile.ZipFile(wheel).namelist()
    core = sorted(p.relative_to(REPO).as_posix() for p in (REPO / "bd_uv").rglob("*.py"))
    packaged = sorted(n for n in names if not n.startswith(f"bd_uv-{__version__}.dist-info/"))
    assert packaged == core
    assert not [n for n in names if n.split("/")[0] in ("operators", "ui", "scripts", "tests")
                or n == "__init__.py" or "__pycache__" in n]
    info = f"bd_uv-{__version__}.dist-info"
    entry_points = zipfile.ZipFile(wheel).read(f"{info}/entry_points.txt").decode()
    assert "[console_scripts]\nbd-uv=bd_uv.cli:main" in entry_points.replace(" ", "")
    meta = email.parser.Parser().parsestr(zipfile.ZipFile(wheel).read(f"{info}/METADATA").decode())
    requires = meta.get_all("Requires-Dist")
    for name in ("numpy", "scipy", "clarabel", "trimesh"):
        assert any(r.startswith(name) and "extra" not in r for r in requires), requires
    assert any(r.startswith("distributed") and 'extra == "cluster"' in r for r in requires)
    assert any(r.startswith("matplotlib") and 'extra == "png"' in r for r in requires)
    assert not any(r.startswith(("dask", "distributed")) and "extra" not in r for r in requires)


def test_installed_wheel_gives_bd_uv_and_its_command(wheel, tmp_path):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    py = venv / "bin" / "python"
    purelib = subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()"
                              "['purelib'])"], capture_output=True, text=True, check=True)
    purelib = pathlib.Path(purelib.stdout.strip())
    # this environment's packages (numpy, scipy, ...) without this checkout: install --no-deps
    outer = {*site.getsitepackages(), sysconfig.get_paths()["purelib"]}
    (purelib / "outer.pth").write_text("\n".join(sorted(outer)) + "\n")
    # --ignore-installed: after the README's first command bd-uv is installed in the outer
    # environment too, which pip saw through outer.pth as already satisfied (nothing installed)
    proc = subprocess.run([sys.executable, "-m", "pip", "--python", str(py), "install",
                           "--no-deps", "--no-index", "--ignore-installed", str(wheel)],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr

    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    where = subprocess.run([str(py), "-c", "import bd_uv, sys; print(bd_uv.__file__); "
                            "print('bpy' in sys.modules)"], cwd=tmp_path, env=env,
                           capture_output=True, text=True, check=True).stdout.split()
    assert pathlib.Path(where[0]).is_relative_to(purelib) and where[1] == "False"
    bd_uv = venv / "bin" / "bd-uv"
    help_ = subprocess.run([str(bd_uv), "--help"], cwd=tmp_path, env=env, capture_output=True,
                           text=True)
    same = subprocess.run([str(py), "-m", "bd_uv", "--help"], cwd=tmp_path, env=env,
                          capture_output=True, text=True)
    assert help_.returncode == 0 and "unwrap,batch" in help_.stdout
    assert help_.stdout == same.stdout
    batch_help = subprocess.run([str(bd_uv), "batch", "--help"], cwd=tmp_path, env=env,
                                capture_output=True, text=True)
    assert batch_help.returncode == 0 and "--scheduler" in batch_help.stdout
    run = subprocess.run([str(bd_uv), "unwrap", str(REPO / "tests" / "data" / "nefertiti.off"),
                          "-o", str(tmp_path / "n.obj"), "--bound", "3"], cwd=tmp_path, env=env,
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "n.obj").read_text().count("\nvt ") == 299
