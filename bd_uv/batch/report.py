"""The batch's JSON report and its one line per mesh."""
import os


def batch_report(items, options, wall, jobs, files, interrupted=False, running=False,
                 resumed=(), scheduler="pool", files_run=None, startup=0.0, working=None):
    """The JSON report: options (JobOptions, UnwrapOptions or a dict), a summary and one entry
    per mesh (file or .blend object).

    ``resumed`` are the entry lists of the files kept from an earlier run by ``--resume``. The
    throughput (files and faces per minute) counts only the ``files_run`` files run this time
    (default: every file with an entry, less those resumed), over the ``working`` seconds from
    the workers being ready to the last file done (default: ``wall`` less the ``startup``
    seconds spent before the workers were ready: starting a LocalCluster, connecting).
    """
    from .. import __version__
    if hasattr(options, "as_dict"):  # JobOptions, UnwrapOptions
        options = options.as_dict()
    count = {k: sum(e["status"] == k for e in items) for k in ("certified", "partial", "failed")}
    seen = {e["input"] for e in items}
    kept = {id(e) for entries in resumed for e in entries}
    ran = [e for e in items if id(e) not in kept]
    working = wall - startup if working is None else working
    minutes = max(working, 1e-9) / 60.0
    if files_run is None:
        files_run = len({e["input"] for e in ran})
    return {"tool": "bd_uv batch", "version": __version__, "options": options,
            "summary": {"files": len(files), "meshes": len(items), **count,
                        "not_run": sum(os.path.abspath(f) not in seen for f in files),
                        "resumed": len(resumed), "seconds": round(wall, 3),
                        "startup_seconds": round(startup, 3),
                        "working_seconds": round(working, 3),
                        "files_per_minute": round(files_run / minutes, 2),
                        "faces_per_minute": round(sum(e["faces"] or 0 for e in ran) / minutes),
                        "overlapping_islands": sum(e.get("overlapping") or 0 for e in items),
                        "layout_overlaps": sum(e.get("layout_overlaps") or 0 for e in items),
                        "scheduler": scheduler, "jobs": jobs, "interrupted": interrupted,
                        "running": running},
            "items": items}


def item_line(e):
    """One line per mesh: status, name, size, the figures or the error."""
    name = os.path.basename(e["input"]) if e.get("input") else e["name"]
    if e.get("object"):
        name += f":{e['object']}"
    head = f"{e['status']:<9} {name}"
    if e["faces"] is not None:
        head += f": {e['faces']} faces, {len(e['islands'])} island(s)"
    if e["bound_certified"] is not None:
        head += (f", C = {e['bound_certified']:.4g}, max {e['max_distortion']:.3f}, mean "
                 f"{e['mean_distortion']:.3f}, {e['flipped']} flipped")
    if e["seconds"] is not None:
        head += f", {e['seconds']:.2f} s"
    if e.get("attempts", 1) > 1:
        head += f" (attempt {e['attempts']})"
    if e["status"] != "certified":
        head += f" -- {e['error']}: {e['message']}"
    return head
