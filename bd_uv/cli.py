"""Command line: ``python -m bd_uv unwrap INPUT -o OUTPUT.obj [options]``.

A stable contract for scripts: exit 0 only if every island was certified (or every face with an
area: zero-area faces, which have no shape to map, take their neighbours' UVs and are counted),
otherwise non-zero with one line per problem on stderr. The JSON report has the shape documented
in README.md.
"""
import argparse
import contextlib
import dataclasses
import json
import os
import sys

import numpy as np

from .api import unwrap
from .arguments import (add_layout_options, add_scene_options, add_solver_options,  # noqa: F401
                        bound_arg, layout_kwargs, scene_option_misuse, solver_kwargs,
                        unwrap_options_of)
from .batch import add_batch_parser
from .batch.job import JobOptions
from .batch.jobs import ZERO_AREA_NOTE, zero_area_only
from .batch.report import item_line
from .batch.scene_files import unwrap_scene_file
from .errors import BDError, OptionError
from .unwrapping.storage import stored_layout_with_headroom
from .meshio import (AS_TRIANGLES, load_mesh, polygons_as_triangles, welded_entry,
                     write_unwrapped)
from .planar_cli import add_planar_parsers
from .progress import TerminalProgress
from .scenes import BLENDER_SUFFIXES, GLTF_SUFFIXES, SCENE_SUFFIXES, USD_SUFFIXES, read_scene
from .scheduling.atomic import atomic_path
from .seams.repaired import unwrap_auto_repaired
from .seams.pack_shape import atlas_cuts_of
from .seams.needed import AUTO_BOUND


def check_outputs(inp, *paths):
    """Refuse, before any work, an output path that is empty, a folder, under a file, the input
    ``inp`` itself (never changed) or the path of another output (one would replace the other)."""
    taken = {os.path.realpath(inp): "the input file, which is never written"} if inp else {}
    for option, path in zip(("output", "report", "png"), paths):
        if path is None:
            continue
        if not path:
            raise OptionError(option, f"--{option} is empty: give a file name to write")
        real = os.path.realpath(path)
        if real in taken:
            raise OptionError(option, f"--{option} {path} is {taken[real]}: give each output "
                                      "its own file")
        taken[real] = f"the --{option} path too"
        if os.path.isdir(path):
            raise OptionError(option, f"{path} is a folder: give a file name to write")
        parent = os.path.dirname(os.path.abspath(path))
        while parent and not os.path.exists(parent):
            parent = os.path.dirname(parent)
        if parent and not os.path.isdir(parent):
            raise OptionError(option, f"cannot write {path}: {parent} is a file, not a folder")


