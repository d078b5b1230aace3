"""Scale and many-islands benchmark: time and peak memory vs faces, bd-uv vs Blender's unwrappers.

    python benchmarks/bench_scale.py [--sections scale islands] [--out scale.md]
        [--json scale.json] [--reuse-peers scale.json] [--cap blender-abf=1800] [--max-faces N]

Scale section: face.obj as whole-ring patches of >= 10k and 25k faces (``assets.patch``), whole
(51,712), subdivided once and twice (``trimesh.remesh.subdivide``: 206,848 and 827,392); and
mannequin-devil.off whole (25,888) and subdivided once and twice (103,552 and 414,208). On each:
bd-uv BD-LSCM C = 5 (defaults) and Blender ABF, LSCM (Conformal) and Minimum Stretch through bpy,
each in its own process (``isolate.py``): seconds, peak resident memory, max / mean distortion,
flips. Then issue 9's two named cases with their ratios to ABF (face.obj x2: <= 1.0x ABF time and
<= 8 GiB; mannequin-devil x2: <= 2.0x ABF time and <= 8 GiB), and a log-log PNG of seconds and
peak memory vs faces written next to ``--out`` (same name, ``.png``).

Many-islands section: ``assets.many_islands(1000, seed=0)`` (1000 separate bumpy patches, 13,852
faces), bd-uv C = 5 vs Blender ABF (whose operator time includes packing the 1000 islands into the
unit square; bd-uv's includes its own island layout), ratio <= 2x.

Per-method caps: ``--cap KEY=SECONDS`` (bd-uv is cancelled at the cap; any process is killed 120 s
after it). Blender results do not depend on this repository: ``--json`` saves every row and
``--reuse-peers`` reuses them, so the lead's re-run only runs bd-uv.
"""
from __future__ import annotations

import argparse
import os
import shlex
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
REPO = os.path.dirname(HERE)
if REPO not in sys.path:
    sys.path.insert(1, REPO)

import assets  # noqa: E402
from bench_unwrap import (cached_warning, fmt, fmt_mb, fmt_s, from_cache,  # noqa: E402
                          load_cache, measure_row, run_header, save_json)
from isolate import footprint  # noqa: E402
from methods import METHODS, is_peer  # noqa: E402

MESHES = "/work/shared/meshes" if os.path.isdir("/work/shared/meshes") else os.path.join(
    REPO, "..", "shared", "meshes")
SCALE_METHODS = ["blender-abf", "blender-lscm", "blender-minstretch", "bd-lscm-5"]
ISLAND_METHODS = ["blender-abf", "bd-lscm-5"]
GIB = 1024.0
NAMED = {  # asset name -> (label, max time ratio to ABF, max peak MiB)
    "face-sub2.obj": ("face.obj subdivided twice", 1.0, 8 * GIB),
    "mannequin-devil-sub2.obj": ("mannequin-devil subdivided twice (bound active)", 2.0, 8 * GIB),
}


def scale_assets(meshes_dir, out_dir, max_faces):
    """(family, path) of the scale section's meshes, smallest first (so a run stopped early
    still has the small end of every curve)."""
    face = os.path.join(meshes_dir, "face.obj")
    devil = os.path.join(meshes_dir, "mannequin-devil.off")
    plan = [("face", lambda: assets.patch(face, 10000, out_dir), 10206),
            ("face", lambda: assets.patch(face, 25000, out_dir), 25234),
            ("face", lambda: face, 51712),
            ("face", lambda: assets.subdivided(face, 1, out_dir), 206848),
            ("face", lambda: assets.subdivided(face, 2, out_dir), 827392),
            ("mannequin-devil", lambda: devil, 25888),
            ("mannequin-devil", lambda: assets.subdivided(devil, 1, out_dir), 103552),
            ("mannequin-devil", lambda: assets.subdivided(devil, 2, out_dir), 414208)]
    plan = sorted((p for p in plan if not max_faces or p[2] <= max_faces), key=lambda p: p[2])
    return [(fam, make()) for fam, make, nf in plan]


