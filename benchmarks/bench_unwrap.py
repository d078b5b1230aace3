"""Benchmark bd-uv against Blender's unwrappers and libigl's SLIM on the same triangles.

    python benchmarks/bench_unwrap.py [FOLDER_OR_FILES...] [--methods M ...] [--out table.md]
        [--json results.json] [--reuse-peers results.json]

For every mesh (OBJ/OFF/PLY; folders are scanned, default ``tests/data``) and every method, one
after another, each in its own fresh Python process (``isolate.py``: time and peak memory are the
method's own), it prints a markdown table: faces, seconds, max and area-weighted mean conformal
distortion, flipped faces, the time ratio to Blender's ABF measured in the same run, peak resident
memory, and the load average around the run. Distortion is recomputed for every method by
``measure.uv_stats`` from the UVs the method returned, never taken from the method itself. Closed
meshes are skipped (they need seams). A method that fails or hits its cap gets its error in the
table and the run goes on.

Below the table: issue 9's "done when" per mesh and over meshes, PASS/FAIL per criterion
(``done_when``). Blender and libigl results do not depend on this repository's code:
``--json`` saves every row, and ``--reuse-peers`` takes them from such a file so that a re-run
only runs bd-uv.

It is a measurement, not a test: nothing here asserts a time.
"""
from __future__ import annotations

import argparse
import glob
import os
import platform
import shlex
import statistics
import json
import sys
import time
from dataclasses import asdict, dataclass

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if REPO not in sys.path:
    sys.path.insert(1, REPO)

from isolate import footprint, run_isolated  # noqa: E402
from measure import boundary_edge_count, load_mesh_by_index  # noqa: E402
from methods import METHODS, is_peer  # noqa: E402

DEFAULT_ORDER = ["blender-abf", "blender-lscm", "blender-minstretch", "igl-slim",
                 "bd-init-lscm", "bd-lscm-5", "bd-lscm-auto", "bd-arap-5"]
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
    rss_base_mb: float | None = None
    rss_peak_mb: float | None = None
    rss_children_mb: float | None = None
    load: str = ""
    cached: bool = False


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


def measure_row(path, name, faces, key, max_seconds, repeat=1, kill_after=None) -> Row:
    """Run ``key`` on ``path`` in ``repeat`` fresh processes (``isolate.run_isolated``) and keep
    the fastest; an error or a cap becomes the row's ``error``."""
    row = Row(name, faces, key)
    best = None
    for _ in range(max(1, repeat)):
        r = run_isolated(path, key, max_seconds, kill_after)
        if "error" in r:
            row.error = r["error"]
            row.rss_base_mb, row.rss_peak_mb = r.get("rss_base_mb"), r.get("rss_peak_mb")
            if "load_start" in r:
                row.load = f"{r['load_start']:.1f}->{r['load_end']:.1f}"
            return row
        if best is None or r["seconds"] < best["seconds"]:
            best = r
    row.seconds, row.note, row.certified_c = best["seconds"], best["note"], best["certified_c"]
    row.max_d = float("nan") if best["max_d"] is None else best["max_d"]
    row.mean_d = float("nan") if best["mean_d"] is None else best["mean_d"]
    row.flips = best["flips"]
    row.rss_base_mb, row.rss_peak_mb = best["rss_base_mb"], best["rss_peak_mb"]
    row.rss_children_mb = best["rss_children_mb"]
    row.load = f"{best['load_start']:.1f}->{best['load_end']:.1f}"
    return row


def load_cache(path) -> dict:
    """Rows of a ``--json`` file by (mesh, faces, key)."""
    with open(path, encoding="utf-8") as fh:
        data = json.load(fh)
    known = set(Row.__dataclass_fields__)
    return {(d["mesh"], d["faces"], d["key"]): Row(**{k: v for k, v in d.items() if k in known})
            for d in data["rows"]}


def save_json(path, rows, extra=None):
    """Every row (and ``extra``) as JSON; NaN becomes null."""
    def clean(v):
        return None if isinstance(v, float) and not np.isfinite(v) else v

    data = {"rows": [{k: clean(v) for k, v in asdict(r).items()} for r in rows]}
    data.update(extra or {})
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(data, fh, indent=1)


