"""Unwrap the mesh objects of a .blend (or FBX, Alembic, Collada, STL) headless with bd-uv, write
their UV maps, save (or export the same format).

Inside Blender (installed extension or not)::

    blender -b scene.blend --python bd_uv_batch.py -- [--objects NAME...] [--method lscm|arap]
        [--bound C|auto] [--uv-map NAME] [--pack] [--output out.blend] [--report report.json]
        [--png DIR]
    blender -b --python bd_uv_batch.py -- --input scene.fbx --output out/scene.fbx [options]

With the ``bpy`` module (``pip install bpy``)::

    python bd_uv_batch.py scene.blend -- [same options]
    python bd_uv_batch.py scene.fbx -- --output out/scene.fbx [same options]

FBX, Alembic (.abc), Collada (.dae, Blender 4.x) and STL files are read with Blender's own
importers into an empty scene and written with its exporters (``operators/formats.py``): the
output's suffix picks the format (.blend saves the scene; STL stores no UVs).

Each object is unwrapped along its marked seams, with seams added (and marked) only on islands
that cannot be certified as they are (``--seams needed``, the default; closed meshes need no
seams marked first) and the mesh repaired where it is not a manifold, keeping its pinned UVs
exactly (an object with pins is unwrapped as marked), with the object's scale
applied like the ``uv.bd_unwrap`` operator, and with ``--pack`` the islands are packed as the
operator does: by the atlas packer (``operators/pack.pack_atlas``, its layout certified) or Blender's
Pack Islands (``--pack-shape``). Then each island is certified again from the UV map as it will
be saved (float32, packed or not) with its own bound, and an island that fails is put back before
saving: no island that failed is ever saved. The report's figures and the PNG are those of the
saved map; faces are also counted as Blender's polygons. Arrays come from the add-on's
``operators/mesh_data/`` and are solved by ``bd_uv.batch.unwrap_job``, the code
``python -m bd_uv batch`` runs; the objects are chosen and written by
``operators/batch_objects.py``, checked as saved by ``batch_saved.py``, packed by
``batch_pack.py``; this file parses the options, opens and saves the file, and reports. Islands that are not certified keep their old UVs. Exit code 0
only if every object was certified.

This file lives in ``<extension root>/scripts/``; it imports ``bd_uv`` and the add-on's modules from
the extension root by path, so it works from the repository and from an installed extension alike.
"""
import argparse
import importlib.util
import json
import os
import sys
import time

import bpy
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _extension_package():
    """This extension's root package: the one Blender loaded when the extension is enabled,
    otherwise the root imported here under the name ``bd_uv_ext``."""
    init = os.path.join(ROOT, "__init__.py")
    for module in list(sys.modules.values()):
        # Only a package will do: a test runner may also have imported the root __init__.py as
        # a plain module (pytest names it "__init__" when the checkout folder's name is no
        # identifier), and its submodules cannot be imported through that.
        if (os.path.abspath(getattr(module, "__file__", None) or "") == init
                and getattr(module, "__path__", None)):
            return module
    # Blender puts the extensions' wheels (scipy, clarabel) on sys.path at start-up; add them here
    # too in case this extension is installed but not enabled.
    site = os.path.join(os.path.dirname(os.path.dirname(ROOT)), ".local", "lib",
                        "python{}.{}".format(*sys.version_info[:2]), "site-packages")
    if os.path.isdir(site) and site not in sys.path:
        sys.path.append(site)
    spec = importlib.util.spec_from_file_location("bd_uv_ext", init,
                                                  submodule_search_locations=[ROOT])
    module = importlib.util.module_from_spec(spec)
    sys.modules["bd_uv_ext"] = module
    spec.loader.exec_module(module)
    return module


def _import_addon():
    """The modules used here, from this extension: bd_uv's batch and arguments, and the add-on's
    mesh_data (bpy <-> numpy), session (packing), stored (the post-write check) and formats."""
    pkg = _extension_package().__name__
    return tuple(importlib.import_module(f"{pkg}.{name}") for name in
                 ("bd_uv", "bd_uv.batch", "bd_uv.arguments", "operators.mesh_data",
                  "operators.session", "operators.stored", "operators.formats"))