def run_unwrap(args):
    misuse = scene_option_misuse(args, [args.input])
    if misuse:
        print(f"error: {misuse}", file=sys.stderr)
        return 2
    check_outputs(args.input, args.output, args.report, args.png)
    ext = os.path.splitext(args.input)[1].lower()
    out_ext = os.path.splitext(args.output)[1].lower()
    # An STL holds no UVs: written as an OBJ it is read here (welded: STL splits every vertex);
    # to any other format it goes through Blender (its message says how).
    mesh_file = ext == ".stl" and out_ext == ".obj"
    if (ext in SCENE_SUFFIXES or ext in BLENDER_SUFFIXES) and not mesh_file:
        if ext in BLENDER_SUFFIXES:
            read_scene(args.input)     # raises with the Blender command that handles the file
        return run_scene_unwrap(args)
    if out_ext in (".off", ".ply") + SCENE_SUFFIXES + BLENDER_SUFFIXES:
        raise OptionError("output", f"a mesh file is written as OBJ: give -o an .obj path, not "
                                    f"{out_ext!r} (that file would hold OBJ text)")
    options = unwrap_options_of(args)
    layout_options = layout_kwargs(args)      # bad packing options: said before solving
    mesh = load_mesh(args.input)
    if mesh.welded:
        print(f"{mesh.name}: {mesh.welded} of the file's vertices lie where another does (split "
              f"by its exporter): welded for the unwrap; the OBJ keeps the file's vertices and "
              f"faces")
    if args.seams == "uv" and mesh.corner_uv is None:
        print(f"error: {args.input} has no UVs, so --seams uv has nothing to cut along",
              file=sys.stderr)
        return 2
    # The file's UV seams (when it has UVs), kept when seams are added too; none with --seams none.
    seams = mesh.uv_seams() if args.seams != "none" and mesh.corner_uv is not None else None
    initial_uv = None
    if options.frames == "input-uv":
        if mesh.corner_uv is None:
            print(f"error: --frames input-uv needs UVs in {args.input}", file=sys.stderr)
            return 2
        initial_uv = mesh.corner_uv
    with TerminalProgress(quiet=args.quiet) as progress:
        if options.seams_mode == "auto":
            res = auto_seams(mesh, seams, options, progress)
        else:
            res = unwrap(mesh.V, mesh.F, seams=seams, initial_uv=initial_uv, progress=progress,
                         face_groups=mesh.face_groups, options=options)
        progress.stage("storing: cut, pack and certify the UVs as stored")
        layout, res, _ = stored_layout_with_headroom(mesh.V, mesh.F, res,
                                                     stretch=options.stretch,
                                                     face_labels=mesh.labels,
                                                     face_groups=mesh.face_groups,
                                                     **layout_options)
    if options.seams_mode == "needed":
        _print_needed(res, options, args.output)
    islands = layout.island_entries(res)
    zero = zero_area_only(res, layout, len(mesh.F))
    uv, F_uv = layout.vertex_uv(mesh.F, fill=zero)
    split = polygons_as_triangles(mesh, F_uv)
    report = {"input": os.path.abspath(args.input), **welded_entry(mesh),
              **({"polygons_as_triangles": split} if split else {}),
              **({"zero_area_faces": int(zero.sum())} if zero is not None else {}), **res.report(),
              "islands": islands,
              "summary": layout.totals(), "layout_overlaps": layout.overlaps.tolist(),
              "pack": layout.pack}
    any_certified = any(e["status"] == "certified" for e in islands)
    # Every output goes to a temporary file first and is renamed into place only when all were
    # written (the OBJ first): a failed write leaves no file that looks like a result. With no
    # island certified there is no result: only the report (which says why) is written.
    with contextlib.ExitStack() as stack:
        if args.png and any_certified:
            from .metrics import conformal_distortion
            from .render import uv_layout_png
            D = np.full(len(mesh.F), np.nan)
            w = layout.face_island >= 0
            if w.any():
                D[w] = conformal_distortion(mesh.V, mesh.F[w], layout.corner_uv[w])
            bound = layout.totals()["bound"] or (args.bound if args.bound != "auto" else None)
            uv_layout_png(stack.enter_context(atomic_path(args.png)), layout.corner_uv, D, bound,
                          layout.caption(mesh.name, args.method, res.seconds), **png_tiles(layout))
        if args.report:
            with open(stack.enter_context(atomic_path(args.report)), "w",
                      encoding="utf-8") as fh:
                json.dump(report, fh, indent=2)
        if any_certified:
            write_unwrapped(stack.enter_context(atomic_path(args.output)), args.input, mesh, uv,
                            F_uv)
    _print_report(mesh.name, islands, layout, res.seconds, args, sys.stdout)
    if split and any_certified:
        print(f"  {split} polygon(s) written as their triangles: {AS_TRIANGLES}")
    if zero is not None:
        print(f"  {ZERO_AREA_NOTE.format(int(zero.sum()))}")
    failed = [e for e in islands if e["status"] != "certified"] if zero is None else []
    for e in failed:
        print(f"error: {e['message']}", file=sys.stderr)
    if not any_certified:
        print(f"no island was certified: nothing was written to {args.output}"
              + (f" (the report {args.report} says why)" if args.report else ""))
    return 0 if not failed else 1


def png_tiles(layout):
    """uv_layout_png's ``tiles`` and ``padding`` for a layout packed by the atlas packer."""
    if not layout.pack:
        return {}
    return dict(tiles=layout.pack["tiles"],
                padding=layout.pack["padding_px"] / layout.pack["resolution"])


