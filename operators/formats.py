"""Scene files only Blender reads (FBX, Alembic, Collada, STL): Blender's own importers and
exporters, for ``scripts/bd_uv_batch.py``.

A file is imported into an empty scene, its mesh objects are unwrapped like a .blend's, and the
scene is exported to the same format with the new UV map (or saved as a .blend). What round-trips
is what Blender's exporters write (README.md, "Scene files"): FBX and Alembic keep every UV map by
name (not seams or pins); Collada exists only in Blender 4.x (bpy 5.0.1 has no Collada
operators); STL stores no UVs, so an STL is saved as a .blend or exported to another format.
"""
import os

import bpy

# suffix: (import operator, its options, export operator or None, its options)
FORMATS = {
    ".fbx": ("import_scene.fbx", {}, "export_scene.fbx",
             {"use_selection": False, "use_mesh_modifiers": False, "bake_anim": True}),
    ".abc": ("wm.alembic_import", {"as_background_job": False}, "wm.alembic_export",
             {"as_background_job": False, "selected": False, "uvs": True}),
    ".dae": ("wm.collada_import", {}, "wm.collada_export", {"selected": False}),
    ".stl": ("wm.stl_import", {}, None, {}),
}
SUFFIXES = tuple(FORMATS) + (".blend",)


class FormatError(Exception):
    """A file this Blender cannot read or write as asked (message in the user's terms)."""


def _operator(name, path):
    module, op = name.split(".")
    fn = getattr(getattr(bpy.ops, module), op)
    try:
        fn.get_rna_type()
    except KeyError:
        raise FormatError(f"{path}: Blender {bpy.app.version_string} has no {name} operator "
                          "(Collada was removed in Blender 5.0: use Blender 4.2 LTS for .dae)")
    return fn


def import_file(path):
    """Read ``path`` into an empty scene with Blender's importer; the mesh objects read."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in FORMATS:
        raise FormatError(f"{path}: not a format Blender imports here ({', '.join(FORMATS)})")
    if not os.path.isfile(path):
        raise FormatError(f"{path}: no such file")
    name, options, _, _ = FORMATS[ext]
    fn = _operator(name, path)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    try:
        result = fn(filepath=os.path.abspath(path), **options)
    except RuntimeError as exc:
        raise FormatError(f"{path}: Blender's importer failed: {exc}") from exc
    if "FINISHED" not in result:
        raise FormatError(f"{path}: Blender's importer did not finish ({result})")
    return [ob for ob in bpy.data.objects if ob.type == 'MESH']


def save_file(path):
    """Write the current scene to ``path``: a .blend, or the format's exporter."""
    ext = os.path.splitext(path)[1].lower()
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    if ext == ".blend":
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(path))
        return
    if ext not in FORMATS or FORMATS[ext][2] is None:
        why = "STL stores no UVs" if ext == ".stl" else f"{ext} is not a format written here"
        raise FormatError(f"{path}: {why}; save as .blend or {', '.join(e for e in FORMATS if FORMATS[e][2])}")
    _, _, name, options = FORMATS[ext]
    result = _operator(name, path)(filepath=os.path.abspath(path), **options)
    if "FINISHED" not in result:
        raise FormatError(f"{path}: Blender's exporter did not finish ({result})")