def from_cache(cache, name, faces, key):
    """A cached peer row, or None (NaN restored for missing numbers)."""
    r = cache.get((name, faces, key))
    if r is None or r.error:
        return None
    for f in ("seconds", "max_d", "mean_d"):
        if getattr(r, f) is None:
            setattr(r, f, float("nan"))
    r.cached = True
    return r


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


def fmt_mb(x):
    return "-" if x is None else f"{x:.0f}"


def run_header(command, footprints):
    """Command, date, machine, versions and the import footprints, as markdown lines."""
    out = [f"Command: `{command}`  ",
           f"Run: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
           f"{platform.machine()} with {os.cpu_count()} cores (shared), {versions()}."]
    if footprints:
        out.append("")
        out.append("Peak RSS of a Python process that only imports: " + ", ".join(
            f"{k} {fmt_mb(v)} MiB" for k, v in footprints.items())
            + " (bpy: import plus the empty factory scene). Every method below runs in its own "
            "process; 'peak' is that process's most resident memory during the timed call "
            "(Linux VmHWM, reset after imports, mesh load and the untimed warm-up; so it includes "
            "the bpy or bd_uv import and the loaded mesh), 'peak - base' what the call added to "
            "the memory resident just before it, both in MiB.")
    return out


def cached_warning(rows):
    """A warning line when some rows were reused from an earlier run (``--reuse-peers``)."""
    if not any(r.cached for r in rows):
        return []
    return ["**Some peer rows are reused from an earlier run (`--reuse-peers`): their time ratios "
            "compare two runs made under different loads (see 'load' per row); for ratios of "
            "record, run the peers again in the same run.**", ""]


def main_table(rows):
    """The per-(mesh, method) markdown table."""
    out = ["| mesh | faces | method | seconds | max D | mean D | flips | time / ABF | "
           "peak MiB | peak - base | load | notes |",
           "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---|---|"]
    abf = {r.mesh: r.seconds for r in rows if r.key == "blender-abf" and not r.error}
    for r in rows:
        label = METHODS[r.key][0]
        ratio = r.seconds / abf[r.mesh] if r.mesh in abf and np.isfinite(r.seconds) else None
        notes = ([f"ERROR {r.error}"] if r.error else []) + ([r.note] if r.note else [])
        if r.rss_children_mb and r.rss_children_mb > 1:
            notes.append(f"worker processes' peak {r.rss_children_mb:.0f} MiB")
        if r.cached:
            notes.append("cached peer result")
        note = "; ".join(notes)
        added = (r.rss_peak_mb - r.rss_base_mb) if r.rss_peak_mb is not None else None
        out.append(f"| {r.mesh} | {r.faces} | {label} | {fmt_s(r.seconds)} | {fmt(r.max_d)} | "
                   f"{fmt(r.mean_d)} | {'-' if r.flips is None else r.flips} | "
                   f"{'-' if ratio is None else f'{ratio:.2f}'} | {fmt_mb(r.rss_peak_mb)} | "
                   f"{fmt_mb(added)} | {r.load} | {note.replace('|', '/')} |")
    return out


def _ok(r):
    return r is not None and not r.error and np.isfinite(r.seconds)


def verdict(ok):
    return "n/a" if ok is None else ("PASS" if ok else "FAIL")