def run_scene_unwrap(args):
    """``unwrap`` of a glTF or USD scene: every mesh, the scene written whole to ``-o``."""
    ins, outs = (os.path.splitext(p)[1].lower() for p in (args.input, args.output))
    for family in (GLTF_SUFFIXES, USD_SUFFIXES):
        if (ins in family) != (outs in family):
            print(f"error: {args.input} is written back as its own format: give -o a "
                  f"{' or '.join(family if ins in family else ())} path, not {outs!r}",
                  file=sys.stderr)
            return 2
    options = JobOptions(unwrap_options_of(args), **layout_kwargs(args), uv_set=args.uv_set,
                         uv_name=args.uv_name)
    entries = unwrap_scene_file(args.input, args.output, options, args.seams, png=args.png)
    report = {"input": os.path.abspath(args.input), "output": os.path.abspath(args.output),
              "options": options.as_dict(), "meshes": entries}
    if args.report:
        os.makedirs(os.path.dirname(os.path.abspath(args.report)), exist_ok=True)
        with open(args.report, "w", encoding="utf-8") as fh:
            json.dump(report, fh, indent=2)
    for e in entries:
        print(item_line(e) + "".join(f"\n  warning: {w}" for w in e.get("warnings", [])))
    bad = [e for e in entries if e["status"] != "certified"]
    for e in bad:
        print(f"error: {e['name']}: {e['message']}", file=sys.stderr)
    done = len(entries) - len(bad)
    print(f"{done}/{len(entries)} mesh(es) certified and written -> {args.output}" if done else
          f"0/{len(entries)} mesh(es) certified: nothing written to {args.output}")
    return 0 if not bad else 1


def core_cuts(islands):
    """Islands unwrap() cut because their UVs overlapped: {"islands": n, "edges": cut edges},
    from the report entries (pieces name the island they were cut from)."""
    first = {e["cut_from"]: len(e["cut_edges"] or []) for e in islands
             if e.get("cut_from") is not None}
    return {"islands": len(first), "edges": sum(first.values())}


def _print_needed(res, options, output):
    """What the default seams mode repaired and added (``bd_uv.seams.needed``)."""
    for note in res.repair:
        print(f"repaired: {note}")
    n = len(res.seams_added)
    print(f"seams: {n} added, only on islands that could not be certified as they were ("
          + ("their charts at C = 2, then each at its least C" if options.bound == "auto" else
             f"their charts at C = {min(float(options.bound), AUTO_BOUND):g}") + ", stretch <= "
          f"{options.seams_stretch:g})" + (f"; they are UV discontinuities of {output} and "
                                          "\"seams_added\" in the report" if n else "")
          + (f"; {atlas_line(res.atlas_cuts, options)}" if n and res.atlas_cuts is not None
             else ""))


def auto_seams(mesh, seams, options, progress=None):
    """Seams added where needed (``options.seams_mode == "auto"``): ``seams`` (the file's UV
    seams, or None) kept, more added; prints what was added. ``progress(fraction, message)``,
    optional."""
    res, added, info, rep = unwrap_auto_repaired(
        mesh.V, mesh.F, seams=seams, bound=options.bound, stretch=options.seams_stretch,
        method=options.method, frames=options.frames, cone=options.cone, progress=progress,
        atlas_cuts=options.atlas_cuts, polygons=mesh.face_groups)
    res = dataclasses.replace(res, seams_added=added, atlas_cuts=atlas_cuts_of(info))
    for note in res.repair:
        print(f"repaired: {note}")
    print(f"seams auto: {info['charts']} charts, {len(added)} edges added, seam length "
          f"{info['seam_length']:.4g} ({100 * info['seam_length'] / info['edge_length']:.2f}% of "
          f"all edge length), max stretch {max(info['max_stretch'], default=1.0):.3f} <= "
          f"{options.seams_stretch:g}; {atlas_line(res.atlas_cuts, options)}")
    return res


def atlas_line(atlas, options):
    """What the atlas cuts (``UnwrapResult.atlas_cuts``) added, for the report lines."""
    if not options.atlas_cuts:
        return "no atlas cuts (--no-atlas-cuts)"
    return (f"{atlas['cuts']} atlas cut(s), {len(atlas['seams'])} edges of length "
            f"{atlas['length']:.4g} (charts cut in two for the packing: \"atlas_cuts\" in the "
            "report; --no-atlas-cuts for none)")


