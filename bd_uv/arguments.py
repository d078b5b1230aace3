"""Command-line options shared by ``python -m bd_uv unwrap``, ``python -m bd_uv batch`` and the
Blender script ``scripts/bd_uv_batch.py``: how they are declared and what they become.

Below ``cli`` and ``batch`` (both build on it), so neither imports the other for its options.
"""
import argparse

from .options import (AUTO_SEAMS_STRETCH, BOUNDARIES, CONES, ENTRY_SEAMS_MODE, FRAMES, METHODS,
                      OVERLAPS, UnwrapOptions)
from .errors import OptionError
from .packing import GROUPINGS, ROTATIONS, PackOptions

# Every default below is UnwrapOptions' own: changing one there changes it here.
DEFAULTS = UnwrapOptions()
# The command line's own: the library's time budget is None (no limit).
TIME_BUDGET = 120.0
# The packing options' defaults (``--udim`` is a flag): with ``--no-pack`` any other is refused.
PACK_DEFAULTS = dict(resolution=1024, padding=4.0, texel_density=None, rotate="any", udim=False,
                     pack_seconds=None, group="none")


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
                        f"(default {DEFAULTS.bound_limit:g}; where seams are added, --seams "
                        "needed or auto, C is never raised: such an island gets seams)")
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
                        f"--seams auto: {AUTO_SEAMS_STRETCH:g} by default; --seams needed (the "
                        "default): only the charts it cuts, "
                        f"{AUTO_SEAMS_STRETCH:g} by default")
    p.add_argument("--no-atlas-cuts", action="store_true",
                   help="where seams are added (--seams needed or auto): only the seams the "
                        "charts' certificate needs; by default a chart the search made that alone "
                        "caps the atlas's coverage (a torus's band, a long strip) is also cut in "
                        "two where both pieces pass, and the report's atlas_cuts lists those "
                        "seams. Marked seams' islands are never cut for the atlas")
    p.add_argument("--boundary", choices=BOUNDARIES, default=DEFAULTS.boundary,
                   help="each island's outer boundary: free (default), on a circle, on a rectangle "
                        "(corners at the four boundary vertices nearest a right angle, or four "
                        "pinned ones) or on the polygon of its pinned UVs; holes stay holes; the "
                        "report says bijective: true when Theorems 5.1/5.2's premises hold")


def unwrap_options_of(args):
    """The :class:`bd_uv.UnwrapOptions` of parsed options (``unwrap``, ``batch``, the Blender
    script, which has neither ``--seams`` nor ``--overlap``).

    ``--seams needed`` (also the Blender script's) and ``auto`` add seams, ``uv``, ``none`` and
    ``marked`` (the script's) do not; no ``--seams`` is ``ENTRY_SEAMS_MODE`` ("needed") unless
    an option takes only the islands as they are (``--frames input-uv``, a fixed
    ``--boundary``: then "marked"); ``--bound auto`` with "needed" minimises C on each island
    and on each chart the seam search cuts; the time budget counts only with ``--bound auto``.

    Raises
    ------
    OptionError naming an option out of range, or options that cannot go together
    """
    seams = getattr(args, "seams", None)
    as_they_are = args.frames == "input-uv" or args.boundary != "free"
    if seams is None:
        mode = "marked" if as_they_are else ENTRY_SEAMS_MODE
    elif seams == "auto" and args.bound == "auto":   # said in the flags' terms
        raise OptionError("seams", "--seams auto certifies the charts it makes at a number C: "
                          "give --bound a number (e.g. --bound 2), or --seams needed (the "
                          "default), which gives each island and chart its least C")
    else:
        mode = seams if seams in ("needed", "auto") else "marked"
    return UnwrapOptions(
        seams_mode=mode,
        method=args.method, bound=args.bound, frames=args.frames,
        raise_bound=not args.no_raise, bound_limit=args.bound_limit, cone=args.cone,
        time_budget=args.time_budget if args.bound == "auto" else None,
        stretch=args.stretch, boundary=args.boundary,
        overlap=getattr(args, "overlap", DEFAULTS.overlap),
        atlas_cuts=not args.no_atlas_cuts)


def solver_kwargs(args):
    """``unwrap_options_of(args)`` as keyword arguments of ``bd_uv.unwrap``."""
    return unwrap_options_of(args).as_dict()


def add_scene_options(p):
    """Where a scene's new UVs go (``unwrap`` and ``batch``)."""
    p.add_argument("--uv-set", type=int, default=0, metavar="N",
                   help="glTF: write the UVs to TEXCOORD_N (default 0; e.g. 1 for a lightmap "
                        "beside the artist's UVs)")
    p.add_argument("--uv-name", default=None, metavar="NAME",
                   help="USD: read and write the UVs as primvars:NAME (default: the primvar "
                        "the mesh's materials read UVs from, else its one UV primvar, e.g. "
                        "map1 from Maya, else st)")


