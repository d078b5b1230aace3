"""Command line for planar meshes: ``python -m bd_uv deform ...`` and ``python -m bd_uv improve``.

Both read a flat mesh (OBJ, OFF or PLY; z is ignored after checking it is constant) and write an
OBJ with the input's faces in order and the new positions as vertex coordinates (z = 0).
"""
import json
import os
import sys

import numpy as np

from .deform import METHODS, deform
from .errors import BDError, InvalidMeshError
from .meshio import load_mesh, write_obj


def _flat(mesh, path):
    V = mesh.V
    if np.ptp(V[:, 2]) > 1e-9 * max(np.ptp(V[:, :2]), 1e-300):
        raise InvalidMeshError(f"{path}: not a flat mesh in the xy plane (z varies)")
    return V[:, :2].copy()


def _write(path, V2, F):
    write_obj(path, np.column_stack([V2, np.zeros(len(V2))]), F)


def _user_errors(run):
    """Bad options and inputs (ValueError, KeyError in handles.json) exit 2 with one line; no
    certified result (``BDError``: infeasible, an overlap that cannot be mended) exits 1."""
    def wrapped(args):
        try:
            return run(args)
        except (ValueError, KeyError, OSError) as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        except BDError as exc:                  # no certified result (infeasible, overlap)
            print(f"error: {exc}", file=sys.stderr)
            return 1
    return wrapped


@_user_errors
def run_deform(args):
    mesh = load_mesh(args.input)
    V2 = _flat(mesh, args.input)
    with open(args.handles, encoding="utf-8") as fh:
        h = json.load(fh)
    res = deform(V2, mesh.faces_to_write, np.asarray(h["vertices"], dtype=np.int64),
                 np.asarray(h["positions"], dtype=np.float64), method=args.method,
                 bound=args.bound, frames=args.frames, stretch=args.stretch)
    _write(args.output, res.uv, mesh.faces_to_write)
    print(f"{mesh.name}: BD-{args.method.upper()} deformation, {len(mesh.faces_to_write)} faces, "
          f"max distortion {res.max_distortion:.4f} <= C = {res.bound:g}, {res.flipped} flipped, "
          f"{res.solves} solves, {res.seconds:.2f} s"
          + (" (mended: the direct solve overlapped itself; reached in certified steps)"
             if res.mended else "") + f" -> {args.output}")
    return 0


@_user_errors
def run_improve(args):
    from .improve import improve
    mesh = load_mesh(args.input)
    V2 = _flat(mesh, args.input)
    res = improve(V2, mesh.faces_to_write)
    _write(args.output, res.V2, mesh.faces_to_write)
    fixed = "" if res.movable_after == res.max_after else (
        f"; faces with an interior vertex {res.movable_before:.4f} -> {res.movable_after:.4f} "
        "(the rest have all corners on the fixed boundary)")
    print(f"{mesh.name}: {len(mesh.faces_to_write)} faces, max distortion vs equilateral {res.max_before:.4f} "
          f"-> {res.max_after:.4f} ({100 * (1 - res.max_after / res.max_before):.1f}% lower)"
          f"{fixed}, boundary unchanged, {res.flipped} flipped, {res.solves} solves, "
          f"{res.seconds:.2f} s -> {args.output}")
    if args.report:
        with open(args.report, "w", encoding="utf-8") as fh:
            json.dump({"input": os.path.abspath(args.input), "faces": int(len(mesh.faces_to_write)),
                       "max_distortion_before": res.max_before,
                       "max_distortion_after": res.max_after,
                       "movable_max_distortion_before": res.movable_before,
                       "movable_max_distortion_after": res.movable_after,
                       "flipped": res.flipped,
                       "solves": res.solves, "seconds": round(res.seconds, 4)}, fh, indent=2)
    return 0


def add_planar_parsers(sub):
    """Add the ``deform`` and ``improve`` subcommands to the main parser's subparsers."""
    p = sub.add_parser("deform", help="deform a flat mesh by handles within a conformal bound")
    p.add_argument("input", help="flat mesh file (.obj, .off, .ply) in the xy plane")
    p.add_argument("-o", "--output", required=True, help="output OBJ (same faces, z = 0)")
    p.add_argument("--handles", required=True,
                   help='JSON {"vertices": [i, ...], "positions": [[x, y], ...]} (0-based)')
    p.add_argument("--method", choices=METHODS, default="arap", help="energy (default arap)")
    p.add_argument("--bound", type=float, default=5.0, help="conformal bound C (default 5)")
    p.add_argument("--frames", choices=("rest", "previous"), default="rest",
                   help="frames from the rest shape (default) or the plain energy minimiser")
    p.add_argument("--stretch", type=float, default=None,
                   help="also bound singular values to [1/S, S] (S >= sqrt(C))")
    p.set_defaults(func=run_deform)
    p = sub.add_parser("improve", help="make a flat mesh's triangles closer to equilateral "
                                       "(boundary fixed)")
    p.add_argument("input", help="flat mesh file (.obj, .off, .ply) in the xy plane")
    p.add_argument("-o", "--output", required=True, help="output OBJ (same faces, z = 0)")
    p.add_argument("--report", help="write a JSON report here (max distortion against the "
                                    "equilateral before and after)")
    p.set_defaults(func=run_improve)
