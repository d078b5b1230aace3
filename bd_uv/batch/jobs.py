"""One mesh's job: plain arrays in, a certified unwrap and its report entry out.

Shared by ``python -m bd_uv batch`` (each file is read into a :class:`Job`) and
``scripts/bd_uv_batch.py`` (each mesh object of a .blend): ``unwrap_job`` solves a job with
:func:`bd_uv.unwrap` and returns its report entry, so the report has the same shape whichever way
the arrays were gathered; ``entry_png`` draws it with ``caption`` under it.
"""
import os
import time
import traceback
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ..api import unwrap
from ..errors import BDError, DegenerateFacesError
from ..unwrapping.storage import stored_layout_with_headroom, with_predicted_headroom
from ..metrics import conformal_distortion
from ..options import OPTION_NAMES, UnwrapOptions
from ..pack import MARGIN
from ..repair import flat_at_precision, side_by_side
from ..packing import PackOptions

# The atlas packer's options as they appear in an options mapping and in the report.
PACK_FIELDS = ("resolution", "padding_px", "texel_density", "rotate", "udim", "solve_seconds",
               "group")
from ..scheduling.atomic import atomic_path
from ..scheduling.entries import failed_entry


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


def _num(x):
    return None if x is None or not np.isfinite(x) else float(x)


def unwrap_job(job, options, png=None):
    """Unwrap one job; never raises (a failure goes into the entry, with a traceback if a bug).

    Positions stored in float32 (``job.position_dtype``) may hold faces float32 cannot tell from
    a line (``repair.zero_area_faces``' precision). Two of them side by side (OpenChessSet's
    bishops: 608, in strips) refuse their island as stored at any stretch, and trying costs
    (a bishop: 400 s of conic stretch solves, against 45 s for the whole job without them):
    such faces are left out as zero-area from the start. A face that stands alone is often
    certified as stored (the storage headroom's stretch), so it is tried; when faces fail and
    some of them are such faces, the job runs again with them left out, and the run leaving
    fewer faces with an area uncertified (a scene writes a mesh whose only uncertified faces
    are the ones left out as zero-area), then fewer faces at all, is kept.

    Parameters
    ----------
    job : Job
    options : JobOptions, or what ``JobOptions.of`` takes (an UnwrapOptions, or a dict of its
        fields and pack, cut, margin)
    png : str, optional, where to draw the UV layout (:func:`bd_uv.render.uv_layout_png`)

    Returns
    -------
    JobResult
        ``entry`` holds: name, status ("certified" | "partial" | "failed"), faces, islands
        (per-island entries of ``UnwrapResult.report``), bound_certified (the largest over the
        certified islands), max_distortion, mean_distortion (area-weighted over certified
        faces), flipped, seconds, error (exception type) and message.
    """
    flat = flat_at_precision(job.V, job.F, job.position_dtype)
    if flat is not None and side_by_side(job.F, flat):
        return _unwrap_job(job, options, png, job.position_dtype)
    out = _unwrap_job(job, options, png, None)
    if flat is None or out.entry["status"] == "certified":
        return out
    left = _uncertified(out, len(job.F))
    if not (left & flat).any():
        return out
    again = _unwrap_job(job, options, png, job.position_dtype)
    if _refusals(again, len(job.F)) >= _refusals(out, len(job.F)):
        return out
    again.entry["seconds"] = round(again.entry["seconds"] + out.entry["seconds"], 4)
    return again


def _uncertified(out, m):
    """(m,) bool: the faces a job's layout left without certified UVs."""
    return np.ones(m, bool) if out.layout is None else out.layout.face_island < 0


def _refusals(out, m):
    """(faces with an area left uncertified, faces left uncertified): the smaller the better.
    Counting all faces alone kept a first run that failed 500 faces with an area over a rerun
    that left out only OpenChessSet's bishop's 608 zero-area ones (which a scene writes), when
    the first run's search happened to fail fewer (a bishop under load: 770 to 1,982 faces)."""
    left = _uncertified(out, m)
    return int((left & ~zero_area_left_out(out.result, m)).sum()), int(left.sum())


def zero_area_left_out(res, m):
    """(m,) bool: the faces an ``UnwrapResult`` left out as zero-area: those a
    ``DegenerateFacesError`` names. Seams "needed" makes them an island of their own; the marked
    and automatic seams refuse the island holding them, whose faces with an area are left
    uncertified, not out (counting them as zero-area wrote such a scene mesh as certified). None
    for no result."""
    zero = np.zeros(m, bool)
    for r in (res.islands if res is not None else ()):
        if isinstance(r.error, DegenerateFacesError):
            named = r.error.faces
            zero[r.faces if named is None else np.intersect1d(r.faces, named)] = True
    return zero


