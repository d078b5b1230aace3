"""Benchmark bd-uv against Blender's unwrappers and libigl's SLIM on the same triangles.

    python benchmarks/bench_unwrap.py [FOLDER_OR_FILES...] [--methods M ...] [--out table.md]

For every mesh (OBJ/OFF/PLY; folders are scanned, default ``tests/data``) and every method, one
after another in this one process, it prints a markdown table: faces, seconds, max and
area-weighted mean conformal distortion, flipped faces, and the time ratio to Blender's ABF measured
in the same run. Distortion is recomputed for every method by ``measure.uv_stats`` from the UVs the
method returned, never taken from the method itself. Closed meshes are skipped (they need seams).
A method that raises gets its error in the table and the run goes on.

Below the table: per mesh, whether bd-uv ``bound="auto"``'s certified C is at most the lowest max
distortion of Blender ABF, LSCM (only when flip-free) and Minimum Stretch, times 1.02; and the
median over meshes of BD-LSCM (C = 5) seconds / ABF seconds.

It is a measurement, not a test: nothing here asserts a time.
"""
from __future__ import annotations

import argparse
import glob
import os
import platform
import shlex
import statistics
import sys
import threading
import time
import traceback
from dataclasses import dataclass, field

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if REPO not in sys.path:
    sys.path.insert(1, REPO)

from measure import boundary_edge_count, load_mesh_by_index, uv_stats  # noqa: E402
import peers  # noqa: E402

# method key -> (label, kind, parameters)
METHODS = {
    "bd-lscm-5": ("bd-uv BD-LSCM C=5", "bd", {"method": "lscm", "bound": 5.0}),
    "bd-lscm-auto": ("bd-uv BD-LSCM auto", "bd", {"method": "lscm", "bound": "auto"}),
    "bd-arap-5": ("bd-uv BD-ARAP C=5", "bd", {"method": "arap", "bound": 5.0}),
    "blender-abf": ("Blender ABF", "blender", {"method": "ANGLE_BASED"}),
    "blender-lscm": ("Blender LSCM", "blender", {"method": "CONFORMAL"}),
    "blender-minstretch": ("Blender Min Stretch", "blender", {"method": "MINIMUM_STRETCH"}),
    "igl-slim": ("libigl SLIM (sym. Dirichlet, 20 it)", "slim", {"iterations": 20}),
}
DEFAULT_ORDER = ["blender-abf", "blender-lscm", "blender-minstretch", "igl-slim",
                 "bd-lscm-5", "bd-lscm-auto", "bd-arap-5"]
MESH_EXTS = (".obj", ".off", ".ply")


@dataclass
class Row:
    mesh: str
    faces: int
    key: str
    seconds: float = float("nan")
    max_d: float = float("nan")
    mean_d: float = float("nan")
    flips: int | None = None
    note: str = ""
    error: str = ""
    certified_c: float | None = None
    extra: dict = field(default_factory=dict)


def mesh_paths(args: list[str]) -> list[str]:
    """Mesh files named by ``args`` (files, or folders scanned for OBJ/OFF/PLY, sorted)."""
    out = []
    for a in args:
        if os.path.isdir(a):
            out.extend(sorted(p for p in glob.glob(os.path.join(a, "*"))
                              if p.lower().endswith(MESH_EXTS)))
        else:
            out.append(a)
    return out


def _bd_warmup():
    """Import bd_uv and unwrap a small bumpy grid once, untimed (imports, solver load)."""
    import bd_uv

    g = np.linspace(0.0, 1.0, 6)
    x, y = np.meshgrid(g, g)
    V = np.c_[x.ravel(), y.ravel(), 0.1 * np.sin(3 * x.ravel()) * np.cos(2 * y.ravel())]
    i = np.arange(5)
    a = (i[:, None] * 6 + i[None, :]).ravel()
    F = np.r_[np.c_[a, a + 1, a + 7], np.c_[a, a + 7, a + 6]].astype(np.int64)
    try:
        bd_uv.unwrap(V, F, method="lscm", bound=5.0)
    except Exception:  # the timed run reports errors; the warm-up only loads code
        pass


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
    for isl in res.islands:
        c = isl.bound_certified
        if c is not None:
            cs.append(float(c))
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
        notes = [f"{len(res.islands)} islands"] + notes
    certified = max(cs) if cs and res.certified else None
    return np.asarray(res.corner_uv, dtype=np.float64), seconds, "; ".join(notes), certified


