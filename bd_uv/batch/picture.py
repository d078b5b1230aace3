"""A job's picture: its UV layout drawn with its report figures as the caption (the PNG of
``python -m bd_uv batch``, ``scripts/bd_uv_batch.py`` and the Blender batch operator)."""
import os

from ..scheduling.atomic import atomic_path
from .job import JobOptions


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
