"""One mesh's job: plain arrays in, a certified unwrap and its report entry out.

Shared by ``python -m bd_uv batch`` (each file is read into a :class:`Job`) and
``scripts/bd_uv_batch.py`` (each mesh object of a .blend): ``unwrap_job`` solves a job with
:func:`bd_uv.unwrap` and returns its report entry, so the report has the same shape whichever way
the arrays were gathered; ``picture.entry_png`` draws it with its caption under it. The job
and its options are :mod:`.job`.
"""
import time
import traceback

import numpy as np

from ..api import unwrap
from ..errors import BDError, DegenerateFacesError
from ..unwrapping.storage import stored_layout_with_headroom, with_predicted_headroom
from ..metrics import conformal_distortion
from ..repair import flat_at_precision, side_by_side
from ..scheduling.entries import failed_entry
from .job import JobOptions, JobResult
from .picture import entry_png


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


ZERO_AREA_NOTE = ("{} face(s) of zero area have no shape to map or certify: their corners take "
                  "the UVs of the same vertices in neighbouring faces")


def zero_area_only(res, layout, m):
    """(m,) bool, the zero-area faces left out (``zero_area_left_out``), when they are the only
    faces of a layout not written and some face is: every face with an area is certified, so
    the mesh is, its zero-area faces given their neighbours' UVs (``Layout.vertex_uv``'s
    ``fill``), as a scene writes them. None otherwise (also when there are none)."""
    if layout is None:
        return None
    zero = zero_area_left_out(res, m)
    written = layout.face_island >= 0
    if not zero.any() or not written.any() or not (written | zero).all():
        return None
    return zero & ~written


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
