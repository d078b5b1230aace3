"""Fixtures shared by the whole suite.

``linux_extension_zips`` are the linux-x64 extension zips (Python 3.11 for Blender 4.2-5.0, and
Python 3.13 for Blender 5.1+) built by ``build.py`` once per session. Their wheels come from the
cache in ``$BD_UV_WHEEL_CACHE`` (default ``.wheel-cache`` in the repo) and are downloaded from PyPI
when missing there (about 80 MB).
"""
import importlib.util
import os
import pathlib
import subprocess
import sys
import tomllib

import pytest

REPO_ROOT = pathlib.Path(__file__).resolve().parents[1]


def wheel_cache():
    return pathlib.Path(os.environ.get("BD_UV_WHEEL_CACHE", REPO_ROOT / ".wheel-cache"))


@pytest.fixture(scope="session")
def linux_extension_zips(tmp_path_factory):
    """``{python: path}`` of the zips built by ``build.py --platform linux-x64``."""
    if importlib.util.find_spec("bpy") is None:
        pytest.skip("the bpy module (which ships Blender's extension builder) is not installed")
    out = tmp_path_factory.mktemp("dist")
    cmd = [sys.executable, str(REPO_ROOT / "build.py"), "--platform", "linux-x64",
           "--cache", str(wheel_cache()), "--out", str(out), "--no-write-manifest"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, f"{' '.join(cmd)} failed:\n{proc.stdout}\n{proc.stderr}"
    version = tomllib.loads((REPO_ROOT / "blender_manifest.toml").read_text())["version"]
    zips = {"3.11": out / f"bd_uv-{version}-linux_x64.zip",
            "3.13": out / f"bd_uv-{version}-py313-linux_x64.zip"}
    for path in zips.values():
        assert path.is_file(), proc.stdout
    return zips


@pytest.fixture(scope="session")
def linux_extension_zip(linux_extension_zips):
    """The zip for Blender 4.2 to 5.0 (Python 3.11), the one the bpy module can install."""
    return linux_extension_zips["3.11"]
