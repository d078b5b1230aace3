"""``UnwrapOptions``: every option of an unwrap, defined, documented and checked in one place.

The command line (``bd_uv.arguments``), the batch and its workers (pool or Dask: it pickles),
``scripts/bd_uv_batch.py``, the Blender operator and ``bd_uv.unwrap`` itself build one and pass it
down; the functions below ``unwrap`` take it, or only the fields they use. What belongs to one
mesh (its seams as vertex pairs, pins, current UVs, polygons) and how a run reports (progress,
cancel) are arguments of ``unwrap``, not options.
"""
import dataclasses
import math
from typing import Optional, Union

from .boundary import SHAPES
from .deform import METHODS
from .errors import OptionError
from .spaces import check_stretch

FRAMES = ("auto", "harmonic", "conformal", "input-uv", "constant")
# How the seams are found: "marked" (the given seams only), "needed" (the mesh repaired, seams
# added only to the islands that cannot be certified as they are), "auto" (seams searched on
# every island).
SEAMS_MODES = ("marked", "needed", "auto")
# The seams mode of the command line, the batch, the Blender script and the operator when none
# is asked for (``bd_uv.unwrap`` keeps "marked" for its callers); the command line falls back to
# "marked" for options only the islands as they are take (--bound auto, --frames input-uv, a
# fixed --boundary), the operator also for pinned UVs.
ENTRY_SEAMS_MODE = "needed"
CONES = ("soc", "linf")
OVERLAPS = ("cut", "fail")
BOUNDARIES = ("free",) + SHAPES
# S when seams are added and no stretch is asked for: every chart's singular values in [1/2, 2].
AUTO_SEAMS_STRETCH = 2.0


@dataclasses.dataclass(frozen=True)
class UnwrapOptions:
    """How to unwrap (Lipman 2012): checked when made, so a wrong value never reaches a solve.

    Attributes
    ----------
    seams_mode : "marked" | "needed" | "auto" (``SEAMS_MODES``). "marked": cut along the given
        seams only, each island must be a disk; "needed" (``seams="needed"``, the entry points'
        default ``ENTRY_SEAMS_MODE``): repair the mesh (``bd_uv.repair``), keep the given seams,
        unwrap their islands at C and add seams only to those that cannot be certified
        (``bd_uv.seams.needed.unwrap_needed``: their charts at ``min(C, 2)`` within
        ``stretch``); "auto" (``seams="auto"``): keep them and add seams where an island cannot
        be certified as it is (``bd_uv.seams.unwrap_auto``: every chart a disk within C and
        within ``stretch``). Where seams are added C is never raised (a chart that cannot be
        certified is cut further), so ``raise_bound`` and ``bound_limit`` do not apply; "auto"
        decides ``overlap`` per round (a chart overlapping itself is split; only the last round
        cuts), "needed" applies it to the given seams' islands
    method : "lscm" | "arap" | "dirichlet" | "biharmonic" | "stretch-l1", the energy minimised in
        F_C (section 6.1; see ``bd_uv.unwrapping.unwrap``)
    bound : float >= 1 or "auto", C: every face's conformal distortion at most C (eq. 4.9);
        "auto" minimises C (free boundary, given seams only)
    frames : "auto" | "harmonic" | "conformal" | "input-uv" | "constant", the frames of F_C
        (eq. 4.21): "input-uv" starts from the mesh's current UVs
    raise_bound : bool, raise C (by a factor) when no map within C is found ...
    bound_limit : float >= 1, ... up to this C
    cone : "soc" (F_C, eq. 4.15) | "linf" (F_C^inf, eq. 4.22)
    time_budget : float >= 0 seconds per island for ``bound="auto"``: the search starts no new
        target after it, and conic Dinkelbach steps refine its map while it lasts; None: the
        search alone, no conic solve where a flip-free map is at hand
    stretch : float S >= sqrt(C), or None: every face's singular values within [1/S, S]
        (section 6.3); where seams are added every chart within S, any S >= 1, None meaning
        ``AUTO_SEAMS_STRETCH``
    boundary : "free" | "circle" | "rectangle" | "pinned", where each island's outer boundary
        goes (section 5); not "free" needs a numeric bound, frames "auto" or "harmonic" and
        ``seams_mode="marked"``
    overlap : "cut" | "fail", an island whose UVs lie over themselves: cut into overlap-free
        pieces, or failed
    atlas_cuts : bool, where seams are added (``adds_seams``): also bisect a chart the search
        made where it alone caps the atlas's coverage (a torus's band, a long strip:
        ``bd_uv.seams.pack_shape``), never an island the given seams alone bound; the result's
        ``atlas_cuts`` says which seams are for the atlas. False: only the seams the charts'
        certificate needs (minimal seams); refused with ``seams_mode="marked"``, which adds no
        seams

    Raises
    ------
    OptionError (a BDError and a ValueError) naming the option, when made with a value out of
    range or with options that cannot go together.
    """
    seams_mode: str = "marked"
    method: str = "lscm"
    bound: Union[float, str] = 5.0
    frames: str = "auto"
    raise_bound: bool = True
    bound_limit: float = 1000.0
    cone: str = "soc"
    time_budget: Optional[float] = None
    stretch: Optional[float] = None
    boundary: str = "free"
    overlap: str = "cut"
    atlas_cuts: bool = True

    def __post_init__(self):
        _one_of("seams_mode", self.seams_mode, SEAMS_MODES)
        _one_of("method", self.method, METHODS)
        _one_of("frames", self.frames, FRAMES)
        if self.bound != "auto" and not (_number(self.bound) and 1.0 <= self.bound < math.inf):
            raise OptionError("bound", "bound must be a finite number >= 1 or 'auto', got "
                              f"{self.bound!r}")
        if not (_number(self.bound_limit) and 1.0 <= self.bound_limit < math.inf):
            raise OptionError("bound_limit", "bound_limit must be a finite number >= 1, got "
                              f"{self.bound_limit!r}")
        if not isinstance(self.raise_bound, bool):
            raise OptionError("raise_bound", f"raise_bound must be True or False, got "
                              f"{self.raise_bound!r}")
        _one_of("cone", self.cone, CONES)
        if self.time_budget is not None and not (_number(self.time_budget)
                                                 and 0.0 <= self.time_budget <= math.inf):
            raise OptionError("time_budget", "time_budget must be a number of seconds >= 0 or "
                              f"None, got {self.time_budget!r}")
        _one_of("boundary", self.boundary, BOUNDARIES)
        _one_of("overlap", self.overlap, OVERLAPS)
        if not isinstance(self.atlas_cuts, bool):
            raise OptionError("atlas_cuts", f"atlas_cuts must be True or False, got "
                              f"{self.atlas_cuts!r}")
        if not self.atlas_cuts and not self.adds_seams:
            raise OptionError("atlas_cuts", "atlas_cuts=False applies where seams are added "
                              "(seams_mode 'needed' or 'auto'); seams_mode='marked' adds none")
        if self.boundary != "free" and self.bound == "auto":
            raise OptionError("boundary", f"boundary={self.boundary!r} needs a numeric bound C "
                              "(bound='auto' minimises C with a free boundary only)")
        if self.boundary != "free" and self.frames not in ("auto", "harmonic"):
            raise OptionError("boundary", f"boundary={self.boundary!r} takes its frames from a "
                              "Tutte embedding onto the boundary (frames 'auto' or 'harmonic'), "
                              f"got frames={self.frames!r}")
        if self.adds_seams:
            auto = f"seams_mode={self.seams_mode!r}"
            if self.boundary != "free":
                raise OptionError("seams_mode", f"{auto} makes free-boundary charts; boundary= "
                                  "needs boundary='free' there")
            if self.bound == "auto" and self.seams_mode == "auto":
                raise OptionError("seams_mode", f"{auto} needs a numeric bound C (its charts "
                                  "are certified at C; seams_mode='needed' takes bound='auto')")
            if self.frames == "input-uv":
                raise OptionError("seams_mode", f"{auto} does not take pins or the current UVs: "
                                  "call bd_uv.seams.unwrap_auto for material groups, or mark "
                                  "seams")
            # The seam search's own S: any S >= 1 (every chart within S and within C).
            if not (_number(self.seams_stretch) and 1.0 <= self.seams_stretch < math.inf):
                raise OptionError("stretch", "stretch must be a finite number >= 1, got "
                                  f"{self.stretch!r}")
        elif self.stretch is not None:
            try:
                check_stretch(1.0 if self.bound == "auto" else float(self.bound), self.stretch)
            except ValueError as exc:
                raise OptionError("stretch", str(exc)) from None

    @property
    def adds_seams(self):
        """True when seams may be added (any ``seams_mode`` but "marked")."""
        return self.seams_mode != "marked"

    @property
    def seams_stretch(self):
        """S as the seam search uses it: ``stretch``, or ``AUTO_SEAMS_STRETCH`` when None."""
        return AUTO_SEAMS_STRETCH if self.stretch is None else self.stretch

    def replace(self, **changes):
        """A copy with ``changes`` (checked again)."""
        return dataclasses.replace(self, **changes)

    def as_dict(self):
        """The options as a JSON-able dict (reports, the batch journal's options hash)."""
        return dataclasses.asdict(self)


