"""Command-line options shared by ``python -m bd_uv unwrap``, ``python -m bd_uv batch`` and the
Blender script ``scripts/bd_uv_batch.py``: how they are declared and what they become.

Below ``cli`` and ``batch`` (both build on it), so neither imports the other for its options.
"""
import argparse

from .unwrapping import FRAMES, METHODS
from .unwrapping.fixed_boundary import BOUNDARIES


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
                   help="energy: BD-LSCM (default), BD-ARAP, BD-Dirichlet, BD-Biharmonic "
                        "(eq. 6.1, meant for --boundary circle|rectangle|pinned) or the L1 stretch "
                        "energy sum (|alpha| + |beta|) Area (free boundary: scale held at the 3D "
                        "area)")
    p.add_argument("--bound", type=bound_arg, default=5.0,
                   help="conformal distortion bound C >= 1, or 'auto' to minimise it (default 5)")
    p.add_argument("--frames", choices=FRAMES, default="auto",
                   help="frame field: auto (conformal map if flip-free, else harmonic), harmonic, "
                        "conformal, input-uv (the file's UVs, eq. 4.21), constant (planar meshes)")
    p.add_argument("--bound-limit", type=float, default=1000.0,
                   help="raise C up to this limit when infeasible (default 1000; with --seams "
                        "needed or auto C is never raised: such an island gets seams)")
    p.add_argument("--no-raise", action="store_true", help="fail instead of raising C")
    p.add_argument("--cone", choices=("soc", "linf"), default="soc",
                   help="space: F_C with second-order cones (default) or F_C^inf (eq. 4.22)")
    p.add_argument("--time-budget", type=float, default=120.0,
                   help="seconds per island for --bound auto (default 120)")
    p.add_argument("--stretch", type=float, default=None, metavar="S",
                   help="every face's singular values within [1/S, S] at its island's own scale "
                        "(UV area = 3D area; Lipman 2012, section 6.3), with every --method; with "
                        "--boundary circle|rectangle|pinned relative to the 3D geometry (the "
                        "target gives the scale); with --bound auto: the smallest C within S; "
                        "--seams auto: 2 by default")
    p.add_argument("--boundary", choices=BOUNDARIES, default="free",
                   help="each island's outer boundary: free (default), on a circle, on a rectangle "
                        "(corners at the four boundary vertices nearest a right angle, or four "
                        "pinned ones) or on the polygon of its pinned UVs; holes stay holes; the "
                        "report says bijective: true when Theorems 5.1/5.2's premises hold")


def seams_mode(args):
    """The seams mode of parsed options: ``--seams`` as given, else "needed" (the marked seams,
    i.e. the file's UV seams, kept and seams added only where an island cannot be certified)
    unless an option needs the islands as they are: ``--bound auto``, ``--frames input-uv`` or a
    fixed ``--boundary`` (then the old default: the file's UV seams, or the components).
    ``--seams marked`` (``scripts/bd_uv_batch.py``) is None too."""
    fixed = args.bound == "auto" or args.frames == "input-uv" or args.boundary != "free"
    if args.seams == "needed" and fixed:
        raise SystemExit("error: --seams needed adds seams at a numeric --bound with --frames "
                         "auto and --boundary free; for --bound auto, --frames input-uv or a "
                         "fixed --boundary choose --seams uv or none")
    if args.seams == "marked":
        return None
    if args.seams is not None:
        return args.seams
    return None if fixed else "needed"


def solver_kwargs(args):
    """The unwrap() keyword arguments from parsed options; with seams "needed" also
    ``needed_stretch`` (S of the charts the seam search cuts; ``batch.jobs.unwrap_job``)."""
    kwargs = dict(method=args.method, bound=args.bound, frames=args.frames,
                  bound_limit=args.bound_limit, raise_bound=not args.no_raise, cone=args.cone,
                  time_budget=args.time_budget if args.bound == "auto" else None)
    if args.boundary != "free":  # absent by default: options hashed by --resume stay the same
        kwargs["boundary"] = args.boundary
    mode = seams_mode(args)
    if args.stretch is not None and mode != "auto":  # "needed": on the marked islands too
        kwargs["stretch"] = args.stretch
    if mode == "needed":
        kwargs["needed_stretch"] = 2.0 if args.stretch is None else args.stretch
    return kwargs


LAYOUT_OPTIONS = ("pack", "cut", "margin")


def add_layout_options(p):
    """How the UVs are stored (``unwrap`` and ``batch``): cut overlaps, pack, margin."""
    p.add_argument("--no-pack", action="store_true",
                   help="keep each island at (0, 0) instead of packing them into the unit square")
    p.add_argument("--margin", type=float, default=0.005,
                   help="packing margin between islands, in the unit square (default 0.005)")
    p.add_argument("--overlap", choices=("cut", "fail"), default="cut",
                   help="an island whose UVs lie over themselves: cut it into overlap-free "
                        "pieces (default, the cut edges are reported), or fail it")


def layout_kwargs(args):
    """The :func:`bd_uv.layout.stored_layout` keyword arguments from parsed options."""
    return dict(pack=not args.no_pack, cut=args.overlap == "cut", margin=args.margin)


def split_options(options):
    """(unwrap keyword arguments, stored_layout keyword arguments) of one options dict; without
    layout keys (the Blender script, which packs with Blender) nothing is cut or packed."""
    solve = {k: v for k, v in options.items() if k not in LAYOUT_OPTIONS}
    layout = {k: options[k] for k in LAYOUT_OPTIONS if k in options}
    if "cut" in layout:  # unwrap() itself cuts (or fails) an island whose UVs overlap
        solve["overlap"] = "cut" if layout["cut"] else "fail"
    layout.setdefault("pack", False)
    layout.setdefault("cut", False)
    return solve, layout
