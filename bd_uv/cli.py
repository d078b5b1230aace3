"""Command line: ``python -m bd_uv unwrap INPUT -o OUTPUT.obj [options]``.

A stable contract for scripts: exit 0 only if every island was certified, otherwise non-zero with
one line per problem on stderr. The JSON report has the shape documented in README.md.
"""
import argparse
import json
import os
import sys
import time

import numpy as np

from .errors import BDError
from .meshio import load_mesh, write_obj
from .unwrapping import FRAMES, METHODS, unwrap


def bound_arg(text):
    """``C`` (a number >= 1) or ``auto``."""
    if text == "auto":
        return "auto"
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"bound must be a number >= 1 or 'auto', not {text!r}")
    if not value >= 1.0:
        raise argparse.ArgumentTypeError(f"bound must be >= 1, not {value:g}")
    return value


def add_solver_options(p):
    """Options shared by ``unwrap`` and ``batch``."""
    p.add_argument("--method", choices=METHODS, default="lscm",
                   help="energy: BD-LSCM (default), BD-ARAP or BD-Dirichlet")
    p.add_argument("--bound", type=bound_arg, default=5.0,
                   help="conformal distortion bound C >= 1, or 'auto' to minimise it (default 5)")
    p.add_argument("--frames", choices=FRAMES, default="auto",
                   help="frame field: auto (conformal map if flip-free, else harmonic), harmonic, "
                        "conformal, input-uv (the file's UVs, eq. 4.21), constant (planar meshes)")
    p.add_argument("--bound-limit", type=float, default=1000.0,
                   help="raise C up to this limit when infeasible (default 1000)")
    p.add_argument("--no-raise", action="store_true", help="fail instead of raising C")
    p.add_argument("--cone", choices=("soc", "linf"), default="soc",
                   help="space: F_C with second-order cones (default) or F_C^inf (eq. 4.22)")
    p.add_argument("--time-budget", type=float, default=120.0,
                   help="seconds per island for --bound auto (default 120)")
    p.add_argument("--stretch", type=float, default=2.0,
                   help="with --seams auto: every face's stretch max(sigma_1, 1/sigma_2), each "
                        "chart at its 3D area, at most S (default 2)")


def solver_kwargs(args):
    """The unwrap() keyword arguments from parsed options."""
    return dict(method=args.method, bound=args.bound, frames=args.frames,
                bound_limit=args.bound_limit, raise_bound=not args.no_raise, cone=args.cone,
                time_budget=args.time_budget if args.bound == "auto" else None)


class ProgressBar:
    """A one-line progress bar on stderr (only when stderr is a terminal, or forced)."""

    def __init__(self, enabled=None, stream=sys.stderr):
        self.stream = stream
        self.enabled = stream.isatty() if enabled is None else enabled
        self.last = 0.0

    def __call__(self, fraction, message):
        now = time.monotonic()
        if not self.enabled or (now - self.last < 0.1 and fraction < 1.0):
            return
        self.last = now
        n = int(30 * fraction)
        self.stream.write(f"\r[{'#' * n}{'.' * (30 - n)}] {100 * fraction:5.1f}% {message[:60]:<60}")
        if fraction >= 1.0:
            self.stream.write("\n")
        self.stream.flush()


def run_unwrap(args):
    mesh = load_mesh(args.input)
    seams = None
    use_uv = args.seams == "uv" or (args.seams is None and mesh.corner_uv is not None)
    if use_uv:
        if mesh.corner_uv is None:
            print(f"error: {args.input} has no UVs, so --seams uv has nothing to cut along",
                  file=sys.stderr)
            return 2
        seams = mesh.uv_seams()
    kwargs = solver_kwargs(args)
    if args.frames == "input-uv":
        if mesh.corner_uv is None:
            print(f"error: --frames input-uv needs UVs in {args.input}", file=sys.stderr)
            return 2
        kwargs["initial_uv"] = mesh.corner_uv
    if args.seams == "auto":
        res = auto_seams(mesh, args, kwargs)
        if res is None:
            return 2
    else:
        res = unwrap(mesh.V, mesh.F, seams=seams, progress=ProgressBar(), **kwargs)
    uv, F_uv = res.vertex_uv()
    write_obj(args.output, mesh.V, mesh.F, uv, F_uv)
    report = {"input": os.path.abspath(args.input), **res.report()}
    if args.report:
        os.makedirs(os.path.dirname(os.path.abspath(args.report)), exist_ok=True)
        with open(args.report, "w", encoding="utf-8") as fh:
            json.dump(report, fh, indent=2)
    if args.png:
        from .render import uv_layout_png
        D = np.full(len(mesh.F), np.nan)
        for r in res.islands:
            if r.distortion is not None:
                D[r.faces] = r.distortion
        bound = max([r.bound_certified or 1.0 for r in res.islands] +
                    [args.bound if args.bound != "auto" else 1.0])
        caption = _caption(mesh.name, res, args.method)
        uv_layout_png(args.png, res.corner_uv, D, bound, caption)
    _print_report(mesh.name, res, args, sys.stdout)
    failed = [r for r in res.islands if r.status != "certified"]
    for r in failed:
        print(f"error: {r.message}", file=sys.stderr)
    return 0 if not failed else 1