def scene_option_misuse(args, paths):
    """An error message when ``--uv-set`` or ``--uv-name`` is given but no input is of the
    format it applies to (an option is never accepted and ignored), else None."""
    low = [p.lower() for p in paths]
    if args.uv_set != 0 and not any(p.endswith((".gltf", ".glb")) for p in low):
        return "--uv-set applies to glTF files (.gltf, .glb) only"
    if args.uv_name is not None and not any(p.endswith((".usd", ".usda", ".usdc", ".usdz"))
                                        for p in low):
        return "--uv-name applies to USD files (.usd, .usda, .usdc, .usdz) only"
    if args.uv_set < 0:
        return f"--uv-set must be 0 or more, not {args.uv_set}"
    return None


def add_layout_options(p):
    """How the UVs are stored (``unwrap`` and ``batch``): cut overlaps, pack and its options."""
    p.add_argument("--no-pack", action="store_true",
                   help="keep each island at (0, 0) instead of packing them into the unit square")
    add_pack_options(p)
    p.add_argument("--overlap", choices=OVERLAPS, default=DEFAULTS.overlap,
                   help="an island whose UVs lie over themselves: cut it into overlap-free "
                        "pieces (default, the cut edges are reported), or fail it")


def add_pack_options(p):
    """The atlas packer's options (``unwrap``, ``batch`` and the Blender script): defaults
    ``PACK_DEFAULTS``, read back by :func:`pack_options_of`."""
    p.add_argument("--resolution", type=int, default=PACK_DEFAULTS["resolution"],
                   help="texture size in texels the packing is measured at (default 1024)")
    p.add_argument("--padding", type=float, default=PACK_DEFAULTS["padding"],
                   help="least gap between two charts in texels at --resolution, half of it to "
                        "the square's edge (default 4)")
    p.add_argument("--texel-density", type=float, default=PACK_DEFAULTS["texel_density"],
                   help="texels per scene unit for every chart (default: one density, as large "
                        "as fits the square)")
    p.add_argument("--rotate", choices=ROTATIONS, default=PACK_DEFAULTS["rotate"],
                   help="turns a chart may make when packed (never a mirror; default any)")
    p.add_argument("--pack-seconds", type=_seconds, default=PACK_DEFAULTS["pack_seconds"],
                   metavar="S|auto",
                   help="seconds the nesting and compaction may take for the smallest square, "
                        "half each, the compaction's in CPU time (default auto: about 6 ms "
                        "sqrt(charts x faces), at most 80 ms a chart; 2-5 charts are laid out "
                        "without nesting); 0: the first placements found only, for less "
                        "coverage; a number with 2-5 charts nests too and keeps the smaller "
                        "square")
    p.add_argument("--group", choices=GROUPINGS, default=PACK_DEFAULTS["group"],
                   help="pack the charts of one material (OBJ usemtl, glTF primitive material, "
                        "USD materialBind subset) or one object (OBJ o) together, one region per "
                        "group the padding apart (default none)")
    p.add_argument("--udim", action="store_true",
                   help="with --texel-density: charts that do not fit tile 1001 spill into 1002, "
                        "1003, ... (Blender's UDIM numbering)")


def pack_options_given(args):
    """The atlas packing options set to other than their defaults, as flags (``--padding``):
    refused where nothing is packed by the atlas packer (never accepted and ignored)."""
    return ["--" + name.replace("_", "-") for name, default in PACK_DEFAULTS.items()
            if getattr(args, name) != default]


def pack_options_of(args):
    """The PackOptions of parsed :func:`add_pack_options` (bad values raise PackError)."""
    return PackOptions(resolution=args.resolution, padding_px=args.padding,
                       texel_density=args.texel_density, rotate=args.rotate, udim=args.udim,
                       solve_seconds=args.pack_seconds, group=args.group)


def pack_flags(options):
    """PackOptions as the command-line flags of :func:`add_pack_options` (what
    ``python -m bd_uv batch`` hands the Blender script)."""
    out = ["--resolution", str(options.resolution), "--padding", repr(options.padding_px),
           "--rotate", options.rotate, "--group", options.group]
    if options.texel_density is not None:
        out += ["--texel-density", repr(options.texel_density)]
    if options.solve_seconds is not None:
        out += ["--pack-seconds", repr(options.solve_seconds)]
    if options.udim:
        out.append("--udim")
    return out


def _seconds(text):
    """``--pack-seconds``: a number of seconds, or "auto" (None: adaptive)."""
    if text.strip().lower() == "auto":
        return None
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number of seconds nor auto: {text!r}") from None


def layout_kwargs(args):
    """The :func:`bd_uv.layout.stored_layout` keyword arguments from parsed options: packed by
    the atlas packer (``pack_options``) unless ``--no-pack``. Bad packing options raise
    ``PackError`` here, before anything is solved."""
    pack = not args.no_pack
    if not pack:   # an option is never accepted and ignored
        given = pack_options_given(args)
        if given:
            raise OptionError("no_pack", f"{', '.join(given)} set how islands are packed: "
                                         "not with --no-pack")
    options = pack_options_of(args) if pack else None
    return dict(pack=pack, cut=args.overlap == "cut", pack_options=options)