def _print_report(name, islands, layout, seconds, args, out):
    t = layout.totals()
    cut = core_cuts(islands)
    print(f"{name}: BD-{args.method.upper()}, bound {args.bound}, {len(islands)} island(s), "
          f"{t['certified']}/{t['islands']} stored island(s) certified, "
          f"{t['overlapping_unwrapped'] + cut['islands']} overlapping ({t['cut_islands'] + cut['islands']} cut along "
          f"{t['cut_edges'] + cut['edges']} edges), {t['layout_overlaps']} overlapping island pair(s)"
          f"{'' if layout.packed else ' (not packed)'}, {seconds:.2f} s -> {args.output}",
          file=out)
    p = layout.pack
    if p:
        gap = "" if p["least_gap_px"] is None else f", least gap {p['least_gap_px']:.2f} px"
        print(f"  packed: coverage {p['coverage']:.3f} at {p['resolution']} px{gap}, padding "
              f"{p['padding_px']:g} px {'met' if p['certified'] else 'NOT met: ' + p['reason']}, "
              f"tiles {', '.join(map(str, p['tiles']))}, {p['texel_density']:.4g} texels per "
              f"unit, {p['seconds']:.2f} s", file=out)
    for e in islands:
        if e["status"] == "certified":
            cut = f", cut into {e['pieces']} pieces" if e["pieces"] > 1 else ""
            print(f"  island {e['island']}: {e['faces']} faces, certified C = "
                  f"{e['bound_certified']:.4g}, max distortion {e['max_distortion']:.4f}, mean "
                  f"{e['mean_distortion']:.4f}, {e['flipped']} flipped, overlap-free{cut}, "
                  f"frames {e['frames']}, {e['solves']} solves / {e['iterations']} iterations, "
                  f"{e['seconds']:.2f} s" + (f" [{', '.join(e['flags'])}]" if e["flags"] else "")
                  + (", bijective" if e.get("bijective") else ""),
                  file=out)
        else:
            print(f"  island {e['island']}: FAILED ({e['error']}): {e['message']}", file=out)


def build_parser():
    parser = argparse.ArgumentParser(prog="python -m bd_uv",
                                     description="Certified bounded-distortion UV unwrapping "
                                                 "(Lipman 2012).")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("unwrap", help="unwrap one mesh file (OBJ, OFF, PLY) or scene (glTF, USD)")
    p.add_argument("input", help="mesh file: .obj, .off or .ply; scene: .gltf, .glb, .usd, "
                                 ".usda, .usdc, .usdz (FBX, Alembic, Collada, STL and .blend: "
                                 "the answer gives the Blender command)")
    p.add_argument("-o", "--output", required=True,
                   help="output OBJ with UVs; for a scene, the scene written whole (same format)")
    add_solver_options(p)
    add_layout_options(p)
    add_scene_options(p)
    p.add_argument("--seams", choices=("needed", "uv", "none", "auto"), default=None,
                   help="needed (the default): keep the file's UV seams (if it has vt), repair "
                        "non-manifold vertices and edges, flipped parts and duplicate faces, and "
                        "add seams only to islands that cannot be certified at C as they are "
                        "(their charts at C = min(C, 2) within --stretch, default 2); uv: cut "
                        "where the file's UVs are discontinuous, nothing added; none: islands "
                        "are the mesh's components; auto: search seams on every island (closed, "
                        "genus, over C or --stretch). Without --seams, --bound auto, --frames "
                        "input-uv and a fixed --boundary take the islands as they are")
    p.add_argument("--report", help="write the JSON report here")
    p.add_argument("--png", help="write a picture of the UV layout coloured by distortion")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="no progress bar on stderr (there is none either when stderr is not a "
                        "terminal); the report lines still print")
    p.set_defaults(func=run_unwrap)
    add_batch_parser(sub)
    add_planar_parsers(sub)
    return parser


def main(argv=None):
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except BDError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:   # a file that cannot be read or written (permissions, full disk)
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"error: {where}{exc.strerror or exc}; nothing was written", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("error: interrupted; nothing was written", file=sys.stderr)
        return 130
