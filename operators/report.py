"""Reporting: the report line and the panel's figures, from the post-write check of what is
stored, in Blender's terms (faces are polygons, islands are named with their object)."""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

METHOD_LABELS = {"lscm": "BD-LSCM", "arap": "BD-ARAP"}

@dataclass(frozen=True)
class Summary:
    """The report line and the figures the panel shows: those of the post-write check."""

    message: str
    level: str          # 'INFO' | 'WARNING' | 'ERROR'
    written: bool       # something was written and kept
    islands: int        # islands written and kept
    failed: int         # islands the core could not unwrap
    max_distortion: float
    mean_distortion: float
    flipped: int
    bound_certified: float
    seconds: float
    method: str
    raised: int = 0     # islands certified at a C above the one asked for
    put_back: int = 0   # islands put back by the post-write check
    overlaps: int = 0   # pairs of islands overlapping in the stored layouts


LISTED = 8  # islands named one by one in the report line; the rest are counted


def _more(n):
    return f", ... ({n} islands in all)" if n > LISTED else ""


def _some(values, k=8):
    values = [int(v) for v in values]
    text = ", ".join(str(v) for v in values[:k])
    return text + (f", ... ({len(values)} in all)" if len(values) > k else "")


def _up(x, digits=4):
    """``x`` rounded up to ``digits`` significant digits, as text (a bound shown never below
    the truth)."""
    if not np.isfinite(x) or x <= 0:
        return f"{x:g}"
    step = 10.0 ** (np.floor(np.log10(x)) - digits + 1)
    return f"{np.ceil(x / step - 1e-9) * step:.{digits}g}"


def _down(x, digits=4):
    """``x`` rounded down to ``digits`` significant digits (a measure shown never above it)."""
    if not np.isfinite(x) or x <= 0:
        return f"{x:g}"
    step = 10.0 ** (np.floor(np.log10(x)) - digits + 1)
    return f"{np.floor(x / step + 1e-9) * step:.{digits}g}"


_FACE_LIST = re.compile(r"\bfaces (\d+(?:, \d+)*(?:, \.\.\. \(\d+ in all\))?)")


def failure_text(r, polygons):
    """Why island ``r`` (a failed IslandResult) was not unwrapped, in Blender's terms: the
    core's message without its own "island N (k faces)" prefix (the caller names the island),
    with triangle counts and indices replaced by the polygons they belong to.

    Parameters
    ----------
    r : IslandResult
    polygons : callable
        ``polygons(tris)`` -> {object name: sorted polygon indices} of (k,) triangle indices
        (``Batch.polygons``).
    """
    text = re.sub(rf"^island {r.index}(?: \(\d+ faces\))?:?\s*", "", r.message or "")
    tris = getattr(r.error, "faces", None)
    if tris is not None and len(tris):
        where = polygons(tris)
        n = sum(len(p) for p in where.values())
        listed = "; ".join(f"{name} faces {_some(p)}" if len(where) > 1 else f"faces {_some(p)}"
                           for name, p in where.items())
        text = _FACE_LIST.sub(lambda _: listed, text, count=1)
        text = re.sub(rf"\b{len(tris)} (zero-area )?face(\(s\)|s)\b",
                      lambda m: f"{n} {m.group(1) or ''}face{'s' if n != 1 else ''}", text,
                      count=1)
    return text


def _name(batch, result, i, names):
    """``island 3 of Cube (6 faces)``: an island named once, counted in polygons."""
    r = result.islands[i]
    where = batch.polygons(r.faces)
    n = sum(len(p) for p in where.values())
    return f"island {i} of {names.get(i, '?')} ({n} face{'s' if n != 1 else ''})"