def run_method(key, V, F, max_seconds):
    """Run one method; returns (corner_uv (m,3,2), seconds, note, certified C or None)."""
    _, kind, params = METHODS[key]
    if kind == "blender":
        cu, s, note = peers.blender_unwrap(V, F, params["method"])
        return cu, s, note, None
    if kind == "slim":
        cu, s, note = peers.slim_unwrap(V, F, params["iterations"])
        return cu, s, note, None
    return run_bd(V, F, params, max_seconds)


def fmt(x, digits=4):
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "-" if x is None or np.isnan(x) else "inf"
    return f"{x:.{digits}g}"


def fmt_s(x):
    if x is None or not np.isfinite(x):
        return "-"
    return f"{x:.3f}" if x < 10 else f"{x:.1f}"


def versions() -> str:
    parts = [f"Python {platform.python_version()}", f"numpy {np.__version__}"]
    for mod, attr in (("bpy", None), ("igl", None), ("clarabel", "__version__"),
                      ("scipy", "__version__")):
        try:
            m = __import__(mod)
            if mod == "bpy":
                v = m.app.version_string
            else:
                from importlib.metadata import version
                v = version("libigl" if mod == "igl" else mod)
            parts.append(f"{mod} {v}")
        except Exception:
            parts.append(f"{mod} unavailable")
    return ", ".join(parts)