OPTION_NAMES = tuple(f.name for f in dataclasses.fields(UnwrapOptions))


# Types whose values are immutable and compare by value: options made of them are kept.
_PLAIN = (str, float, int, bool, type(None))
_MADE = {}
_MADE_MOST = 64
_NAMES = frozenset(OPTION_NAMES)


def unwrap_options(options=None, **values):
    """``options`` (an UnwrapOptions, default: the defaults) with ``values`` replacing its fields.

    Raises
    ------
    OptionError for a name that is no option, or a value out of range
    """
    unknown = [] if _NAMES.issuperset(values) else sorted(set(values) - _NAMES)
    if unknown:
        raise OptionError(unknown[0], f"{unknown[0]!r} is not an unwrap option; the options are "
                          f"{', '.join(OPTION_NAMES)}")
    if options is None:
        # Options made from plain values are kept (they are frozen): ``bd_uv.unwrap``'s
        # checks cost ~8 us a call, ~1.4 % of a 115-face disk at C = 5. Keyed by each value's
        # type too (True == 1 == 1.0 would share a key, and True is refused as a bound).
        if not all(v.__class__ in _PLAIN for v in values.values()):
            return UnwrapOptions(**values)
        key = tuple((k, v.__class__, v) for k, v in values.items())
        made = _MADE.get(key)
        if made is None:
            made = UnwrapOptions(**values)      # checked: a refused value raises, unkept
            if len(_MADE) >= _MADE_MOST:
                _MADE.clear()
            _MADE[key] = made
        return made
    if not isinstance(options, UnwrapOptions):
        raise OptionError("options", f"options must be an UnwrapOptions, got "
                          f"{type(options).__name__}")
    return options.replace(**values) if values else options


def _one_of(name, value, allowed):
    if value not in allowed:
        raise OptionError(name, f"{name} must be one of {allowed}, got {value!r}")


def _number(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and not math.isnan(x)
