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
``operators/mesh_data.py`` and are solved by ``bd_uv.batch.unwrap_job``, the code
``python -m bd_uv batch`` runs. Islands that are not certified keep their old UVs. Exit code 0
only if every object was certified.

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
    mesh_data (bpy <-> numpy), session (packing) and stored (the post-write check)."""
    pkg = _extension_package().__name__
    return tuple(importlib.import_module(f"{pkg}.{name}") for name in
                 ("bd_uv", "bd_uv.batch", "bd_uv.arguments", "operators.mesh_data",
                  "operators.session", "operators.stored", "operators.formats"))


def _import_packing():
    """The add-on's ``operators/batch_pack.py``: this script's packing (both packers)."""
    return importlib.import_module(f"{_extension_package().__name__}.operators.batch_pack")


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


def nothing_to_unwrap():
    """Why a file has no mesh object to unwrap: linked libraries that are missing, collection
    instances (their meshes are in another file, or need making real)."""
    text = "the file holds no mesh object with faces"
    empty = [ob.name for ob in bpy.data.objects if ob.type == 'MESH' and not len(ob.data.polygons)]
    if empty:
        text += (f"; mesh object(s) {', '.join(empty[:3])}{' ...' if len(empty) > 3 else ''} "
                 "have edges or points only")
    lost = [lib.filepath for lib in bpy.data.libraries
            if not os.path.exists(bpy.path.abspath(lib.filepath))]
    if lost:
        text += (f"; {len(lost)} linked librar{'y is' if len(lost) == 1 else 'ies are'} "
                 f"missing ({', '.join(lost[:3])}), so their meshes could not be read")
    inst = [ob.name for ob in bpy.data.objects
            if ob.instance_type == 'COLLECTION' and ob.instance_collection is not None]
    if inst:
        text += (f"; collection instances ({', '.join(inst[:3])}) are not unwrapped: unwrap the "
                 "file they link, or make them real (Object > Apply > Make Instances Real)")
    return text


def _leave_edit_mode(objects):
    view_layer = bpy.context.view_layer
    for ob in objects:
        if ob.mode != 'OBJECT' and ob.name in view_layer.objects:
            view_layer.objects.active = ob
            bpy.ops.object.mode_set(mode='OBJECT')


def _file_name(text):
    return re.sub(r'[\\/:*?"<>|\s]+', "_", text).strip("._") or "object"


def in_polygons(entry, result, name, arrays, session):
    """Each island entry gains ``polygons`` (its faces as Blender counts them), and a failed
    island's message names polygons, not the triangles the core was given."""
    def polygons(tris):
        return {name: np.unique(arrays.tri_poly[np.asarray(tris, dtype=np.int64)])}
    for isl in entry["islands"]:
        r = result.islands[isl["island"]]
        isl["polygons"] = int(len(np.unique(arrays.tri_poly[r.faces])))
        if r.status != "certified":
            isl["message"] = (f"island {r.index} ({isl['polygons']} faces): "
                              f"{session.failure_text(r, polygons)}")
    bad = [i for i in entry["islands"] if i["status"] != "certified"]
    if bad:
        more = f" (and {len(bad) - 1} more failed island(s))" if len(bad) > 1 else ""
        entry["message"] = bad[0]["message"] + more


def unwrap_objects(objects, args, batch, options, mesh_data, session, source):
    """Unwrap each object and write its certified islands into its UV map.

    Returns
    -------
    items : list of report entries, one per object
    written : list of Written, one per object with something written
    """
    items, written = [], []
    for ob in objects:
        try:
            scale = (1.0, 1.0, 1.0) if args.no_object_scale else tuple(abs(c) for c in ob.scale)
            arrays = mesh_data.mesh_arrays(ob, uv_name=args.uv_map, scale=scale)
            seams = arrays.seams
            if args.seams == "none":
                seams = None
            elif args.seams == "uv":
                if arrays.corner_uv is None:
                    raise ValueError(f"{ob.name} has no UV map, so --seams uv has nothing to "
                                     "cut along")
                meshio = importlib.import_module(f"{_extension_package().__name__}.bd_uv.meshio")
                seams = meshio.uv_seams(arrays.F, arrays.corner_uv)
            job = batch.Job(ob.name, arrays.V, arrays.F, seams=seams,
                            pin_corners=arrays.pin_corners, pin_uv=arrays.pin_uv,
                            corner_uv=arrays.corner_uv, face_groups=arrays.tri_poly,
                            uv_dtype=np.float32, position_dtype=np.float32)
            result = batch.unwrap_job(job, options)
            entry = {"input": source, "object": ob.name, "output": None, "uv_map": None,
                     "polygons": int(len(np.unique(arrays.tri_poly))), **result.entry}
            if result.result is not None:
                in_polygons(entry, result.result, ob.name, arrays, session)
            ok = np.isfinite(result.corner_uv).all(axis=(1, 2))
            if ok.any():
                name = args.uv_map or arrays.uv_name
                initial = None
                if arrays.corner_uv is None:  # a new map: keep what it holds before writing
                    layer = ob.data.uv_layers.new(name=name or "UVMap")
                    name, initial = layer.name, mesh_data.loop_uvs(ob.data, layer.name)
                entry["uv_map"] = mesh_data.write_corner_uvs(
                    ob.data, name, arrays.tri_loops, result.corner_uv, ok)
                written.append(Written(entry, ob, arrays, ok, result.result, initial))
        except Exception as exc:  # one object never stops the others
            entry = batch.failed_entry(ob.name, type(exc).__name__, f"{ob.name}: {exc}",
                                       input=source, object=ob.name, output=None, uv_map=None)
        items.append(entry)
    return items, written


