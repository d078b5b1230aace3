"""Unwrap the mesh objects of a .blend headless with bd-uv, write their UV maps, save.

Inside Blender (installed extension or not)::

    blender -b scene.blend --python bd_uv_batch.py -- [--objects NAME...] [--method lscm|arap]
        [--bound C|auto] [--uv-map NAME] [--output out.blend] [--report report.json] [--png DIR]

With the ``bpy`` module (``pip install bpy``)::

    python bd_uv_batch.py scene.blend -- [same options]

Each object is unwrapped along its seams, keeping its pinned UVs exactly, with the object's scale
applied like the ``uv.bd_unwrap`` operator. Arrays come from the add-on's ``operators/mesh_data.py``
and are solved by ``bd_uv.batch.unwrap_job``, the code ``python -m bd_uv batch`` runs. Islands
that are not certified keep their old UVs. Exit code 0 only if every object was certified.

This file lives in ``<extension root>/scripts/``; it imports ``bd_uv`` and ``mesh_data`` from the
extension root by path, so it works from the repository and from an installed extension alike.
"""
import argparse
import importlib.util
import json
import os
import re
import sys
import time

import bpy
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _load(name, path, package_dir=None):
    """Import the module at ``path`` as ``name`` (a package when ``package_dir`` is given)."""
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(
        name, path, submodule_search_locations=[package_dir] if package_dir else None)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[name]
        raise
    return module


def _import_addon():
    """``bd_uv.batch`` and the add-on's ``mesh_data``, from this extension's root."""
    # Blender puts the extensions' wheels (scipy, clarabel) on sys.path at start-up; add them here
    # too in case this extension is installed but not enabled.
    site = os.path.join(os.path.dirname(os.path.dirname(ROOT)), ".local", "lib",
                        "python{}.{}".format(*sys.version_info[:2]), "site-packages")
    if os.path.isdir(site) and site not in sys.path:
        sys.path.append(site)
    _load("bd_uv", os.path.join(ROOT, "bd_uv", "__init__.py"), os.path.join(ROOT, "bd_uv"))
    from bd_uv import batch, cli
    mesh_data = _load("bd_uv_addon_mesh_data", os.path.join(ROOT, "operators", "mesh_data.py"))
    return batch, cli, mesh_data


def split_argv(argv):
    """(.blend files before ``--`` when run as ``python bd_uv_batch.py FILE -- ...``, options)."""
    rest = argv[argv.index("--") + 1:] if "--" in argv else []
    as_script = bool(argv) and os.path.abspath(argv[0]) == os.path.abspath(__file__)
    head = argv[1:argv.index("--")] if "--" in argv else argv[1:]
    return (head if as_script else []), rest


def build_parser(cli):
    p = argparse.ArgumentParser(
        prog="bd_uv_batch.py",
        description="Unwrap the mesh objects of a .blend with bd-uv (certified bounded "
                    "distortion), write their UV maps and save.")
    p.add_argument("--objects", nargs="+", metavar="NAME",
                   help="mesh objects to unwrap (default: every mesh object with faces)")
    cli.add_solver_options(p)
    p.add_argument("--uv-map", metavar="NAME",
                   help="UV map to read pins from and write (default: the active one; created "
                        "when missing)")
    p.add_argument("--no-object-scale", action="store_true",
                   help="unwrap the mesh data as is, ignoring the objects' scale")
    p.add_argument("--output", metavar="OUT.blend",
                   help="save here (default: save the opened file in place)")
    p.add_argument("--report", metavar="REPORT.json", help="write the JSON report here")
    p.add_argument("--png", metavar="DIR", help="write a picture of each object's UV layout here")
    p.add_argument("--png-prefix", default="", help="prefix of the PNG file names")
    return p


def mesh_objects(names):
    """(objects to unwrap, report entries for names that are not usable mesh objects)."""
    missing = []
    if names:
        objects = []
        for name in names:
            ob = bpy.data.objects.get(name)
            if ob is None or ob.type != 'MESH':
                what = "no object" if ob is None else f"a {ob.type.lower()} object, not a mesh,"
                missing.append((name, f"there is {what} named {name!r} in the file"))
            else:
                objects.append(ob)
    else:
        objects = sorted((ob for ob in bpy.data.objects
                          if ob.type == 'MESH' and len(ob.data.polygons)),
                         key=lambda ob: ob.name)
    seen, unique = {}, []
    for ob in objects:  # linked duplicates share one mesh: unwrap it once
        if ob.data.name in seen:
            print(f"skipped {ob.name}: shares its mesh with {seen[ob.data.name]}")
        elif ob.data.library is not None:
            missing.append((ob.name, f"{ob.name}'s mesh is linked from {ob.data.library.filepath}"
                                     " and cannot be written here"))
        else:
            seen[ob.data.name] = ob.name
            unique.append(ob)
    return unique, missing