def render(rows, skipped, methods, command) -> str:
    """The markdown report: the main table, the auto check and the median time ratio."""
    out = []
    out.append(f"Command: `{command}`  ")
    out.append(f"Run: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
               f"{platform.machine()} with {os.cpu_count()} cores (shared), {versions()}.")
    out.append("")
    out.append("Distortion is recomputed for every method from its UVs: per face the 2x2 Jacobian "
               "from the face's 3D shape to its UVs, D = s_max/s_min; flipped = signed UV area <= 0; "
               "max D and the 3D-area-weighted mean D are over non-flipped faces.")
    out.append("")
    out.append("| mesh | faces | method | seconds | max D | mean D | flips | time / ABF | notes |")
    out.append("|---|---:|---|---:|---:|---:|---:|---:|---|")
    abf = {r.mesh: r.seconds for r in rows if r.key == "blender-abf" and not r.error}
    for r in rows:
        label = METHODS[r.key][0]
        ratio = r.seconds / abf[r.mesh] if r.mesh in abf and np.isfinite(r.seconds) else None
        note = r.note
        if r.error:
            note = ("ERROR " + r.error + ("; " + note if note else "")).replace("|", "/")
        out.append(f"| {r.mesh} | {r.faces} | {label} | {fmt_s(r.seconds)} | {fmt(r.max_d)} | "
                   f"{fmt(r.mean_d)} | {'-' if r.flips is None else r.flips} | "
                   f"{'-' if ratio is None else f'{ratio:.2f}'} | {note.replace('|', '/')} |")
    if skipped:
        out.append("")
        for name, why in skipped:
            out.append(f"- skipped {name}: {why}")

    meshes = list(dict.fromkeys(r.mesh for r in rows))
    by = {(r.mesh, r.key): r for r in rows}
    if "bd-lscm-auto" in methods:
        out.append("")
        out.append("bd-uv `auto` certified C against the lowest max D of Blender ABF, LSCM (only if "
                   "flip-free) and Minimum Stretch on the same mesh, with 2% slack:")
        out.append("")
        out.append("| mesh | auto certified C | auto max D (recomputed) | lowest peer max D | "
                   "peer x 1.02 | C <= peer x 1.02 |")
        out.append("|---|---:|---:|---:|---:|---|")
        for m in meshes:
            auto = by.get((m, "bd-lscm-auto"))
            cands = []
            for k in ("blender-abf", "blender-lscm", "blender-minstretch"):
                r = by.get((m, k))
                if r is None or r.error or not np.isfinite(r.max_d):
                    continue
                if k == "blender-lscm" and r.flips:
                    continue
                cands.append((r.max_d, METHODS[k][0]))
            best = min(cands) if cands else None
            c = auto.certified_c if auto is not None else None
            if c is None or best is None:
                verdict = "n/a (" + ("no certified auto result" if c is None
                                     else "no peer result") + ")"
            else:
                verdict = "yes" if c <= best[0] * 1.02 else "NO"
            out.append(f"| {m} | {fmt(c)} | {fmt(auto.max_d) if auto else '-'} | "
                       f"{fmt(best[0]) + ' (' + best[1] + ')' if best else '-'} | "
                       f"{fmt(best[0] * 1.02) if best else '-'} | {verdict} |")
    if "bd-lscm-5" in methods and "blender-abf" in methods:
        ratios = []
        for m in meshes:
            a, b = by.get((m, "blender-abf")), by.get((m, "bd-lscm-5"))
            if a and b and not a.error and not b.error:
                ratios.append((m, b.seconds / a.seconds))
        out.append("")
        if ratios:
            med = statistics.median(r for _, r in ratios)
            out.append(f"Median over {len(ratios)} meshes of (BD-LSCM C=5 seconds / ABF seconds): "
                       f"**{med:.2f}** (" + ", ".join(f"{m} {r:.2f}" for m, r in ratios) + ").")
        else:
            out.append("Median BD-LSCM C=5 / ABF time ratio: n/a (no mesh with both results).")
    return "\n".join(out) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("paths", nargs="*", default=[os.path.join(REPO, "tests", "data")],
                    help="mesh files or folders (default: tests/data)")
    ap.add_argument("--methods", nargs="+", choices=list(METHODS), default=DEFAULT_ORDER,
                    metavar="METHOD", help="any of: " + ", ".join(DEFAULT_ORDER))
    ap.add_argument("--out", help="also write the markdown report to this file")
    ap.add_argument("--repeat", type=int, default=1,
                    help="run each method this many times and keep the fastest (default 1)")
    ap.add_argument("--max-seconds", type=float, default=600.0,
                    help="cancel a bd-uv call after this long, through its cancel event "
                         "(default 600; 0 = never)")
    args = ap.parse_args(argv)
    command = "python " + " ".join(shlex.quote(a) for a in [os.path.relpath(sys.argv[0], REPO)]
                                   + sys.argv[1:]) if argv is None else "bench_unwrap " + " ".join(argv)

    paths = mesh_paths(args.paths)
    if not paths:
        print(f"no OBJ/OFF/PLY meshes in {args.paths}", file=sys.stderr)
        return 2
    methods = [k for k in DEFAULT_ORDER if k in args.methods]

    if any(METHODS[k][1] == "bd" for k in methods):
        try:
            _bd_warmup()
        except Exception as exc:
            print(f"bd_uv unavailable: {exc!r}", file=sys.stderr)

    rows, skipped = [], []
    for path in paths:
        name = os.path.basename(path)
        try:
            V, F = load_mesh_by_index(path)
        except Exception as exc:
            skipped.append((name, f"could not load: {exc!r}"))
            continue
        if boundary_edge_count(F) == 0:
            skipped.append((name, f"closed mesh ({len(F)} faces, no boundary): needs seams"))
            print(f"{name}: closed, skipped", file=sys.stderr)
            continue
        for key in methods:
            row = Row(name, len(F), key)
            try:
                best = None
                for _ in range(max(1, args.repeat)):
                    cu, s, note, c = run_method(key, V, F, args.max_seconds)
                    if best is None or s < best[1]:
                        best = (cu, s, note, c)
                cu, row.seconds, row.note, row.certified_c = best
                st = uv_stats(V, F, cu)
                row.max_d, row.mean_d, row.flips = st.max_distortion, st.mean_distortion, st.flips
                if row.certified_c is not None and row.max_d > row.certified_c * (1 + 1e-6):
                    row.note += f"; recomputed max D exceeds certified C {row.certified_c:.6g}"
            except Exception as exc:
                row.error = f"{type(exc).__name__}: {exc}".splitlines()[0][:300]
                traceback.print_exc(file=sys.stderr)
            rows.append(row)
            print(f"{name} {len(F)}f {METHODS[key][0]}: {fmt_s(row.seconds)} s, max D "
                  f"{fmt(row.max_d)}, mean D {fmt(row.mean_d)}, flips {row.flips} "
                  f"{row.note} {row.error}", file=sys.stderr, flush=True)

    report = render(rows, skipped, methods, command)
    print(report)
    if args.out:
        with open(args.out, "w", encoding="utf-8") as fh:
            fh.write(report)
    return 0


if __name__ == "__main__":
    sys.exit(main())