def _import_batch():
    """The add-on's modules of this script: ``operators/batch_pack.py`` (its packing, both
    packers), ``batch_objects.py`` (the objects unwrapped and written), ``batch_saved.py`` (the
    post-write check and the pictures)."""
    pkg = _extension_package().__name__
    return tuple(importlib.import_module(f"{pkg}.operators.{name}") for name in
                 ("batch_pack", "batch_objects", "batch_saved"))


def split_argv(argv):
    """(.blend files, options): the files are those before ``--`` when this runs with the bpy
    module (``python bd_uv_batch.py FILE -- ...``); inside Blender, Blender opened the file."""
    rest = argv[argv.index("--") + 1:] if "--" in argv else []
    if bpy.app.binary_path:  # the Blender program, not the bpy module
        return [], rest
    return (argv[1:argv.index("--")] if "--" in argv else argv[1:]), rest


def build_parser(arguments, packing):
    p = argparse.ArgumentParser(
        prog="bd_uv_batch.py",
        description="Unwrap the mesh objects of a .blend with bd-uv (certified bounded "
                    "distortion), write their UV maps and save.")
    p.add_argument("--objects", nargs="+", metavar="NAME",
                   help="mesh objects to unwrap (default: every mesh object with faces)")
    arguments.add_solver_options(p)
    p.add_argument("--seams", choices=("needed", "marked", "auto", "uv", "none"), default=None,
                   help="needed (the default): the marked seams kept, the mesh repaired where "
                        "it is not a manifold, seams added (and marked) only on islands that "
                        "cannot be certified as they are; marked: the marked seams only, every "
                        "island must be a disk; auto: seams searched on every island (as "
                        "python -m bd_uv's --seams auto), added and marked; uv: cut where the "
                        "UV map (--uv-map) is discontinuous, marked seams left out; none: no "
                        "seams, the islands are the mesh's parts. Objects with pinned UVs are "
                        "unwrapped as marked")
    p.add_argument("--uv-map", metavar="NAME",
                   help="UV map to read pins from and write (default: the active one; created "
                        "when missing)")
    p.add_argument("--no-object-scale", action="store_true",
                   help="unwrap the mesh data as is, ignoring the objects' scale")
    p.add_argument("--pack", action="store_true",
                   help="pack each object's unwrapped islands into its UV square, like the "
                        "operator: with the atlas packer (--pack-shape ATLAS, the default) or "
                        "Blender's Pack Islands; islands with pinned UVs stay where they are")
    p.add_argument("--pack-shape", choices=packing.PACK_SHAPES, default="ATLAS",
                   help="ATLAS (default): bd-uv's atlas packer, charts by their true shapes, "
                        "turned only, the padding in texels, the layout certified (Blender's "
                        "AABB when it cannot, e.g. a pinned island outside the square, said in "
                        "the report); AABB, CONVEX, CONCAVE: Blender's Pack Islands with "
                        "that island shape and --margin")
    p.add_argument("--margin", type=float, default=None,
                   help=f"space between islands for Blender's packer (default "
                        f"{packing.MARGIN})")
    arguments.add_pack_options(p)
    p.add_argument("--input", metavar="FILE",
                   help="an FBX, Alembic, Collada or STL file to import (inside Blender; with the "
                        "bpy module it may also come before '--')")
    p.add_argument("--output", metavar="OUT.blend",
                   help="save here (default: save the opened .blend in place); for an imported "
                        "file, the file to export (its suffix picks the format: .fbx, .abc, .dae, "
                        "or .blend)")
    p.add_argument("--report", metavar="REPORT.json", help="write the JSON report here")
    p.add_argument("--png", metavar="DIR", help="write a picture of each object's UV layout here")
    p.add_argument("--png-prefix", default="", help="prefix of the PNG file names")
    return p