def _leave_edit_mode(objects):
    view_layer = bpy.context.view_layer
    for ob in objects:
        if ob.mode != 'OBJECT' and ob.name in view_layer.objects:
            view_layer.objects.active = ob
            bpy.ops.object.mode_set(mode='OBJECT')


def _file_name(text):
    return re.sub(r'[\\/:*?"<>|\s]+', "_", text).strip("._") or "object"


def unwrap_objects(objects, args, batch, options, mesh_data, source):
    """Unwrap each object and write its UV map. Returns the report entries."""
    items = []
    for ob in objects:
        scale = (1.0, 1.0, 1.0) if args.no_object_scale else tuple(abs(c) for c in ob.scale)
        arrays = mesh_data.mesh_arrays(ob, uv_name=args.uv_map, scale=scale)
        job = batch.Job(ob.name, arrays.V, arrays.F, seams=arrays.seams,
                        pin_corners=arrays.pin_corners, pin_uv=arrays.pin_uv,
                        corner_uv=arrays.corner_uv)
        png = (os.path.join(args.png, args.png_prefix + _file_name(ob.name) + ".png")
               if args.png else None)
        result = batch.unwrap_job(job, options, png=png)
        entry = {"input": source, "object": ob.name, "output": None, "uv_map": None,
                 **result.entry}
        if entry["status"] != "failed":
            entry["uv_map"] = mesh_data.write_corner_uvs(
                ob.data, args.uv_map or arrays.uv_name, arrays.tri_loops, result.corner_uv,
                np.ones(len(arrays.F), dtype=bool))
        items.append(entry)
        print(batch.item_line(entry), flush=True)
    return items


def _failed(source, name, message):
    return {"input": source, "object": name, "output": None, "uv_map": None, "name": name,
            "status": "failed", "faces": None, "islands": [], "bound_certified": None,
            "max_distortion": None, "mean_distortion": None, "flipped": None, "seconds": None,
            "error": "ObjectError", "message": message}


def main(argv):
    blends, rest = split_argv(argv)
    batch, cli, mesh_data = _import_addon()
    args = build_parser(cli).parse_args(rest)
    options = cli.solver_kwargs(args)
    if len(blends) > 1:
        print("error: give one .blend file before '--'", file=sys.stderr)
        return 2
    if blends:
        bpy.ops.wm.open_mainfile(filepath=os.path.abspath(blends[0]))
    source = bpy.data.filepath or None
    output = os.path.abspath(args.output) if args.output else source
    if output is None:
        print("error: nothing to save to: open a .blend or pass --output", file=sys.stderr)
        return 2
    for d in (args.png, os.path.dirname(output),
              os.path.dirname(os.path.abspath(args.report)) if args.report else None):
        if d:
            os.makedirs(d, exist_ok=True)

    t0 = time.perf_counter()
    objects, missing = mesh_objects(args.objects)
    _leave_edit_mode(objects)
    items = [_failed(source, name, message) for name, message in missing]
    for e in items:
        print(batch.item_line(e), flush=True)
    items += unwrap_objects(objects, args, batch, options, mesh_data, source)
    written = [e for e in items if e["uv_map"] is not None]
    if written or args.output:
        bpy.ops.wm.save_as_mainfile(filepath=output)
        for e in written:
            e["output"] = output
    wall = time.perf_counter() - t0

    report = batch.batch_report(items, options, wall, jobs=1,
                                files=[source] if source else [])
    report.update(tool="bd_uv_batch.py", output=output if (written or args.output) else None)
    if args.report:
        with open(args.report, "w", encoding="utf-8") as fh:
            json.dump(report, fh, indent=2)
    s = report["summary"]
    print(f"{s['meshes']} object(s): {s['certified']} certified, {s['partial']} partial, "
          f"{s['failed']} failed; {wall:.1f} s; saved {report['output']}")
    return 0 if items and s["certified"] == s["meshes"] else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
