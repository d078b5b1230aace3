"""Run one (mesh, method) in its own Python process, so its time and peak memory are its own.

Parent side: ``run_isolated(mesh_path, key, max_seconds)`` starts
``python benchmarks/isolate.py MESH KEY --max-seconds S`` and returns the child's result dict.
``footprint(what)`` measures the peak resident memory of a process that only imports
``numpy`` / ``bd_uv`` / ``bpy`` (the bpy module's own footprint, to set Blender's peaks beside
bd-uv's).

Child side (``main``): import, load the mesh, warm the method up (untimed); then on Linux reset
the process's resident-memory high-water mark (``echo 5 > /proc/self/clear_refs``), so that the
transient memory of loading a large OBJ does not hide the method's own peak, and read the resident
set size ("base", ``VmRSS``); run the method once (timed as the method says), read the high-water
mark ("peak", ``VmHWM``: the most resident memory at any moment of the call, base included).
A call shorter than ``REPEAT_BELOW`` is made again, the same way, until ``REPEAT_SECONDS`` of
calls or ``REPEAT_MAX`` calls, and its time is the least (``calls`` in the result): a single
timing of a millisecond call moves by 20-40 % with the machine's state (stop 46's runs), more
than the ratios it decides. Every method is timed so, Blender's and xatlas's as bd-uv's.
Where ``/proc`` cannot do that, both come from ``resource.getrusage(RUSAGE_SELF).ru_maxrss``
(then the peak also covers loading and warm-up). ``RUSAGE_CHILDREN`` covers worker processes the
method waited for, reported separately when it grew during the call (a fork during bpy's warm-up
does not count). Then the UVs are measured with ``measure.uv_stats`` and, for the disk methods,
``map_shape`` (pieces in UV and whether a piece overlaps itself), and one JSON line prefixed
``BENCH_RESULT`` is printed; the peak was read before, so measuring does not change it.
"""
from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
MARK = "BENCH_RESULT "
REPEAT_BELOW = 0.1    # seconds: a call shorter than this is timed again ...
REPEAT_SECONDS = 0.5  # ... until this much time of calls ...
REPEAT_MAX = 20       # ... or this many calls; the least time counts


def _maxrss_mb(who=resource.RUSAGE_SELF) -> float:
    """Peak resident set size in MiB (Linux reports ru_maxrss in KiB, macOS in bytes)."""
    r = resource.getrusage(who).ru_maxrss
    return r / (1024.0 * 1024.0) if sys.platform == "darwin" else r / 1024.0


def _proc_status_mb(field: str) -> float | None:
    """``VmRSS`` / ``VmHWM`` of this process from /proc/self/status in MiB, or None."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith(field + ":"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return None


def _reset_peak() -> bool:
    """Reset this process's VmHWM to its current RSS (Linux >= 4.0); True if it worked."""
    try:
        with open("/proc/self/clear_refs", "w", encoding="ascii") as fh:
            fh.write("5")
    except OSError:
        return False
    hwm, rss = _proc_status_mb("VmHWM"), _proc_status_mb("VmRSS")
    return hwm is not None and rss is not None and hwm <= rss + 1.0


def _child_env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([HERE, REPO] + ([env["PYTHONPATH"]]
                                                      if env.get("PYTHONPATH") else []))
    return env


def _run_child(args, timeout):
    """Run ``python isolate.py ARGS``; return (result dict or None, error text)."""
    cmd = [sys.executable, os.path.join(HERE, "isolate.py")] + list(args)
    t0 = time.perf_counter()
    load0 = os.getloadavg()[0]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=_child_env(),
                           cwd=REPO)
    except subprocess.TimeoutExpired:
        return None, (f"killed after the {timeout:g} s cap (wall {time.perf_counter() - t0:.0f} s,"
                      " warm-up included)")
    for line in reversed(p.stdout.splitlines()):
        if line.startswith(MARK):
            out = json.loads(line[len(MARK):])
            out["load_start"], out["load_end"] = load0, os.getloadavg()[0]
            return out, ""
    tail = (p.stderr.strip().splitlines() or ["(no output)"])[-1]
    return None, f"child exited {p.returncode}: {tail[:300]}"


def run_isolated(mesh_path: str, key: str, max_seconds: float, kill_after: float | None = None):
    """Run method ``key`` on ``mesh_path`` in a fresh process.

    Parameters
    ----------
    mesh_path : str
    key : str, a key of ``methods.METHODS``
    max_seconds : float
        bd-uv is cancelled through its cancel event after this long (0 = never).
    kill_after : float, optional
        Wall-clock cap of the whole child (imports and warm-up included), after which it is
        killed; the only cap Blender and libigl get. Default ``max_seconds + 120`` (none if 0).

    Returns
    -------
    dict with ``seconds, note, certified_c, max_d, mean_d, flips, faces, rss_base_mb,
    rss_peak_mb, rss_children_mb, load_start, load_end`` or ``{"error": text}``.
    """
    if kill_after is None:
        kill_after = max_seconds + 120.0 if max_seconds else None
    out, err = _run_child([mesh_path, key, "--max-seconds", str(max_seconds)], kill_after)
    return out if out is not None else {"error": err}


def footprint(what: str) -> float | None:
    """Peak RSS in MiB of a fresh Python that imports numpy and ``what`` ("numpy", "bd_uv",
    "bpy": bpy also loads the empty factory scene), or None if that fails."""
    out, _ = _run_child(["--footprint", what], 300)
    return None if out is None else out["rss_mb"]