def _unwrap_job(job, options, png, precision):
    t0 = time.perf_counter()
    m = int(len(job.F))
    entry = failed_entry(job.name, None, "", faces=m, seconds=0.0)
    try:
        options = JobOptions.of(options)
        o = options.unwrap
        if o.frames == "input-uv" and job.corner_uv is None:
            raise ValueError(f"{job.name} has no UVs to take frames from (--frames input-uv)")
        if o.seams_mode != "marked" and job.pin_corners is not None and len(job.pin_corners):
            o = o.replace(seams_mode="marked", atlas_cuts=True)   # pinned UVs: as marked
        res = unwrap(job.V, job.F, job.seams, job.pin_corners, job.pin_uv,
                     initial_uv=job.corner_uv if o.frames == "input-uv" else None,
                     face_groups=job.face_groups, options=o, precision=precision)
        if o.stretch is None:   # its UVs are saved as float32 too (Blender script, scenes)
            res, _ = with_predicted_headroom(job.V, job.F, res)
        layout, res, _ = stored_layout_with_headroom(
            job.V, job.F, res, stretch=o.stretch, pack=options.pack, cut=options.cut,
            margin=options.margin, pack_options=options.pack_options,
            face_labels=job.face_labels, dtype=job.uv_dtype, face_groups=job.face_groups,
            v_down=job.v_down)
    except Exception as exc:  # a bad mesh, or a bug: either way it stays this job's failure
        entry.update(error=type(exc).__name__, message=str(exc),
                     seconds=round(time.perf_counter() - t0, 4))
        if not isinstance(exc, (BDError, ValueError)):
            entry["traceback"] = traceback.format_exc()
        return JobResult(entry, np.full((m, 3, 2), np.nan), None)
    # Every figure below is measured on the UVs as stored (layout.certificates).
    islands = layout.island_entries(res)
    ok = [e for e in islands if e["status"] == "certified"]
    bad = [e for e in islands if e["status"] != "certified"]
    t = layout.totals()
    w = layout.face_island >= 0
    D = np.full(m, np.nan)
    if w.any():
        D[w] = conformal_distortion(job.V, np.asarray(job.F)[w], layout.corner_uv[w])
    entry["islands"] = islands
    entry.update(res.seams_report())
    entry["status"] = "certified" if not bad else ("partial" if ok else "failed")
    entry.update(overlapping=t["overlapping_unwrapped"], cut_edges=t["cut_edges"],
                 layout_overlaps=t["layout_overlaps"])
    if layout.pack:
        entry["pack"] = layout.pack
    if ok:
        entry.update(bound_certified=max(e["bound_certified"] for e in ok),
                     max_distortion=t["max_distortion"], mean_distortion=_num(t["mean_distortion"]),
                     flipped=int(t["flipped"]))
    if bad:
        entry["error"] = bad[0]["error"] or "IslandError"
        more = f" (and {len(bad) - 1} more failed island(s))" if len(bad) > 1 else ""
        entry["message"] = bad[0]["message"] + more
    entry["seconds"] = round(res.seconds, 4)
    if png:
        entry_png(png, entry, layout.corner_uv, D, options)
    return JobResult(entry, layout.corner_uv, res, layout)


def entry_png(path, entry, corner_uv, distortion, options):
    """Draw a job's UV layout with its report figures as the caption; records ``entry["png"]``.

    ``corner_uv`` (m,3,2) and ``distortion`` (m,) are NaN on faces that are not certified.
    """
    from ..render import uv_layout_png
    entry["png"] = os.path.abspath(path)
    with atomic_path(path) as tmp:
        p = entry.get("pack")
        tiles = dict(tiles=p["tiles"], padding=p["padding_px"] / p["resolution"]) if p else {}
        uv_layout_png(tmp, corner_uv, distortion, entry["bound_certified"],
                      caption(entry, options), **tiles)


def caption(entry, options):
    """The figures under a PNG: what was asked, what was certified, how long it took."""
    o = JobOptions.of(options).unwrap
    ask = "bound auto" if o.bound == "auto" else f"bound {o.bound:g}"
    head = (f"{entry['name']}: BD-{o.method.upper()}, {ask}, "
            f"{entry['faces']} faces, {len(entry['islands'])} island(s)")
    if entry["bound_certified"] is None:
        return f"{head}\nnothing certified: {entry['message']}"[:400]
    n_ok = sum(i["status"] == "certified" for i in entry["islands"])
    lines = [head, f"certified C = {entry['bound_certified']:.4g} on {n_ok} island(s): max "
             f"distortion {entry['max_distortion']:.4f}, mean {entry['mean_distortion']:.4f}, "
             f"{entry['flipped']} flipped, "
             + (f"{entry['overlapping']} overlapping island(s) cut along {entry['cut_edges']} "
                "edges, " if entry.get("overlapping") else "")
             + f"{entry['seconds']:.2f} s"]
    p = entry.get("pack")
    if p:
        gap = "" if p["least_gap_px"] is None else f", least gap {p['least_gap_px']:.2f} px"
        lines.append(f"packed: coverage {p['coverage']:.3f} at {p['resolution']} px{gap} "
                     f"(padding {p['padding_px']:g} px{'' if p['certified'] else ', NOT met'}), "
                     f"tiles {', '.join(map(str, p['tiles']))}, {p['seconds']:.2f} s")
    if entry["status"] != "certified":
        lines.append(f"not certified: {entry['message']}"[:160])
    return "\n".join(lines)
