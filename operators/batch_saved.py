"""``scripts/bd_uv_batch.py``'s post-write check: each written island certified again from the
UV map as it will be saved (float32, packed or not) with its own bound, the failing ones put back
as they were (no island that failed is ever saved), the report's figures those of the saved map,
and the saved layout drawn (``--png``).
"""
import os

import numpy as np

from ..bd_uv import batch
from ..bd_uv.metrics import conformal_distortion
from . import mesh_data, stored
from .batch_objects import file_name


def _put_back(w, undo):
    """Give the triangles ``undo`` (m,) bool their UVs from before the unwrap; a map created
    here is restored to what it held, or removed when nothing written is left on it. UVs that
    would lie over the islands kept go back moved right by whole tiles (``stored.tiles_off``).

    Returns
    -------
    int, the whole tiles they were moved by (0: exactly as they were)
    """
    mesh, name = w.ob.data, w.entry["uv_map"]
    kept = w.ok & ~undo
    if w.initial_uv is not None and not kept.any():
        mesh.uv_layers.remove(mesh.uv_layers[name])
        mesh.update()
        w.entry["uv_map"] = None
        return 0
    now = mesh_data.loop_uvs(mesh, name)
    loops = w.arrays.tri_loops[undo].ravel()
    old = (w.initial_uv[loops] if w.initial_uv is not None
           else np.asarray(w.arrays.corner_uv, np.float64)[undo].reshape(-1, 2))
    tiles = stored.tiles_off(now[w.arrays.tri_loops[kept].ravel()], old)
    if w.initial_uv is None:
        shift = np.array([tiles, 0.0])
        mesh_data.write_corner_uvs(mesh, name, w.arrays.tri_loops,
                                   w.arrays.corner_uv + shift if tiles else w.arrays.corner_uv,
                                   undo)
        return tiles
    now[loops] = old + np.array([tiles, 0.0], dtype=now.dtype)
    mesh.uv_layers[name].uv.foreach_set("vector", now.ravel())
    mesh.update()
    return tiles


def check_saved(written, packed):
    """The post-write check: re-certify each written island from the UV map as it will be saved
    (float32, packed or not) with that island's own bound, and put back every island that fails,
    so no island that failed is ever saved. The entry's figures become those of the stored,
    kept islands (area-weighted mean), its island entries gain the stored figures, and overlaps
    between the kept islands of the layout are counted.
    """
    for w in written:
        entry, arrays = w.entry, w.arrays
        uv = mesh_data.loop_uvs(w.ob.data, entry["uv_map"])[arrays.tri_loops].astype(np.float64)
        labels = np.where(w.ok, w.result.face_island, -1)
        checks = stored.check_stored(arrays.V, arrays.F, uv, labels, w.result.islands,
                                     solved_uv=w.result.corner_uv)
        by_index = {c.island: c for c in checks}
        undo = np.isin(labels, [c.island for c in checks if not c.certified])
        for isl in entry["islands"]:
            c = by_index.get(isl["island"])
            if c is None:
                continue
            isl.update(bound_certified=c.bound, max_distortion=c.max_distortion,
                       mean_distortion=c.mean_distortion, flipped=c.flipped,
                       overlap_free=bool(c.overlap_free))
            if not c.certified:
                cause = ("as solved already" if c.failed_as_solved else
                         "after packing" if packed else "after float32 storage")
                isl.update(status="failed", error="CertificationError",
                           message=f"island {c.island}: put back as it was, its saved UVs fail "
                                   f"the certificate ({c.reason}; {cause})")
        if undo.any():
            tiles = _put_back(w, undo)
            if tiles:
                for isl in entry["islands"]:
                    c = by_index.get(isl["island"])
                    if c is not None and not c.certified:
                        isl["message"] += (f"; moved {tiles} UV tile(s) right, off the saved "
                                           "islands it lay over")
                        isl["moved_tiles"] = tiles
            w.ok = w.ok & ~undo
        kept = [c for c in checks if c.certified]
        P = arrays.V[arrays.F]
        area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
        on = labels >= 0
        island_area = np.bincount(labels[on], weights=area[on], minlength=len(w.result.islands))
        weights = np.array([island_area[c.island] for c in kept])
        bad = [i for i in entry["islands"] if i["status"] != "certified"]
        entry["status"] = "certified" if not bad else ("partial" if kept else "failed")
        if kept:
            entry.update(bound_certified=max(c.bound for c in kept),
                         max_distortion=max(c.max_distortion for c in kept),
                         mean_distortion=float(np.dot(weights, [c.mean_distortion for c in kept])
                                               / weights.sum()),
                         flipped=int(sum(c.flipped for c in kept)))
        else:
            entry.update(bound_certified=None, max_distortion=None, mean_distortion=None,
                         flipped=None)
        if bad:
            entry["error"] = bad[0]["error"] or "IslandError"
            more = f" (and {len(bad) - 1} more failed island(s))" if len(bad) > 1 else ""
            entry["message"] = bad[0]["message"] + more
        kept_labels = np.where(w.ok, labels, -1)
        pairs = (stored.layout_overlaps(uv, kept_labels, arrays.F)
                 if len(np.unique(kept_labels[kept_labels >= 0])) > 1 else [])
        entry["island_overlaps"] = None if pairs is None else [
            [int(a), int(b)] for a, b in np.asarray(pairs).reshape(-1, 2)]
        # the layout as saved (packed or not), not the core's unpacked one
        entry["layout_overlaps"] = (None if pairs is None
                                    else len(entry["island_overlaps"]))


def draw_saved(written, options, args):
    """Draw each object's UV layout as saved (only the islands kept), when ``--png``."""
    for w in written:
        entry, ob, arrays, ok = w.entry, w.ob, w.arrays, w.ok
        if not args.png or entry["uv_map"] is None:
            continue
        uv = mesh_data.loop_uvs(ob.data, entry["uv_map"])[arrays.tri_loops].astype(np.float64)
        uv[~ok] = np.nan
        D = np.full(len(arrays.F), np.nan)
        D[ok] = conformal_distortion(arrays.V, arrays.F[ok], uv[ok])
        png = os.path.join(args.png, args.png_prefix + file_name(ob.name) + ".png")
        try:
            batch.entry_png(png, entry, uv, D, options)
        except Exception as exc:  # a picture that cannot be drawn must not lose the UVs
            entry.update(png=None, png_error=f"{type(exc).__name__}: {exc}")
