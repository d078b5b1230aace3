"""Command-line options shared by ``python -m bd_uv unwrap``, ``python -m bd_uv batch`` and the
Blender script ``scripts/bd_uv_batch.py``: how they are declared and what they become.

Below ``cli`` and ``batch`` (both build on it), so neither imports the other for its options.
"""
import argparse

from .options import (AUTO_SEAMS_STRETCH, BOUNDARIES, CONES, FRAMES, METHODS, OVERLAPS,
                      UnwrapOptions)
from .pack import MARGIN

# Every default below is UnwrapOptions' own: changing one there changes it here.
DEFAULTS = UnwrapOptions()
# The command line's own: the library's time budget is None (no limit).
TIME_BUDGET = 120.0


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
    p.add_argument("--method", choices=METHODS, default=DEFAULTS.method,
                   help="energy: BD-LSCM (default), BD-ARAP, BD-Dirichlet, BD-Biharmonic "
                        "(eq. 6.1, meant for --boundary circle|rectangle|pinned) or the L1 stretch "
                        "energy sum (|alpha| + |beta|) Area (free boundary: scale held at the 3D "
                        "area)")
    p.add_argument("--bound", type=bound_arg, default=DEFAULTS.bound,
                   help="conformal distortion bound C >= 1, or 'auto' to minimise it "
                        f"(default {DEFAULTS.bound:g})")
    p.add_argument("--frames", choices=FRAMES, default=DEFAULTS.frames,
                   help="frame field: auto (conformal map if flip-free, else harmonic), harmonic, "
                        "conformal, input-uv (the file's UVs, eq. 4.21), constant (planar meshes)")
    p.add_argument("--bound-limit", type=float, default=DEFAULTS.bound_limit,
                   help="raise C up to this limit when infeasible "
                        f"(default {DEFAULTS.bound_limit:g})")
    p.add_argument("--no-raise", action="store_true", help="fail instead of raising C")
    p.add_argument("--cone", choices=CONES, default=DEFAULTS.cone,
                   help="space: F_C with second-order cones (default) or F_C^inf (eq. 4.22)")
    p.add_argument("--time-budget", type=float, default=TIME_BUDGET,
                   help=f"seconds per island for --bound auto (default {TIME_BUDGET:g})")
    p.add_argument("--stretch", type=float, default=DEFAULTS.stretch, metavar="S",
                   help="every face's singular values within [1/S, S] at its island's own scale "
                        "(UV area = 3D area; Lipman 2012, section 6.3), with every --method; with "
                        "--boundary circle|rectangle|pinned relative to the 3D geometry (the "
                        "target gives the scale); with --bound auto: the smallest C within S; "
                        f"--seams auto: {AUTO_SEAMS_STRETCH:g} by default")
    p.add_argument("--boundary", choices=BOUNDARIES, default=DEFAULTS.boundary,
                   help="each island's outer boundary: free (default), on a circle, on a rectangle "
                        "(corners at the four boundary vertices nearest a right angle, or four "
                        "pinned ones) or on the polygon of its pinned UVs; holes stay holes; the "
                        "report says bijective: true when Theorems 5.1/5.2's premises hold")


def unwrap_options_of(args):
    """The :class:`bd_uv.UnwrapOptions` of parsed options (``unwrap``, ``batch``, the Blender
    script, which has neither ``--seams`` nor ``--overlap``).

    ``--seams auto`` adds seams, ``uv`` and ``none`` do not, no ``--seams`` keeps the default;
    the time budget counts only with ``--bound auto``.

    Raises
    ------
    OptionError naming an option out of range, or options that cannot go together
    """
    seams = getattr(args, "seams", None)
    return UnwrapOptions(
        add_seams=DEFAULTS.add_seams if seams is None else seams == "auto",
        method=args.method, bound=args.bound, frames=args.frames,
        raise_bound=not args.no_raise, bound_limit=args.bound_limit, cone=args.cone,
        time_budget=args.time_budget if args.bound == "auto" else None,
        stretch=args.stretch, boundary=args.boundary,
        overlap=getattr(args, "overlap", DEFAULTS.overlap))


def solver_kwargs(args):
    """``unwrap_options_of(args)`` as keyword arguments of ``bd_uv.unwrap``."""
    return unwrap_options_of(args).as_dict()


def add_layout_options(p):
    """How the UVs are stored (``unwrap`` and ``batch``): cut overlaps, pack, margin."""
    p.add_argument("--no-pack", action="store_true",
                   help="keep each island at (0, 0) instead of packing them into the unit square")
    p.add_argument("--margin", type=float, default=MARGIN,
                   help=f"packing margin between islands, in the unit square (default {MARGIN:g})")
    p.add_argument("--overlap", choices=OVERLAPS, default=DEFAULTS.overlap,
                   help="an island whose UVs lie over themselves: cut it into overlap-free "
                        "pieces (default, the cut edges are reported), or fail it")


def layout_kwargs(args):
    """The :func:`bd_uv.layout.stored_layout` keyword arguments from parsed options."""
    return dict(pack=not args.no_pack, cut=args.overlap == "cut", margin=args.margin)
