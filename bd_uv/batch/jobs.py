"""One mesh's job: plain arrays in, a certified unwrap and its report entry out.

Shared by ``python -m bd_uv batch`` (each file is read into a :class:`Job`) and
``scripts/bd_uv_batch.py`` (each mesh object of a .blend): ``unwrap_job`` solves a job with
:func:`bd_uv.unwrap` and returns its report entry, so the report has the same shape whichever way
the arrays were gathered; ``entry_png`` draws it with ``caption`` under it.
"""
import os
import time
import traceback
from dataclasses import dataclass

import numpy as np

from ..api import unwrap
from ..arguments import split_options
from ..errors import BDError
from ..layout import stored_layout
from ..metrics import conformal_distortion
from ..scheduling.atomic import atomic_path
from ..scheduling.entries import failed_entry
from ..seams import unwrap_auto
from ..seams.needed import unwrap_needed


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
    """
    name: str
    V: np.ndarray
    F: np.ndarray
    seams: np.ndarray = None
    pin_corners: np.ndarray = None
    pin_uv: np.ndarray = None
    corner_uv: np.ndarray = None
    face_groups: np.ndarray = None


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


def _num(x):
    return None if x is None or not np.isfinite(x) else float(x)


def unwrap_job(job, options, png=None):
    """Unwrap one job; never raises (a failure goes into the entry, with a traceback if a bug).

    Parameters
    ----------
    job : Job
    options : dict, keyword arguments of :func:`bd_uv.unwrap` (``solver_kwargs``)
    png : str, optional, where to draw the UV layout (:func:`bd_uv.render.uv_layout_png`)

    Returns
    -------
    JobResult
        ``entry`` holds: name, status ("certified" | "partial" | "failed"), faces, islands
        (per-island entries of ``UnwrapResult.report``), bound_certified (the largest over the
        certified islands), max_distortion, mean_distortion (area-weighted over certified
        faces), flipped, seconds, error (exception type) and message.
    """
    t0 = time.perf_counter()
    m = int(len(job.F))
    entry = failed_entry(job.name, None, "", faces=m, seconds=0.0)
    kwargs, layout_options = split_options(options)
    if kwargs.get("frames") == "input-uv":
        kwargs["initial_uv"] = job.corner_uv
    if job.pin_corners is not None and len(job.pin_corners):
        kwargs.update(pin_corners=job.pin_corners, pin_uv=job.pin_uv)
    if job.face_groups is not None:
        kwargs["face_groups"] = job.face_groups
    try:
        if kwargs.get("frames") == "input-uv" and job.corner_uv is None:
            raise ValueError(f"{job.name} has no UVs to take frames from (--frames input-uv)")
        stretch = kwargs.pop("auto_stretch", None)
        needed = kwargs.pop("needed_stretch", None)
        if needed is not None and "pin_corners" in kwargs:
            needed = None           # pinned UVs: the islands as marked (seams cannot keep pins)
        extra = {}
        if needed is not None:      # the default: repair, seams added only where needed
            res, added, info = unwrap_needed(
                job.V, job.F, seams=job.seams, bound=kwargs["bound"], stretch=needed,
                marked_stretch=kwargs.get("stretch"), polygons=job.face_groups,
                method=kwargs["method"], frames=kwargs["frames"], cone=kwargs["cone"],
                overlap=kwargs.get("overlap", "cut"))
            extra = {"seams_mode": "needed", "seams_added": added.tolist(),
                     "repair": info["repair"]}
        elif stretch is not None:     # --seams auto: the file's own seams are kept, more added
            res = unwrap_auto(job.V, job.F, seams=job.seams, bound=kwargs["bound"],
                              stretch=stretch, method=kwargs["method"], frames=kwargs["frames"],
                              cone=kwargs["cone"])[0]
        else:
            res = unwrap(job.V, job.F, seams=job.seams, **kwargs)
        layout = stored_layout(job.V, job.F, res, **layout_options)
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
    entry.update(extra)
    entry["status"] = "certified" if not bad else ("partial" if ok else "failed")
    entry.update(overlapping=t["overlapping_unwrapped"], cut_edges=t["cut_edges"],
                 layout_overlaps=t["layout_overlaps"])
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
        uv_layout_png(tmp, corner_uv, distortion, entry["bound_certified"],
                      caption(entry, options))


def caption(entry, options):
    """The figures under a PNG: what was asked, what was certified, how long it took."""
    bound = options.get("bound")
    ask = "bound auto" if bound == "auto" else f"bound {bound:g}"
    head = (f"{entry['name']}: BD-{options.get('method', 'lscm').upper()}, {ask}, "
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
    if entry["status"] != "certified":
        lines.append(f"not certified: {entry['message']}"[:160])
    return "\n".join(lines)