def _footprint_main(what):
    import numpy  # noqa: F401

    if what == "bd_uv":
        import bd_uv  # noqa: F401
    elif what == "bpy":
        import bpy

        bpy.ops.wm.read_factory_settings(use_empty=True)
    print(MARK + json.dumps({"rss_mb": _maxrss_mb()}), flush=True)


DISK_KINDS = ("blender", "slim", "bd")     # methods whose map's pieces and overlap are reported


def map_shape(F, corner_uv, flips):
    """(pieces, overlaps) of a map, from its corner UVs alone.

    ``pieces``: connected components of the faces, two faces joined where they share a mesh edge
    and both its corners' UVs (exactly: a cut gives each side its own UVs). ``overlaps``: True
    where the map has a flipped face (a flip lies over its neighbours) or a piece whose UV
    boundary is not simple and counter-clockwise (``bd_uv.overlap.island_overlaps``, Lipman 2012
    Theorems 5.1-5.2, per piece: pieces are not tested against each other).
    """
    import numpy as np
    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import connected_components

    from bd_uv.overlap import island_overlaps

    F = np.asarray(F, dtype=np.int64)
    uv = np.asarray(corner_uv, dtype=np.float64)
    m = len(F)
    nxt = [1, 2, 0]
    a, b = F.ravel(), F[:, nxt].ravel()                        # half-edge (a, b) of face f
    f = np.repeat(np.arange(m), 3)
    ua, ub = uv.reshape(-1, 2), uv[:, nxt].reshape(-1, 2)
    n = int(F.max()) + 1
    key, rkey = a * n + b, b * n + a
    order = np.argsort(key)
    pos = np.searchsorted(key[order], rkey)
    pos = np.minimum(pos, len(key) - 1)
    twin = order[pos]
    has = key[twin] == rkey                                   # half-edge (b, a) exists
    i = np.flatnonzero(has)
    j = twin[i]
    same = (ua[i] == ub[j]).all(axis=1) & (ub[i] == ua[j]).all(axis=1)
    i, j = i[same], j[same]
    g = coo_array((np.ones(len(i)), (f[i], f[j])), shape=(m, m))
    k, lab = connected_components(g, directed=False)
    if flips:
        return int(k), True
    ov = island_overlaps(F, uv, lab, k)
    return int(k), bool(not ov.overlap_free.all())


def main(argv=None):
    import argparse

    ap = argparse.ArgumentParser(description="one (mesh, method) run; prints a JSON line")
    ap.add_argument("mesh", nargs="?")
    ap.add_argument("key", nargs="?")
    ap.add_argument("--max-seconds", type=float, default=0.0)
    ap.add_argument("--footprint", choices=["numpy", "bd_uv", "bpy"])
    a = ap.parse_args(argv)
    if a.footprint:
        _footprint_main(a.footprint)
        return 0

    import numpy as np

    from measure import load_mesh_by_index, uv_stats
    from methods import run_method, warmup

    V, F = load_mesh_by_index(a.mesh)
    warmup(a.key)
    hwm = _reset_peak()
    base = _proc_status_mb("VmRSS") if hwm else _maxrss_mb()
    base_children = _maxrss_mb(resource.RUSAGE_CHILDREN)
    try:
        cu, seconds, note, cert = run_method(a.key, V, F, a.max_seconds)
    except Exception as exc:  # still report the memory the failed or cancelled call reached
        print(MARK + json.dumps({"error": f"{type(exc).__name__}: {exc}".splitlines()[0][:300],
                                 "faces": int(len(F)), "rss_base_mb": base,
                                 "rss_peak_mb": _proc_status_mb("VmHWM") if hwm else _maxrss_mb()}),
              flush=True)
        return 1
    peak = _proc_status_mb("VmHWM") if hwm else _maxrss_mb()
    peak_children = _maxrss_mb(resource.RUSAGE_CHILDREN)
    calls, spent = 1, seconds
    while seconds < REPEAT_BELOW and spent < REPEAT_SECONDS and calls < REPEAT_MAX:
        again = run_method(a.key, V, F, a.max_seconds)[1]
        seconds, spent, calls = min(seconds, again), spent + again, calls + 1
    st = uv_stats(V, F, cu)
    if cert is not None and st.max_distortion > cert * (1 + 1e-6):
        note += f"; recomputed max D exceeds certified C {cert:.6g}"
    res = {"seconds": seconds, "calls": calls, "note": note, "certified_c": cert,
           "max_d": None if not np.isfinite(st.max_distortion) else st.max_distortion,
           "mean_d": None if not np.isfinite(st.mean_distortion) else st.mean_distortion,
           "flips": st.flips, "faces": int(len(F)), "rss_base_mb": base, "rss_peak_mb": peak,
           "peak_source": "VmHWM" if hwm else "ru_maxrss",
           "rss_children_mb": peak_children if peak_children > base_children else 0.0}
    from methods import METHODS

    if METHODS[a.key][1] in DISK_KINDS:
        res["pieces"], res["overlaps"] = map_shape(F, cu, st.flips)
    print(MARK + json.dumps(res), flush=True)
    return 0


if __name__ == "__main__":
    sys.path[:0] = [HERE, REPO]
    try:
        sys.exit(main())
    except Exception as exc:  # the parent reports the last stderr line
        import traceback

        traceback.print_exc()
        print(f"{type(exc).__name__}: {exc}".splitlines()[0][:300], file=sys.stderr)
        sys.exit(1)
