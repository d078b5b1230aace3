"""What a batch job is: one mesh's arrays (:class:`Job`), what a batch does with every mesh
(:class:`JobOptions`, the unwrap's options and how the UVs are stored) and its outcome
(:class:`JobResult`); run by :func:`.jobs.unwrap_job`."""
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ..options import OPTION_NAMES, UnwrapOptions
from ..pack import MARGIN
from ..packing import PackOptions

# The atlas packer's options as they appear in an options mapping and in the report.
PACK_FIELDS = ("resolution", "padding_px", "texel_density", "rotate", "udim", "solve_seconds",
               "group")


@dataclass(frozen=True)
class Job:
    """One mesh to unwrap.

    Attributes
    ----------
    name : str, the object or file name (report entry, PNG caption)
    V : (n,3) float64
    F : (m,3) int64
    seams : (s,2) int64 vertex pairs, or None
    pin_corners : (p,) int64 flat corner indices (face * 3 + corner), or None
    pin_uv : (p,2) float64, or None
    corner_uv : (m,3,2) float64 current UVs (for ``frames="input-uv"``), or None
    face_groups : (m,) int64 polygon of each triangle (a cut never splits a polygon), or None
    face_labels : dict or None, each face's "material" and "object" (``bd_uv.meshio.Mesh.labels``)
        for packing by group
    uv_dtype : the type the UVs are stored in: float64 (OBJ), float32 (glTF, USD, Blender);
        the layout is certified, and islands failing are re-solved, as stored in it
    v_down : the format stores 1 - v (glTF, whose v runs downwards): the layout is certified as
        it holds the UVs (``layout.as_stored``)
    position_dtype : the type ``V`` was stored in: float64 (OBJ, OFF, PLY as read), float32
        (glTF, USD, Blender): faces it cannot tell from a line are left out as zero-area when
        they keep islands from certifying (``unwrap_job``; ``bd_uv.unwrap``'s ``precision``)
    """
    name: str
    V: np.ndarray
    F: np.ndarray
    seams: np.ndarray = None
    pin_corners: np.ndarray = None
    pin_uv: np.ndarray = None
    corner_uv: np.ndarray = None
    face_groups: np.ndarray = None
    face_labels: dict = None
    uv_dtype: type = np.float64
    position_dtype: type = np.float64
    v_down: bool = False


@dataclass(frozen=True)
class JobResult:
    """The outcome of one job.

    Attributes
    ----------
    entry : dict, the job's JSON report entry
    corner_uv : (m,3,2) float64, the UVs to store (cut, packed as asked), NaN on faces not
        certified as stored
    result : UnwrapResult, or None when ``unwrap`` raised (the entry says why)
    layout : bd_uv.layout.Layout, the stored UVs and their certificates, or None
    """
    entry: dict
    corner_uv: np.ndarray
    result: object = None
    layout: object = None


@dataclass(frozen=True)
class JobOptions:
    """What a batch does with every mesh: how it unwraps and how the UVs are stored. Frozen and
    plain, so it travels to the pool's processes and Dask's workers as it is (pickled).

    Attributes
    ----------
    unwrap : bd_uv.UnwrapOptions
    pack : bool, pack the islands into the unit square (``bd_uv.layout.stored_layout``); the
        Blender script packs with Blender instead
    cut : bool, cut an island whose stored UVs lie over themselves into overlap-free pieces
    margin : float, the shelf packing margin in the unit square (without ``pack_options``)
    pack_options : bd_uv.PackOptions or None, pack with the atlas packer (the command line's)
    uv_set : int, where a glTF scene's UVs go: ``TEXCOORD_<uv_set>`` (``bd_uv.scenes``)
    uv_name : str or None, where a USD scene's UVs go: ``primvars:<uv_name>``; None: the
        primvar each mesh's materials read (``bd_uv.scenes.usd_uv_name``), else ``st``
    """
    unwrap: UnwrapOptions = field(default_factory=UnwrapOptions)
    pack: bool = False
    cut: bool = False
    margin: float = MARGIN
    pack_options: PackOptions = None
    uv_set: int = 0
    uv_name: str = None

    @classmethod
    def of(cls, options):
        """``options`` as JobOptions: a JobOptions, an UnwrapOptions (nothing cut or packed in
        the layout), or a mapping of UnwrapOptions fields and ``pack``, ``cut``, ``margin``
        (``cut`` also decides ``unwrap``'s ``overlap``)."""
        if isinstance(options, cls):
            return options
        if isinstance(options, UnwrapOptions):
            return cls(options)
        if not isinstance(options, Mapping):
            raise TypeError(f"options must be JobOptions, UnwrapOptions or a mapping, got "
                            f"{type(options).__name__}")
        solve = {k: v for k, v in options.items() if k in OPTION_NAMES}
        if "cut" in options:  # unwrap() itself cuts (or fails) an island whose UVs overlap
            solve["overlap"] = "cut" if options["cut"] else "fail"
        layout = {k: options[k] for k in ("pack", "cut", "margin", "uv_set", "uv_name")
                  if k in options}
        atlas = {k: options[k] for k in PACK_FIELDS if k in options}
        if atlas and options.get("pack"):
            layout["pack_options"] = PackOptions(**atlas)
        return cls(UnwrapOptions(**solve), **layout)

    def as_dict(self):
        """Every option, flat and JSON-able (the report's "options", the journal's hash)."""
        scene = {"uv_set": self.uv_set, "uv_name": self.uv_name} if (
            self.uv_set, self.uv_name) != (0, None) else {}   # as before for other files
        out = {**self.unwrap.as_dict(), "pack": self.pack, "cut": self.cut}
        if self.pack_options is None:
            out["margin"] = self.margin
        else:
            out.update({k: getattr(self.pack_options, k) for k in PACK_FIELDS})
        return {**out, **scene}
