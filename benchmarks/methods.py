"""The benchmarked methods, by key, and how one of them is run on one mesh.

Every method returns ``(corner_uv (m,3,2) float64, seconds, note, certified C or None)``; what
``seconds`` covers is said per method in BENCHMARKS.md. Nothing here measures distortion: that is
``measure.uv_stats``, the same for every method.
"""
from __future__ import annotations

import threading
import time

import numpy as np

import peers

# method key -> (label, kind, parameters)
METHODS = {
    "bd-lscm-5": ("bd-uv BD-LSCM C=5", "bd", {"method": "lscm", "bound": 5.0}),
    "bd-lscm-auto": ("bd-uv BD-LSCM auto", "bd", {"method": "lscm", "bound": "auto"}),
    "bd-arap-5": ("bd-uv BD-ARAP C=5", "bd", {"method": "arap", "bound": 5.0}),
    "bd-init-lscm": ("bd-uv initial LSCM map (frames.lscm_map)", "init", {}),
    "blender-abf": ("Blender ABF", "blender", {"method": "ANGLE_BASED"}),
    "blender-lscm": ("Blender LSCM", "blender", {"method": "CONFORMAL"}),
    "blender-minstretch": ("Blender Min Stretch", "blender", {"method": "MINIMUM_STRETCH"}),
    "igl-slim": ("libigl SLIM (sym. Dirichlet, 20 it)", "slim", {"iterations": 20}),
    "bd-seams-auto": ("bd-uv seams auto (C=2, S=2)", "seams", {"bound": 2.0, "stretch": 2.0}),
    "xatlas": ("xatlas (defaults)", "xatlas", {}),
}
PEER_KINDS = ("blender", "slim", "xatlas")   # results that do not depend on bd-uv's code


def is_peer(key: str) -> bool:
    """True for a method whose result does not depend on this repository's code."""
    return METHODS[key][1] in PEER_KINDS


def bd_warmup(params=None):
    """Import bd_uv and unwrap a small bumpy grid once, untimed (imports, solver load), with
    ``params`` (``unwrap``'s keywords; C = 5 by default): a method warms up on its own path, as
    each Blender operator is called once on a two-face disk before it is timed
    (``peers._bpy_setup``), so neither side's timed call carries one-time process costs
    (``bound="auto"``'s first search: ~0.4-1 ms of first use on top of C = 5's)."""
    import bd_uv

    g = np.linspace(0.0, 1.0, 6)
    x, y = np.meshgrid(g, g)
    V = np.c_[x.ravel(), y.ravel(), 0.1 * np.sin(3 * x.ravel()) * np.cos(2 * y.ravel())]
    i = np.arange(5)
    a = (i[:, None] * 6 + i[None, :]).ravel()
    F = np.r_[np.c_[a, a + 1, a + 7], np.c_[a, a + 7, a + 6]].astype(np.int64)
    try:
        bd_uv.unwrap(V, F, **(params or {"method": "lscm", "bound": 5.0}))
    except Exception:  # the timed run reports errors; the warm-up only loads code
        pass


def warmup(key: str):
    """Untimed warm-up for the method's kind (imports, first call)."""
    kind = METHODS[key][1]
    if kind == "bd":
        bd_warmup(METHODS[key][2])      # the method itself, on the small grid
    elif kind in ("init", "seams"):
        bd_warmup()
    if kind == "seams":
        run_seams(*_icosphere(), METHODS[key][2])
    elif kind == "xatlas":
        run_xatlas(*_icosphere())
    elif kind == "blender":
        peers._bpy_setup()
    elif kind == "slim":
        import igl  # noqa: F401