def summarise(batch, result, written, seconds, verified=None, packed=False, stretch=None):
    """The report line, from the post-write check of what is stored.

    E.g. ``BD-LSCM: 3 islands, max distortion 2.31 ≤ 5, 0 flipped, 1.8 s``, followed by what
    did not go as asked: islands whose C was raised (to what), islands the core could not
    unwrap (named once, in polygons), islands put back by the post-write check, overlaps
    between islands of a stored layout, objects not written. With ``stretch`` S (Limit Stretch)
    the stored islands' smallest and largest singular values follow the distortion, e.g.
    ``singular values 0.7412 to 1.388 within [0.5, 2]``.
    """
    label = METHOD_LABELS.get(result.method, result.method)
    names = {}
    for part in batch.parts:
        for i in np.unique(result.face_island[part.faces]):
            names[int(i)] = part.object_name
    checked = verified.islands if verified is not None else []
    kept = [c for c in checked if not c.put_back]
    back = [c for c in checked if c.put_back]
    failed = [r for r in result.islands if r.status != "certified"]
    max_d = max((c.stored.max_distortion for c in kept), default=float("nan"))
    weights = np.array([c.area for c in kept])
    means = np.array([c.stored.mean_distortion for c in kept])
    mean_d = (float((weights * means).sum() / weights.sum()) if kept and weights.sum() > 0
              else float("nan"))
    flips = int(sum(c.stored.flipped for c in kept))
    bound_c = max((c.stored.bound for c in kept), default=float("nan"))
    minimised = any(result.islands[c.stored.island].bound_requested == "auto" for c in kept)

    raised = []
    for c in kept:
        r = result.islands[c.stored.island]
        asked = r.bound_requested
        if isinstance(asked, (int, float)) and (
                "bound_raised" in r.flags or c.stored.bound > float(asked) * (1 + 1e-9)):
            raised.append((c, float(asked)))

    parts = []
    if kept:
        parts.append(f"{label}: {len(kept)} island{'s' if len(kept) != 1 else ''}, "
                     f"max distortion {_down(max_d)} \u2264 {_up(bound_c)}"
                     f"{' (minimised)' if minimised else ''}, "
                     + (f"singular values {_down(min(c.stored.min_singular for c in kept))} to "
                        f"{_up(max(c.stored.max_singular for c in kept))} within "
                        f"[{1.0 / stretch:.4g}, {stretch:.4g}], " if stretch is not None else "")
                     + f"{flips} flipped, {seconds:.1f} s")
    else:
        parts.append(f"{label}: nothing unwrapped")
    if raised:
        asked = sorted({a for _, a in raised})
        listed = [f"{_name(batch, result, c.stored.island, names)} to {_up(c.stored.bound)}"
                  for c, _ in raised[:LISTED]]
        parts.append(f"C raised from {', '.join(f'{a:g}' for a in asked)}: "
                     + ", ".join(listed) + _more(len(raised)))
    for r in failed[:LISTED]:
        text = failure_text(r, batch.polygons)
        parts.append(f"{_name(batch, result, r.index, names)} {text}; left as it was"
                     if re.match(r"(is|has) ", text) else
                     f"{_name(batch, result, r.index, names)} left as it was: {text}")
    if len(failed) > LISTED:
        parts.append(f"{len(failed) - LISTED} more islands left as they were")
    for c in back[:LISTED]:
        why = c.stored.reason or "it no longer passes"
        if c.stored.failed_as_solved:  # the solve's own certificate did not check this
            text = f"its UVs fail the certificate ({why}) as solved already"
        else:
            text = (f"its stored UVs fail the certificate ({why}); " + (
                "packing shrank or moved it too far: unwrap it without packing" if packed
                else "float32 storage changed it"))
        where = (f" (moved {c.moved_tiles} UV tile{'s' if c.moved_tiles != 1 else ''} right, "
                 "off the written islands it lay over)" if c.moved_tiles else "")
        parts.append(f"{_name(batch, result, c.stored.island, names)} put back as it was"
                     f"{where}: {text}")
    if len(back) > LISTED:
        parts.append(f"{len(back) - LISTED} more islands put back as they were")
    n_overlaps = 0
    for object_name, pairs in (verified.overlaps.items() if verified is not None else ()):
        if pairs is None or not len(pairs):
            continue
        pairs = np.asarray(pairs).reshape(-1, 2)
        n_overlaps += len(pairs)
        listed = ", ".join(f"{a} and {b}" for a, b in pairs[:6]) + (
            f", ... ({len(pairs)} pairs in all)" if len(pairs) > 6 else "")
        parts.append(f"islands overlap in {object_name}'s UV map: {listed}"
                     + ("" if packed else "; turn on Pack Islands to lay them apart"))
    for object_name, tiles in (verified.moved.items() if verified is not None else ()):
        parts.append(f"the faces of {object_name} left as they were moved {tiles} UV "
                     f"tile{'s' if tiles != 1 else ''} right, off the written islands (a new "
                     "UV map's default squares)")
    for w in written:
        if w.skipped:
            parts.append(f"{w.object_name} not written: {w.skipped}")
    wrote = bool(kept)
    clean = not failed and not back and not n_overlaps and not any(w.skipped for w in written)
    # An ERROR makes a scripted bpy.ops call raise: only when nothing was written because the
    # scene changed under a background solve. Islands that cannot be unwrapped are a WARNING,
    # as with Blender's own Unwrap, so a script looping over objects carries on.
    level = 'INFO' if wrote and clean else (
        'ERROR' if not wrote and any(w.skipped for w in written) else 'WARNING')
    return Summary("; ".join(parts), level, wrote, len(kept), len(failed), float(max_d), mean_d,
                   flips, float(bound_c), float(seconds), label, len(raised), len(back),
                   n_overlaps)


def store(window_manager, summary, faces):
    """Keep ``summary`` in the window manager's ``bd_uv_last_result`` for the panel."""
    last = window_manager.bd_uv_last_result
    last.valid = summary.written
    last.method = summary.method
    last.islands = summary.islands
    last.failed = summary.failed
    last.faces = faces
    last.max_distortion = summary.max_distortion if np.isfinite(summary.max_distortion) else 0.0
    last.mean_distortion = summary.mean_distortion if np.isfinite(summary.mean_distortion) else 0.0
    last.flipped = summary.flipped
    last.bound_certified = summary.bound_certified if np.isfinite(summary.bound_certified) else 0.0
    last.seconds = summary.seconds
    last.raised = summary.raised
    last.put_back = summary.put_back
    last.overlaps = summary.overlaps
    last.report = summary.message
