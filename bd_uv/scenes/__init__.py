"""Scene files in and out whole: glTF 2.0 (``gltf.py``) and OpenUSD (``usd.py``), one module per
format, Blender-free; the formats only Blender reads are named with the command that handles them.

A format module reads a file into a *scene*: its meshes as arrays (:class:`SceneMesh`, one per
glTF mesh or ``UsdGeom.Mesh`` prim, in its own space) and a ``write(path, charts)`` that patches
the document it read with the new UVs and nothing else (STYLE.md item 16), returning what the UVs
as stored certify. ``bd_uv.batch.scene_files`` drives them.
"""
import os

from ..errors import BDError, MissingExtraError, SceneFileError, refuse_lfs_pointer
from .model import Charts, SceneMesh  # noqa: F401  (the scene's meshes and what is written)

GLTF_SUFFIXES = (".gltf", ".glb")
USD_SUFFIXES = (".usd", ".usda", ".usdc", ".usdz")
SCENE_SUFFIXES = GLTF_SUFFIXES + USD_SUFFIXES
# Read and written by Blender's own importers and exporters (scripts/bd_uv_batch.py).
BLENDER_SUFFIXES = (".fbx", ".abc", ".dae", ".stl", ".blend")


def blender_command(path):
    """The command that unwraps a file only Blender reads, for messages."""
    stem = os.path.splitext(os.path.basename(path))[0]
    ext = os.path.splitext(path)[1].lower()
    return (f"blender -b --python scripts/bd_uv_batch.py -- --input {path} --output "
            f"OUT_DIR/{stem}{ext}") if ext != ".blend" else (
            f"blender -b {path} --python scripts/bd_uv_batch.py -- --output OUT_DIR/{stem}.blend")


def read_scene(path, uv_set=0, uv_name=None):
    """Read a glTF or USD file into a scene (``GltfScene`` or ``UsdScene``).

    Raises
    ------
    SceneFileError for a file that cannot be read; MissingExtraError when usd-core is missing;
    BDError for a format that only Blender reads (the message gives the command).
    """
    ext = os.path.splitext(path)[1].lower()
    if ext in SCENE_SUFFIXES:
        refuse_lfs_pointer(path, SceneFileError)
    if ext in GLTF_SUFFIXES:
        from .gltf import GltfScene
        return GltfScene.read(path, uv_set=uv_set)
    if ext in USD_SUFFIXES:
        try:
            import pxr  # noqa: F401
        except ImportError:
            raise MissingExtraError(f"{path}: USD files need usd-core: pip install 'bd-uv[usd]'")
        from .usd import UsdScene
        return UsdScene.read(path, uv_name=uv_name)
    if ext in BLENDER_SUFFIXES:
        own = (" (or give -o an .obj path: bd-uv reads an STL itself and writes its UVs as OBJ)"
               if ext == ".stl" else "")
        raise BDError(f"{path}: {ext} files are read by Blender's own importer: "
                      f"{blender_command(path)}{own}")
    raise BDError(f"{path}: unsupported format {ext!r}")