def auto_seams(mesh, args, kwargs):
    """``--seams auto``: the file's UV seams (if any) kept, more added where needed."""
    if args.bound == "auto":
        print("error: --seams auto needs a numeric --bound C", file=sys.stderr)
        return None
    from .seams import unwrap_auto
    seams = mesh.uv_seams() if mesh.corner_uv is not None else None
    res, added, info = unwrap_auto(mesh.V, mesh.F, seams=seams, bound=args.bound,
                                   stretch=args.stretch, method=args.method, frames=args.frames,
                                   cone=args.cone, progress=ProgressBar())
    print(f"seams auto: {info['charts']} charts, {len(added)} edges added, seam length "
          f"{info['seam_length']:.4g} ({100 * info['seam_length'] / info['edge_length']:.2f}% of "
          f"all edge length), max stretch {max(info['max_stretch'], default=1.0):.3f} <= "
          f"{args.stretch:g}")
    return res


def _caption(name, res, method):
    ok = [r for r in res.islands if r.status == "certified"]
    if not ok:
        return f"{name}: BD-{method.upper()}, no island certified"
    maxD = max(r.max_distortion for r in ok)
    C = max(r.bound_certified for r in ok)
    nf = sum(len(r.faces) for r in ok)
    mean = sum(r.mean_distortion * len(r.faces) for r in ok) / nf
    return (f"{name}: BD-{method.upper()}, {len(ok)}/{len(res.islands)} islands, {nf} faces, "
            f"max distortion {maxD:.3f} <= {C:.3g}, mean {mean:.3f}, 0 flipped, "
            f"{res.seconds:.2f} s")


def _print_report(name, res, args, out):
    print(f"{name}: BD-{args.method.upper()}, bound {args.bound}, {len(res.islands)} island(s), "
          f"{res.seconds:.2f} s -> {args.output}", file=out)
    for r in res.islands:
        if r.status == "certified":
            print(f"  island {r.index}: {len(r.faces)} faces, certified C = "
                  f"{r.bound_certified:.4g}, max distortion {r.max_distortion:.4f}, mean "
                  f"{r.mean_distortion:.4f}, {r.flipped} flipped, frames {r.frames}, "
                  f"{r.solves} solves / {r.iterations} iterations, {r.seconds:.2f} s"
                  + (f" [{', '.join(r.flags)}]" if r.flags else ""), file=out)
        else:
            print(f"  island {r.index}: FAILED ({type(r.error).__name__}): {r.message}", file=out)


def build_parser():
    parser = argparse.ArgumentParser(prog="python -m bd_uv",
                                     description="Certified bounded-distortion UV unwrapping "
                                                 "(Lipman 2012).")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("unwrap", help="unwrap one mesh file (OBJ, OFF, PLY)")
    p.add_argument("input", help="mesh file: .obj, .off or .ply")
    p.add_argument("-o", "--output", required=True, help="output OBJ with UVs")
    add_solver_options(p)
    p.add_argument("--seams", choices=("uv", "none", "auto"), default=None,
                   help="uv: cut where the file's UVs are discontinuous (default when the OBJ "
                        "has vt); none: islands are the mesh's components; auto: add seams "
                        "where needed (closed, genus, over C or --stretch)")
    p.add_argument("--report", help="write the JSON report here")
    p.add_argument("--png", help="write a picture of the UV layout coloured by distortion")
    p.set_defaults(func=run_unwrap)
    from .batch import add_batch_parser  # batch builds on this module's options
    add_batch_parser(sub)
    return parser


def main(argv=None):
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except BDError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("error: interrupted; nothing was written", file=sys.stderr)
        return 130
