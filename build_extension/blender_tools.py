"""Blender's extension tooling, ``blender_ext.py`` (the builder and validator shipped inside the
``bpy`` module), found and run without starting Blender."""
from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

from .config import BuildError


def blender_ext_path() -> Path:
    """Path of ``blender_ext.py``, Blender's extension builder/validator inside the ``bpy`` module.

    Found without importing ``bpy`` (that would start Blender).
    """
    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        raise BuildError("the `bpy` module is not installed: pip install -r requirements-dev.txt")
    for location in spec.submodule_search_locations:
        found = sorted(Path(location).glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
        if found:
            return found[-1]
    raise BuildError("blender_ext.py not found inside the bpy module")


_BLENDER_EXT = None


def blender_ext():
    """Blender's ``blender_ext`` module (standalone: it imports no ``bpy``)."""
    global _BLENDER_EXT
    if _BLENDER_EXT is None:
        spec = importlib.util.spec_from_file_location("blender_ext", blender_ext_path())
        module = importlib.util.module_from_spec(spec)
        sys.modules["blender_ext"] = module
        spec.loader.exec_module(module)
        _BLENDER_EXT = module
    return _BLENDER_EXT


def run_blender_ext(*args: str) -> str:
    """Run ``blender_ext.py`` with ``args``; its output, or BuildError when it fails."""
    cmd = [sys.executable, str(blender_ext_path()), *args]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    out = proc.stdout + proc.stderr
    if proc.returncode != 0:
        raise BuildError(f"`blender_ext.py {' '.join(args)}` failed:\n{out}")
    return out


def validate(path: Path) -> str:
    """Blender's validator on an extension directory or zip; BuildError when it rejects it."""
    return run_blender_ext("validate", str(path))