class Written:
    """One object's written islands: its report entry, the object, its MeshArrays, the (m,) bool
    triangles written (and kept), the UnwrapResult, and for a map created here what it held
    before writing ((L,2) float32; None when the map existed)."""

    def __init__(self, entry, ob, arrays, ok, result, initial_uv=None):
        self.entry, self.ob, self.arrays, self.ok = entry, ob, arrays, ok
        self.result, self.initial_uv = result, initial_uv


def _put_back(w, undo, mesh_data, stored):
    """Give the triangles ``undo`` (m,) bool their UVs from before the unwrap; a map created
    here is restored to what it held, or removed when nothing written is left on it. UVs that
    would lie over the islands kept go back moved right by whole tiles (``stored.tiles_off``).

    Returns
    -------
    int, the whole tiles they were moved by (0: exactly as they were)
    """
    mesh, name = w.ob.data, w.entry["uv_map"]
    kept = w.ok & ~undo
    if w.initial_uv is not None and not kept.any():
        mesh.uv_layers.remove(mesh.uv_layers[name])
        mesh.update()
        w.entry["uv_map"] = None
        return 0
    now = mesh_data.loop_uvs(mesh, name)
    loops = w.arrays.tri_loops[undo].ravel()
    old = (w.initial_uv[loops] if w.initial_uv is not None
           else np.asarray(w.arrays.corner_uv, np.float64)[undo].reshape(-1, 2))
    tiles = stored.tiles_off(now[w.arrays.tri_loops[kept].ravel()], old)
    if w.initial_uv is None:
        shift = np.array([tiles, 0.0])
        mesh_data.write_corner_uvs(mesh, name, w.arrays.tri_loops,
                                   w.arrays.corner_uv + shift if tiles else w.arrays.corner_uv,
                                   undo)
        return tiles
    now[loops] = old + np.array([tiles, 0.0], dtype=now.dtype)
    mesh.uv_layers[name].uv.foreach_set("vector", now.ravel())
    mesh.update()
    return tiles