def done_when(rows, methods):
    """Issue 9's "done when" checks, per mesh and over meshes, as markdown lines.

    C = 5 (``bd-lscm-5``): 0 flips; max D <= 5; max D <= the initial conformal map's
    (``bd-init-lscm``) max D whenever that map has no flip; mean D <= 1.02 x Blender ABF's.
    ``auto``: certified C strictly below the lowest max D of Blender ABF, LSCM, Minimum Stretch and
    SLIM (a peer map with flipped faces is not a candidate); mean D <= 1.05 x ABF's; median
    auto / ABF time <= 3. Speed: median C=5 / ABF time <= 1.0 and none above 3.
    """
    meshes = list(dict.fromkeys(r.mesh for r in rows))
    by = {(r.mesh, r.key): r for r in rows}
    tol = 1 + 1e-6
    out = ["| mesh | C=5 flips = 0 | C=5 max <= 5 | C=5 max <= initial LSCM max | "
           "C=5 mean <= 1.02 ABF | auto C < best peer max | auto mean <= 1.05 ABF | "
           "C=5 / ABF time | auto / ABF time |",
           "|---|---|---|---|---|---|---|---:|---:|"]
    tally = {}

    def mark(name, ok, text):
        tally.setdefault(name, []).append(ok)
        return f"{verdict(ok)} ({text})" if text else verdict(ok)

    r5_ratios, auto_ratios = [], []
    for m in meshes:
        abf, c5 = by.get((m, "blender-abf")), by.get((m, "bd-lscm-5"))
        auto = by.get((m, "bd-lscm-auto"))
        init = by.get((m, "bd-init-lscm"))
        cells = []
        if _ok(c5):
            cells.append(mark("flips", c5.flips == 0, str(c5.flips)))
            cells.append(mark("max5", c5.max_d <= 5.0 * tol
                              and (c5.certified_c is None or c5.certified_c <= 5.0 * tol),
                              fmt(c5.max_d)))
            if _ok(init) and init.flips == 0:
                cells.append(mark("init", c5.max_d <= init.max_d * tol,
                                  f"{fmt(c5.max_d)} vs {fmt(init.max_d)}"))
            else:
                cells.append(mark("init", None, "initial map flips" if _ok(init)
                                  else "no initial-map result"))
            cells.append(mark("mean5", c5.mean_d <= 1.02 * abf.mean_d, f"{fmt(c5.mean_d)} vs "
                              f"{fmt(1.02 * abf.mean_d)}") if _ok(abf)
                         else mark("mean5", None, "no ABF"))
        else:
            cells += [mark(k, False if "bd-lscm-5" in methods else None,
                          "no C=5 result") for k in ("flips", "max5", "init", "mean5")]
        if _ok(auto):
            cands = [(by[(m, k)].max_d, METHODS[k][0]) for k in
                     ("blender-abf", "blender-lscm", "blender-minstretch", "igl-slim")
                     if _ok(by.get((m, k))) and by[(m, k)].flips == 0]
            c = auto.certified_c
            if cands and c is not None:
                best = min(cands)
                cells.append(mark("autoC", c < best[0], f"{fmt(c)} vs {fmt(best[0])} "
                                  f"{best[1].split(' (')[0]}"))
            else:
                cells.append(mark("autoC", False if c is None else None,
                                  "not certified" if c is None else "no flip-free peer"))
            cells.append(mark("autoMean", auto.mean_d <= 1.05 * abf.mean_d,
                              f"{fmt(auto.mean_d)} vs {fmt(1.05 * abf.mean_d)}") if _ok(abf)
                         else mark("autoMean", None, "no ABF"))
        else:
            cells += [mark(k, False if "bd-lscm-auto" in methods else None,
                          "no auto result") for k in ("autoC", "autoMean")]
        t5 = c5.seconds / abf.seconds if _ok(c5) and _ok(abf) else None
        ta = auto.seconds / abf.seconds if _ok(auto) and _ok(abf) else None
        if t5 is not None:
            r5_ratios.append(t5)
        if ta is not None:
            auto_ratios.append(ta)
        cells += ["-" if t5 is None else f"{t5:.2f}", "-" if ta is None else f"{ta:.2f}"]
        out.append(f"| {m} | " + " | ".join(cells) + " |")

    def all_of(name):
        v = [x for x in tally.get(name, []) if x is not None]
        if not v:
            return None
        return all(v)

    def count(name):
        v = tally.get(name, [])
        return (f"{sum(1 for x in v if x)}/{len(v)} pass"
                + (f", {sum(1 for x in v if x is None)} n/a" if any(x is None for x in v) else ""))

    out.append("")
    lines = [
        ("C=5: 0 flips on every mesh", all_of("flips"), count("flips")),
        ("C=5: max D <= 5 on every mesh", all_of("max5"), count("max5")),
        ("C=5: max D <= initial LSCM map's max wherever that map is flip-free", all_of("init"),
         count("init")),
        ("C=5: mean D <= 1.02 x ABF mean on every mesh", all_of("mean5"), count("mean5")),
        ("auto: certified C < min(ABF, LSCM, Min Stretch, SLIM) max on every mesh",
         all_of("autoC"), count("autoC")),
        ("auto: mean D <= 1.05 x ABF mean on every mesh", all_of("autoMean"), count("autoMean")),
    ]
    if auto_ratios:
        med = statistics.median(auto_ratios)
        lines.append(("auto: median time <= 3x ABF", med <= 3.0, f"median {med:.2f}"))
    if r5_ratios:
        med = statistics.median(r5_ratios)
        lines.append(("C=5: median time <= 1.0x ABF", med <= 1.0, f"median {med:.2f}"))
        lines.append(("C=5: no mesh above 3x ABF time", max(r5_ratios) <= 3.0,
                      f"worst {max(r5_ratios):.2f}"))
    for text, ok, detail in lines:
        out.append(f"- **{verdict(ok)}** {text}: {detail}")
    return out