def table(rows, families):
    """Markdown table of the rows, with time and peak ratios to ABF on the same mesh."""
    out = ["| mesh | faces | method | seconds | time / ABF | peak MiB | peak / ABF peak | "
           "peak - base | max D | mean D | flips | load | notes |",
           "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---|"]
    abf = {r.mesh: r for r in rows if r.key == "blender-abf" and not r.error}
    lscm_of = {r.mesh: r for r in rows if r.key == "blender-lscm" and not r.error}
    for r in rows:
        a = abf.get(r.mesh)
        tr = r.seconds / a.seconds if a and np.isfinite(r.seconds) else None
        mr = r.rss_peak_mb / a.rss_peak_mb if a and r.rss_peak_mb and a.rss_peak_mb else None
        added = r.rss_peak_mb - r.rss_base_mb if r.rss_peak_mb is not None else None
        notes = ([f"ERROR {r.error}"] if r.error else []) + ([r.note] if r.note else [])
        if r.cached:
            notes.append("cached peer result")
        lscm = lscm_of.get(r.mesh)
        if (r.key == "blender-abf" and lscm is not None and not r.error
                and (r.max_d, r.mean_d, r.flips) == (lscm.max_d, lscm.mean_d, lscm.flips)):
            notes.append("same distortion as Blender LSCM to the last digit: Blender falls back "
                         "to LSCM when ABF does not converge")
        out.append(f"| {r.mesh} | {r.faces} | {METHODS[r.key][0]} | {fmt_s(r.seconds)} | "
                   f"{'-' if tr is None else f'{tr:.2f}'} | {fmt_mb(r.rss_peak_mb)} | "
                   f"{'-' if mr is None else f'{mr:.2f}'} | {fmt_mb(added)} | {fmt(r.max_d)} | "
                   f"{fmt(r.mean_d)} | {'-' if r.flips is None else r.flips} | {r.load} | "
                   + "; ".join(notes).replace("|", "/") + " |")
    return out


def named_checks(rows, islands_name=None):
    """Issue 9's scale and many-islands criteria as PASS/FAIL lines."""
    by = {(r.mesh, r.key): r for r in rows}
    out = []
    cases = dict(NAMED)
    if islands_name:
        cases[islands_name] = ("1000-island asset", 2.0, None)
    for mesh, (label, tmax, mmax) in cases.items():
        a, b = by.get((mesh, "blender-abf")), by.get((mesh, "bd-lscm-5"))
        if a is None and b is None:
            continue
        if a is None or b is None or a.error or b.error:
            why = "; ".join(f"{k}: {r.error}" for k, r in (("ABF", a), ("bd-uv", b))
                            if r is not None and r.error) or "a result is missing"
            out.append(f"- **FAIL** {label} ({mesh}): {why}")
            continue
        ratio = b.seconds / a.seconds
        ok_t = ratio <= tmax
        line = (f"- **{'PASS' if ok_t else 'FAIL'}** {label} ({mesh}, {b.faces} faces): bd-uv "
                f"C=5 {fmt_s(b.seconds)} s vs ABF {fmt_s(a.seconds)} s = {ratio:.2f}x "
                f"(<= {tmax:g}x)")
        if mmax is not None:
            ok_m = b.rss_peak_mb is not None and b.rss_peak_mb <= mmax
            line += (f"; **{'PASS' if ok_m else 'FAIL'}** peak {fmt_mb(b.rss_peak_mb)} MiB "
                     f"(<= {mmax:.0f}; ABF {fmt_mb(a.rss_peak_mb)})")
        line += (f"; bd-uv {b.flips} flips, max D {fmt(b.max_d)}, mean D {fmt(b.mean_d)}; ABF "
                 f"max D {fmt(a.max_d)}, mean D {fmt(a.mean_d)}")
        out.append(line)
    return out