def main(argv):
    blends, rest = split_argv(argv)
    _, batch, arguments, mesh_data, _, _, formats = _import_addon()
    packing, chosen, saved = _import_batch()
    args = build_parser(arguments, packing).parse_args(rest)
    imported = [f for f in blends if not f.lower().endswith(".blend")] + (
        [args.input] if args.input else [])
    blends = [f for f in blends if f.lower().endswith(".blend")]
    # Packed here (--pack): the core neither packs nor cuts what it stores.
    options = batch.JobOptions(arguments.unwrap_options_of(args))
    atlas, problem = packing.pack_settings(args, arguments)
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    if args.png and importlib.util.find_spec("matplotlib") is None:
        print("error: --png needs matplotlib, which this Python (Blender's own) does not have: "
              "install it into Blender's Python (<blender python> -m pip install matplotlib), "
              "or run python -m bd_uv batch FILE.blend --png DIR with the bpy module",
              file=sys.stderr)
        return 2
    if len(blends) + len(imported) > 1:
        print("error: give one file: a .blend before '--', or --input FILE", file=sys.stderr)
        return 2
    if imported:
        if not args.output:
            print(f"error: {imported[0]} is imported: pass --output (e.g. --output "
                  f"out/{os.path.basename(imported[0])})", file=sys.stderr)
            return 2
        if os.path.abspath(args.output) == os.path.abspath(imported[0]):
            print(f"error: --output {args.output} would overwrite its input", file=sys.stderr)
            return 2
        try:
            formats.import_file(imported[0])
        except formats.FormatError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
    if blends:
        try:
            bpy.ops.wm.open_mainfile(filepath=os.path.abspath(blends[0]))
        except RuntimeError as exc:
            print(f"error: cannot open {blends[0]}: {exc}", file=sys.stderr)
            return 2
    source = os.path.abspath(imported[0]) if imported else (bpy.data.filepath or None)
    output = os.path.abspath(args.output) if args.output else source
    if output is None:
        print("error: nothing to save to: open a .blend or pass --output", file=sys.stderr)
        return 2
    for d in (args.png, os.path.dirname(output),
              os.path.dirname(os.path.abspath(args.report)) if args.report else None):
        if d:
            os.makedirs(d, exist_ok=True)

    t0 = time.perf_counter()
    objects, missing = chosen.mesh_objects(args.objects)
    chosen.leave_edit_mode(objects)
    items = [batch.failed_entry(name, "ObjectError", message, input=source, object=name,
                                output=None, uv_map=None) for name, message in missing]
    if not objects and not items:   # say why there is nothing, in the file's terms
        items.append(batch.failed_entry(os.path.basename(source or "scene"), "ObjectError",
                                        chosen.nothing_to_unwrap(), input=source, object=None,
                                        output=None, uv_map=None))
    for e in items:
        print(batch.item_line(e), flush=True)
    done, written = chosen.unwrap_objects(objects, args, options, source)
    if written and args.pack:
        packing.pack(written, args, atlas)
    saved.check_saved(written, args.pack)
    written = [w for w in written if w.ok.any()]
    for w in written:   # the seams added, where the artist sees them: marked on the mesh saved
        if w.entry.get("seams_added"):
            w.entry["seams_marked"] = int(mesh_data.mark_seams(
                w.ob.data, w.arrays.vertices[np.asarray(w.entry["seams_added"])]).sum())
    saved.draw_saved(written, options, args)
    items += done
    for e in done:
        print(batch.item_line(e), flush=True)
    if written or args.output:
        try:
            formats.save_file(output)
        except formats.FormatError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        for w in written:
            w.entry["output"] = output
    wall = time.perf_counter() - t0

    echoed = options.as_dict()
    if args.pack:   # packed here, not by the core: the options say how
        echoed.update(pack=True, pack_shape=args.pack_shape, **(
            {k: getattr(atlas, k) for k in batch.job.PACK_FIELDS} if atlas is not None
            else {"margin": packing.MARGIN if args.margin is None else args.margin}))
    report = batch.batch_report(items, echoed, wall, jobs=1,
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