def render(rows, skipped, methods, command, footprints=None) -> str:
    """The markdown report: header, the main table, and issue 9's done-when checks."""
    out = run_header(command, footprints)
    out.append("")
    out.append("Distortion is recomputed for every method from its UVs: per face the 2x2 Jacobian "
               "from the face's 3D shape to its UVs, D = s_max/s_min; flipped = signed UV area "
               "<= 0; "
               "max D and the 3D-area-weighted mean D are over non-flipped faces. 'load' is the "
               "1-minute load average when the method's process started and ended.")
    out.append("")
    out += cached_warning(rows)
    out += main_table(rows)
    if skipped:
        out.append("")
        for name, why in skipped:
            out.append(f"- skipped {name}: {why}")
    out.append("")
    out.append("Issue 9 \"done when\" on these meshes (PASS/FAIL per mesh; n/a when a result is "
               "missing or the criterion does not apply):")
    out.append("")
    out += done_when(rows, methods)
    return "\n".join(out) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("paths", nargs="*", default=[os.path.join(REPO, "tests", "data")],
                    help="mesh files or folders (default: tests/data)")
    ap.add_argument("--methods", nargs="+", choices=list(METHODS), default=DEFAULT_ORDER,
                    metavar="METHOD", help="any of: " + ", ".join(DEFAULT_ORDER))
    ap.add_argument("--out", help="also write the markdown report to this file")
    ap.add_argument("--json", help="also write every row (with memory and load) to this JSON file")
    ap.add_argument("--reuse-peers", metavar="JSON",
                    help="take Blender and libigl rows from this earlier --json file instead of "
                         "running them again (matched by mesh name, faces and method)")
    ap.add_argument("--repeat", type=int, default=1,
                    help="run each method this many times (fresh process each) and keep the "
                         "fastest (default 1)")
    ap.add_argument("--max-seconds", type=float, default=600.0,
                    help="cancel a bd-uv call after this long, through its cancel event; any "
                         "method's process is killed 120 s after it (default 600; 0 = never)")
    args = ap.parse_args(argv)
    command = ("python " + " ".join(shlex.quote(a) for a in [os.path.relpath(sys.argv[0], REPO)]
                                    + sys.argv[1:])
               if argv is None else "bench_unwrap " + " ".join(argv))

    paths = [os.path.abspath(p) for p in mesh_paths(args.paths)]
    if not paths:
        print(f"no OBJ/OFF/PLY meshes in {args.paths}", file=sys.stderr)
        return 2
    methods = [k for k in DEFAULT_ORDER if k in args.methods]
    cache = load_cache(args.reuse_peers) if args.reuse_peers else {}
    print(f"start: load {os.getloadavg()}", file=sys.stderr)
    fp = {w: footprint(w) for w in ("numpy", "bd_uv", "bpy")}

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
            row = from_cache(cache, name, len(F), key) if is_peer(key) else None
            if row is None:
                row = measure_row(path, name, len(F), key, args.max_seconds, args.repeat)
            rows.append(row)
            print(f"{name} {len(F)}f {METHODS[key][0]}: {fmt_s(row.seconds)} s, max D "
                  f"{fmt(row.max_d)}, mean D {fmt(row.mean_d)}, flips {row.flips}, peak "
                  f"{fmt_mb(row.rss_peak_mb)} MiB {row.note} {row.error}", file=sys.stderr,
                  flush=True)
    print(f"end: load {os.getloadavg()}", file=sys.stderr)

    report = render(rows, skipped, methods, command, fp)
    print(report)
    if args.out:
        with open(args.out, "w", encoding="utf-8") as fh:
            fh.write(report)
    if args.json:
        save_json(args.json, rows, {"command": command, "footprints_mb": fp})
    return 0


if __name__ == "__main__":
    sys.exit(main())