def check_saved(written, mesh_data, stored, packed):
    """The post-write check: re-certify each written island from the UV map as it will be saved
    (float32, packed or not) with that island's own bound, and put back every island that fails,
    so no island that failed is ever saved. The entry's figures become those of the stored,
    kept islands (area-weighted mean), its island entries gain the stored figures, and overlaps
    between the kept islands of the layout are counted.
    """
    for w in written:
        entry, arrays = w.entry, w.arrays
        uv = mesh_data.loop_uvs(w.ob.data, entry["uv_map"])[arrays.tri_loops].astype(np.float64)
        labels = np.where(w.ok, w.result.face_island, -1)
        checks = stored.check_stored(arrays.V, arrays.F, uv, labels, w.result.islands,
                                     solved_uv=w.result.corner_uv)
        by_index = {c.island: c for c in checks}
        undo = np.isin(labels, [c.island for c in checks if not c.certified])
        for isl in entry["islands"]:
            c = by_index.get(isl["island"])
            if c is None:
                continue
            isl.update(bound_certified=c.bound, max_distortion=c.max_distortion,
                       mean_distortion=c.mean_distortion, flipped=c.flipped,
                       overlap_free=bool(c.overlap_free))
            if not c.certified:
                cause = ("as solved already" if c.failed_as_solved else
                         "after packing" if packed else "after float32 storage")
                isl.update(status="failed", error="CertificationError",
                           message=f"island {c.island}: put back as it was, its saved UVs fail "
                                   f"the certificate ({c.reason}; {cause})")
        if undo.any():
            tiles = _put_back(w, undo, mesh_data, stored)
            if tiles:
                for isl in entry["islands"]:
                    c = by_index.get(isl["island"])
                    if c is not None and not c.certified:
                        isl["message"] += (f"; moved {tiles} UV tile(s) right, off the saved "
                                           "islands it lay over")
                        isl["moved_tiles"] = tiles
            w.ok = w.ok & ~undo
        kept = [c for c in checks if c.certified]
        P = arrays.V[arrays.F]
        area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
        on = labels >= 0
        island_area = np.bincount(labels[on], weights=area[on], minlength=len(w.result.islands))
        weights = np.array([island_area[c.island] for c in kept])
        bad = [i for i in entry["islands"] if i["status"] != "certified"]
        entry["status"] = "certified" if not bad else ("partial" if kept else "failed")
        if kept:
            entry.update(bound_certified=max(c.bound for c in kept),
                         max_distortion=max(c.max_distortion for c in kept),
                         mean_distortion=float(np.dot(weights, [c.mean_distortion for c in kept])
                                               / weights.sum()),
                         flipped=int(sum(c.flipped for c in kept)))
        else:
            entry.update(bound_certified=None, max_distortion=None, mean_distortion=None,
                         flipped=None)
        if bad:
            entry["error"] = bad[0]["error"] or "IslandError"
            more = f" (and {len(bad) - 1} more failed island(s))" if len(bad) > 1 else ""
            entry["message"] = bad[0]["message"] + more
        kept_labels = np.where(w.ok, labels, -1)
        pairs = (stored.layout_overlaps(uv, kept_labels, arrays.F)
                 if len(np.unique(kept_labels[kept_labels >= 0])) > 1 else [])
        entry["island_overlaps"] = None if pairs is None else [
            [int(a), int(b)] for a, b in np.asarray(pairs).reshape(-1, 2)]
        # the layout as saved (packed or not), not the core's unpacked one
        entry["layout_overlaps"] = (None if pairs is None
                                    else len(entry["island_overlaps"]))


def draw_saved(written, core, batch, mesh_data, options, args):
    """Draw each object's UV layout as saved (only the islands kept), when ``--png``."""
    for w in written:
        entry, ob, arrays, ok = w.entry, w.ob, w.arrays, w.ok
        if not args.png or entry["uv_map"] is None:
            continue
        uv = mesh_data.loop_uvs(ob.data, entry["uv_map"])[arrays.tri_loops].astype(np.float64)
        uv[~ok] = np.nan
        D = np.full(len(arrays.F), np.nan)
        D[ok] = core.conformal_distortion(arrays.V, arrays.F[ok], uv[ok])
        png = os.path.join(args.png, args.png_prefix + _file_name(ob.name) + ".png")
        try:
            batch.entry_png(png, entry, uv, D, options)
        except Exception as exc:  # a picture that cannot be drawn must not lose the UVs
            entry.update(png=None, png_error=f"{type(exc).__name__}: {exc}")


def main(argv):
    blends, rest = split_argv(argv)
    core, batch, arguments, mesh_data, session, stored, formats = _import_addon()
    packing = _import_packing()
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
    objects, missing = mesh_objects(args.objects)
    _leave_edit_mode(objects)
    items = [batch.failed_entry(name, "ObjectError", message, input=source, object=name,
                                output=None, uv_map=None) for name, message in missing]
    if not objects and not items:   # say why there is nothing, in the file's terms
        items.append(batch.failed_entry(os.path.basename(source or "scene"), "ObjectError",
                                        nothing_to_unwrap(), input=source, object=None,
                                        output=None, uv_map=None))
    for e in items:
        print(batch.item_line(e), flush=True)
    done, written = unwrap_objects(objects, args, batch, options, mesh_data, session, source)
    if written and args.pack:
        packing.pack(written, args, atlas)
    check_saved(written, mesh_data, stored, args.pack)
    written = [w for w in written if w.ok.any()]
    for w in written:   # the seams added, where the artist sees them: marked on the mesh saved
        if w.entry.get("seams_added"):
            w.entry["seams_marked"] = int(mesh_data.mark_seams(
                w.ob.data, w.arrays.vertices[np.asarray(w.entry["seams_added"])]).sum())
    draw_saved(written, core, batch, mesh_data, options, args)
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
            {k: getattr(atlas, k) for k in batch.jobs.PACK_FIELDS} if atlas is not None
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