def run_bd(V, F, params, max_seconds):
    """bd_uv.unwrap with ``params``; cancelled through its cancel event after ``max_seconds``."""
    import bd_uv

    cancel = threading.Event()
    timer = threading.Timer(max_seconds, cancel.set) if max_seconds else None
    if timer:
        timer.daemon = True
        timer.start()
    try:
        t0 = time.perf_counter()
        try:
            res = bd_uv.unwrap(V, F, cancel=cancel, **params)
        except Exception as exc:
            if type(exc).__name__ == "CancelledError" and cancel.is_set():
                raise RuntimeError(f"not finished within --max-seconds {max_seconds:g} s "
                                   f"(cancelled after {time.perf_counter() - t0:.0f} s)") from exc
            raise
        seconds = time.perf_counter() - t0
    finally:
        if timer:
            timer.cancel()
    notes, cs = [], []
    statuses = {}
    for isl in res.islands:
        c = isl.bound_certified
        if c is not None:
            cs.append(float(c))
        statuses[isl.status] = statuses.get(isl.status, 0) + 1
        if len(res.islands) > 20:
            continue                      # many islands: a summary, not one note per island
        part = f"{isl.status}"
        if c is not None:
            part += f" C={c:.4g}"
        if isl.frames:
            part += f", frames {isl.frames}"
        if isl.solves is not None:
            part += f", {isl.solves} solves"
        if isl.flags:
            part += ", " + "/".join(isl.flags)
        if isl.status != "certified" and isl.message:
            part += f": {isl.message}"
        notes.append(part)
    if len(res.islands) > 1:
        solves = [isl.solves for isl in res.islands if isl.solves is not None]
        head = f"{len(res.islands)} islands (" + ", ".join(
            f"{n} {s}" for s, n in sorted(statuses.items())) + ")"
        if solves:
            head += f", {sum(solves)} solves in all"
        notes = [head] + notes
    certified = max(cs) if cs and res.certified else None
    return np.asarray(res.corner_uv, dtype=np.float64), seconds, "; ".join(notes), certified


def run_init_lscm(V, F):
    """bd-uv's own free-boundary LSCM map, island by island: the map issue 9 compares C=5 with.

    ``bd_uv.islands`` splits the mesh; per island ``bd_uv.geometry.local_coordinates`` and
    ``bd_uv.frames.lscm_map`` (two far boundary vertices pinned, Levy et al. 2002) give the map,
    with no bound and no solve. Timed as a whole.
    """
    from bd_uv import islands
    from bd_uv.frames import lscm_map
    from bd_uv.geometry import local_coordinates

    t0 = time.perf_counter()
    cu = np.full((len(F), 3, 2), np.nan)
    bad = 0
    for isl in islands(V, F):
        if isl.error is not None:
            bad += 1
            continue
        Z = local_coordinates(V[isl.vertices], isl.tris)
        u = lscm_map(Z, isl.tris, len(isl.vertices), isl.loops)
        c = u[isl.tris]
        cu[isl.faces, :, 0] = c.real
        cu[isl.faces, :, 1] = c.imag
    seconds = time.perf_counter() - t0
    return cu, seconds, (f"{bad} islands not mapped" if bad else "no bound, no solve"), None


def _icosphere():
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=2)
    return np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces, dtype=np.int64)


def run_seams(V, F, params):
    """``bd_uv.seams.unwrap_auto`` at C and S; ``seconds`` is the result's own ``seconds`` (the
    unwrap's, as its report gives it: the seam search and the certification, no packing)."""
    from bd_uv.seams import unwrap_auto

    res, added, info = unwrap_auto(V, F, bound=params["bound"], stretch=params["stretch"])
    bad = sum(r.status != "certified" for r in res.islands)
    note = f"{info['charts']} charts, seam length {info['seam_length']:.4g}" + (
        f", {bad} chart(s) not certified" if bad else ", every chart certified")
    cs = [r.bound_certified for r in res.islands if r.bound_certified is not None]
    return (np.asarray(res.corner_uv, dtype=np.float64), res.seconds, note,
            max(cs) if cs and res.certified else None)


def run_xatlas(V, F):
    """``xatlas.parametrize`` with its defaults (charts and packing); only that call is timed."""
    import xatlas

    Vf, Fi = V.astype(np.float32), F.astype(np.uint32)
    t0 = time.perf_counter()
    vmap, idx, uvs = xatlas.parametrize(Vf, Fi)
    seconds = time.perf_counter() - t0
    if not np.array_equal(vmap[idx], F):
        raise RuntimeError("xatlas reordered the faces")
    return uvs.astype(np.float64)[idx], seconds, "", None


def run_method(key, V, F, max_seconds):
    """Run one method; returns (corner_uv (m,3,2), seconds, note, certified C or None)."""
    _, kind, params = METHODS[key]
    if kind == "blender":
        cu, s, note = peers.blender_unwrap(V, F, params["method"])
        return cu, s, note, None
    if kind == "slim":
        cu, s, note = peers.slim_unwrap(V, F, params["iterations"])
        return cu, s, note, None
    if kind == "init":
        return run_init_lscm(V, F)
    if kind == "seams":
        return run_seams(V, F, params)
    if kind == "xatlas":
        return run_xatlas(V, F)
    return run_bd(V, F, params, max_seconds)