def plot(rows, families, png, footprints=None):
    """Log-log seconds and peak MiB vs faces, one line per (family, method); dotted horizontal
    lines mark the import-only footprints of bpy and bd_uv."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 5))
    styles = {"face": "-", "mannequin-devil": "--"}
    colors = {"bd-lscm-5": "C3", "blender-abf": "C0", "blender-lscm": "C2",
              "blender-minstretch": "C1"}
    for fam in dict.fromkeys(families.values()):
        for key in SCALE_METHODS:
            pts = sorted((r.faces, r.seconds, r.rss_peak_mb) for r in rows
                         if r.key == key and families.get(r.mesh) == fam and not r.error
                         and np.isfinite(r.seconds))
            if not pts:
                continue
            f, s, m = np.array(pts, dtype=float).T
            lab = f"{METHODS[key][0]} ({fam})"
            axes[0].loglog(f, s, styles.get(fam, ":"), marker="o", color=colors[key], label=lab)
            axes[1].loglog(f, m, styles.get(fam, ":"), marker="o", color=colors[key], label=lab)
    for what, col in (("bpy", "C0"), ("bd_uv", "C3")):
        if footprints and footprints.get(what):
            axes[1].axhline(footprints[what], color=col, ls=":", lw=1,
                            label=f"import {what} only")
    axes[1].legend(fontsize=7)
    axes[0].set(xlabel="faces", ylabel="seconds", title="time vs faces")
    axes[1].set(xlabel="faces", ylabel="peak resident MiB (own process)",
                title="peak memory vs faces")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle(f"bd-uv vs Blender, scale run {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}"
                 " (solid: face.obj family, dashed: mannequin-devil)", fontsize=9)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)


def parse_caps(items, default):
    caps = {k: default for k in METHODS}
    for it in items or []:
        k, _, v = it.partition("=")
        if k not in METHODS:
            raise SystemExit(f"--cap: unknown method {k!r}")
        caps[k] = float(v)
    return caps


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sections", nargs="+", choices=["scale", "islands"],
                    default=["scale", "islands"])
    ap.add_argument("--meshes", default=MESHES, help="folder with face.obj and mannequin-devil.off")
    ap.add_argument("--asset-dir", default=assets.DEFAULT_DIR,
                    help="where generated OBJ files are written and reused")
    ap.add_argument("--methods", nargs="+", choices=SCALE_METHODS, default=SCALE_METHODS)
    ap.add_argument("--max-faces", type=int, default=0, help="skip larger scale meshes")
    ap.add_argument("--max-seconds", type=float, default=1800.0,
                    help="default per-method cap in seconds (default 1800)")
    ap.add_argument("--cap", action="append", metavar="KEY=SECONDS",
                    help="per-method cap, e.g. --cap bd-lscm-5=900 (repeatable)")
    ap.add_argument("--method-max-faces", action="append", metavar="KEY=FACES",
                    help="skip one method above this many faces, e.g. blender-minstretch=210000 "
                         "(repeatable)")
    ap.add_argument("--out", default="scale.md", help="markdown report; the PNG goes next to it")
    ap.add_argument("--json", help="write every row to this JSON file")
    ap.add_argument("--reuse-peers", metavar="JSON", help="reuse Blender rows from this file")
    ap.add_argument("--render-only", metavar="JSON",
                    help="run nothing: write the report and plot from this --json file (e.g. of a "
                         "run stopped early)")
    args = ap.parse_args(argv)
    command = "python " + " ".join(shlex.quote(a) for a in
                                   [os.path.relpath(sys.argv[0], REPO)] + sys.argv[1:])
    caps = parse_caps(args.cap, args.max_seconds)
    cache = load_cache(args.reuse_peers) if args.reuse_peers else {}
    method_max = {k: int(v) for k, _, v in (it.partition("=")
                                            for it in args.method_max_faces or [])}

    if args.render_only:
        return render_only(args)
    load_start = os.getloadavg()
    print(f"start: load {load_start}", file=sys.stderr)
    fp = {w: footprint(w) for w in ("numpy", "bd_uv", "bpy")}

    rows, families, islands_name = [], {}, None
    plan = []
    if "islands" in args.sections:       # first: small, and one of the criteria
        path = assets.many_islands(1000, 0, args.asset_dir)
        islands_name = os.path.basename(path)
        plan.append(("islands", path, [k for k in ISLAND_METHODS if k in args.methods]))
    if "scale" in args.sections:
        for fam, path in scale_assets(args.meshes, args.asset_dir, args.max_faces):
            plan.append((fam, path, [k for k in SCALE_METHODS if k in args.methods]))
    for fam, path, keys in plan:
        name = os.path.basename(path)
        families[name] = fam
        faces = sum(1 for ln in open(path, "rb") if ln.startswith(b"f ")) if path.endswith(
            ".obj") else None
        if faces is None:
            from measure import load_mesh_by_index
            faces = len(load_mesh_by_index(path)[1])
        for key in keys:
            if faces > method_max.get(key, float("inf")):
                continue
            row = from_cache(cache, name, faces, key) if is_peer(key) else None
            if row is None:
                row = measure_row(path, name, faces, key, caps[key], 1, caps[key] + 120.0)
            rows.append(row)
            print(f"{name} {faces}f {METHODS[key][0]}: {fmt_s(row.seconds)} s, peak "
                  f"{fmt_mb(row.rss_peak_mb)} MiB, max D {fmt(row.max_d)}, mean D "
                  f"{fmt(row.mean_d)}, flips {row.flips} {row.note} {row.error}",
                  file=sys.stderr, flush=True)
            if args.json:
                save_json(args.json, rows, meta(command, fp, families, islands_name, load_start,
                                                None, caps))
    load_end = os.getloadavg()
    print(f"end: load {load_end}", file=sys.stderr)
    info = meta(command, fp, families, islands_name, load_start, load_end, caps)
    if args.json:
        save_json(args.json, rows, info)
    return write_report(rows, info, args.out)


def meta(command, fp, families, islands_name, load_start, load_end, caps):
    """What the report needs besides the rows (saved in the JSON file too)."""
    return {"command": command, "footprints_mb": fp, "families": families,
            "islands_name": islands_name, "load_start": load_start, "load_end": load_end,
            "caps": {k: caps[k] for k in SCALE_METHODS}}


def render_only(args):
    """Report and plot from a saved --json file."""
    import json

    with open(args.render_only, encoding="utf-8") as fh:
        info = json.load(fh)
    rows = sorted(load_cache(args.render_only).values(), key=lambda r: r.faces)
    order = {r.mesh: i for i, r in enumerate(rows)}
    rows.sort(key=lambda r: (order[r.mesh], SCALE_METHODS.index(r.key)
                             if r.key in SCALE_METHODS else 99))
    for r in rows:
        for f in ("seconds", "max_d", "mean_d"):
            if getattr(r, f) is None:
                setattr(r, f, float("nan"))
    return write_report(rows, info, args.out)


def write_report(rows, info, out_path):
    """The markdown report (printed and written to ``out_path``) and the PNG beside it."""
    families, islands_name = info["families"], info["islands_name"]
    out = run_header(info["command"], info["footprints_mb"])
    ls, le = info.get("load_start"), info.get("load_end")
    out.append("")
    out.append("Load average (1, 5, 15 min) at start "
               f"{tuple(round(x, 1) for x in ls) if ls else '-'}, at end "
               f"{tuple(round(x, 1) for x in le) if le else '- (run stopped early)'}. Caps: "
               + ", ".join(f"{k} {v:g} s" for k, v in info["caps"].items()) + ".")
    out += [""] + cached_warning(rows)
    scale_rows = [r for r in rows if families.get(r.mesh) != "islands"]
    png = os.path.splitext(out_path)[0] + ".png"
    if scale_rows:
        out += ["", "### Scale: time and peak memory vs faces", ""]
        out += table(scale_rows, families)
        plot(scale_rows, families, png, info.get("footprints_mb"))
        out += ["", f"Plot: `{os.path.basename(png)}` (log-log).", ""]
    isl_rows = [r for r in rows if families.get(r.mesh) == "islands"]
    if isl_rows:
        out += ["", "### Many islands (1000 separate bumpy patches)", ""]
        out += table(isl_rows, families)
    out += ["", "Issue 9's scale criteria:", ""] + named_checks(rows, islands_name)
    report = "\n".join(out) + "\n"
    print(report)
    with open(out_path, "w", encoding="utf-8") as fh:
        fh.write(report)
    return 0


if __name__ == "__main__":
    sys.exit(main())
