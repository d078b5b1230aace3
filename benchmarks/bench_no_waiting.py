"""Issue 21's "done when" table in one run: bd-uv's times as ratios to its peers, per mesh and median.

    python benchmarks/bench_no_waiting.py [--rounds 2] [--disks NAME ...] [--patches NAME:FACES ...]
        [--closed NAME ...] [--subdivide NAME:TIMES ...] [--meshes DIR] [--out table.md]

Every (mesh, method) runs in its own fresh process (``isolate.py``: time and peak memory are the
method's own). Each method is first called once, untimed, on a small disk of its own (Blender's
operators on a two-face disk, bd-uv's C = 5 and ``auto`` each on a 50-face grid:
``methods.warmup``), so one-time process costs fall in no timed call, on either side. The
methods of one mesh run one after another, and the whole set ``--rounds`` times over,
interleaved; each time is the least of its rounds (a shared machine's load only ever adds time)
and each peak memory the largest. Printed:

- disks (the shared disks, and ``--patches``: ``assets.patch``, whole face rings of a shared mesh
  holding at least FACES faces; default a ~200-face patch of face.obj, the small case of item 2):
  Blender ABF, LSCM, Minimum Stretch, libigl SLIM, bd-uv C = 5 and ``bound="auto"``
  (``bd_uv.unwrap``: validation, islands, start, certification, overlap test; no packing, while
  Blender's operator packs), with ``auto / ABF`` and ``C=5 / ABF``, auto's certified C against
  the smallest max distortion of the four peers and of those whose map does not overlap itself
  (each peer's max is printed, marked "ov" where its map overlaps itself: ``isolate.map_shape``,
  bd_uv's own overlap test on the peer's UVs), bd-uv's pieces (UV islands) at auto and at C = 5,
  and auto's area-weighted mean against ABF's;
- closed meshes (the shared ones, and ``--subdivide``'d ones: ``trimesh.remesh.subdivide``, each
  face into four, ``TIMES`` times): bd-uv ``seams="auto"`` at C = 2, S = 2 (the result's own
  ``seconds``: no packing) against xatlas's whole ``parametrize`` (charts and packing), with the
  peak resident memory of each and bd-uv's charts and seam length;
- the medians, and PASS/FAIL per criterion of the issue.

Distortion is recomputed from each method's corner UVs (``measure.uv_stats``). It is a
measurement, not a test: nothing here asserts a time.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, HERE)

from assets import patch, subdivided  # noqa: E402
from isolate import run_isolated  # noqa: E402

MESHES = next((p for p in (os.path.normpath(os.path.join(REPO, "..", "shared", "meshes")),
                           "/work/shared/meshes") if os.path.isdir(p)), "../shared/meshes")
DISKS = ["nefertiti.off", "three_peaks.off", "hemisphere.obj", "mushroom.off", "lion-head.off",
         "mannequin-devil.off", "face.obj"]
CLOSED = ["cow.off", "dino.off", "fandisk.off", "camel.off", "armadillo.off", "horse.obj"]
PATCHES = ["face.obj:200"]
SUBDIVIDED = ["cow.off:2", "dino.off:3"]
DISK_METHODS = ["blender-abf", "blender-lscm", "blender-minstretch", "igl-slim", "bd-lscm-5",
                "bd-lscm-auto"]
PEERS = ["blender-abf", "blender-lscm", "blender-minstretch", "igl-slim"]
CLOSED_METHODS = ["xatlas", "bd-seams-auto"]


def measure(paths, keys, rounds, cap):
    """{(path, key): merged result}: least seconds over the rounds, largest peak memory."""
    out = {}
    for r in range(rounds):
        for path in paths:
            for key in keys:
                res = run_isolated(path, key, cap)
                print(f"  round {r + 1}: {os.path.basename(path)} {key}: "
                      + (f"{res['seconds']:.3f} s" if "seconds" in res else res.get("error", "?")),
                      file=sys.stderr, flush=True)
                old = out.get((path, key))
                if old is None or "seconds" not in old:
                    out[(path, key)] = res
                elif "seconds" in res:
                    best = res if res["seconds"] < old["seconds"] else old
                    best = dict(best, rss_peak_mb=max(res["rss_peak_mb"], old["rss_peak_mb"]))
                    out[(path, key)] = best
    return out


def _f(x, fmt=".3f"):
    return "-" if x is None else format(x, fmt)


PEER_SHORT = {"blender-abf": "ABF", "blender-lscm": "LSCM", "blender-minstretch": "MinS",
              "igl-slim": "SLIM"}


def _peer_cell(r):
    """A peer's max distortion, marked "ov" when its map overlaps itself (``isolate.map_shape``:
    a flip, or a boundary that is not simple) and "?" when that was not measured."""
    if r.get("max_d") is None:
        return "-"
    mark = {True: " ov", False: "", None: " ?"}[r.get("overlaps")]
    return f"{r['max_d']:.3g}{mark}"


def disk_table(paths, res):
    """Per disk: times and ratios, auto's certified C against the least peer max over all four
    peers and over the peers whose map does not overlap itself, each peer's max (marked where it
    overlaps), bd-uv's pieces at auto and C = 5, and auto's and C = 5's means against ABF's."""
    lines = ["| disk | faces | ABF s | C=5 s | auto s | C=5 / ABF | auto / ABF | auto C | "
             "min peer max D | min one-to-one peer max D | peers' max D (ABF, LSCM, MinS, SLIM; "
             "ov = overlaps itself) | pieces auto, C=5 | auto mean / ABF mean | "
             "C=5 mean / ABF mean |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    r5, ra, ok_c, ok_c1, ok_mean, ok_one = [], [], [], [], [], []
    for p in paths:
        abf, b5, au = res[(p, "blender-abf")], res[(p, "bd-lscm-5")], res[(p, "bd-lscm-auto")]
        if "seconds" not in abf or "seconds" not in b5 or "seconds" not in au:
            lines.append(f"| {os.path.basename(p)} | error: "
                         f"{abf.get('error') or b5.get('error') or au.get('error')} |")
            continue
        if au.get("mean_d") is None or abf.get("mean_d") is None:
            # a call that returned without a map (bd-uv refusing the input: its note says why)
            lines.append(f"| {os.path.basename(p)} | {abf['faces']} | no map: "
                         f"{au.get('note') if au.get('mean_d') is None else 'ABF'} |")
            ok_c.append(False)
            ok_c1.append(False)
            ok_mean.append(False)
            ok_one.append(False)
            continue
        x5, xa = b5["seconds"] / abf["seconds"], au["seconds"] / abf["seconds"]
        r5.append(x5)
        ra.append(xa)
        peers = [res.get((p, k), {}) for k in PEERS]
        peer_max = min(r["max_d"] for r in peers if r.get("max_d") is not None)
        clean = [r["max_d"] for r in peers if r.get("max_d") is not None
                 and r.get("overlaps") is False]
        clean_max = min(clean) if clean else None
        c = au.get("certified_c")
        ok_c.append(c is not None and c < peer_max)
        ok_c1.append(c is not None and (clean_max is None or c < clean_max))
        mean_ratio = au["mean_d"] / abf["mean_d"]
        mean5 = None if b5.get("mean_d") is None else b5["mean_d"] / abf["mean_d"]
        ok_mean.append(mean_ratio <= 1.05)
        pa, p5 = au.get("pieces"), b5.get("pieces")
        ok_one.append(pa == 1 and p5 == 1)
        lines.append(f"| {os.path.basename(p)} | {abf['faces']} | {abf['seconds']:.3f} | "
                     f"{b5['seconds']:.3f} | {au['seconds']:.3f} | {x5:.2f} | {xa:.2f} | "
                     f"{_f(c, '.4g')} | {peer_max:.4g} | {_f(clean_max, '.4g')} | "
                     f"{', '.join(_peer_cell(r) for r in peers)} | {_f(pa, 'd')}, {_f(p5, 'd')} | "
                     f"{mean_ratio:.4f} | "
                     f"{_f(mean5, '.4f')} |")
    if ra:
        lines.append(f"| median | | | | | {statistics.median(r5):.2f} | "
                     f"{statistics.median(ra):.2f} | | | | | | | |")
    small = [x for p, x in zip(paths, r5) if res[(p, "blender-abf")].get("faces", 0) < 1000]
    crit = [
        ("auto / ABF <= 1.0 at the median", bool(ra) and statistics.median(ra) <= 1.0),
        ("auto / ABF <= 2.0 on every disk", bool(ra) and max(ra) <= 2.0),
        ("C=5 / ABF <= 0.5 at the median", bool(r5) and statistics.median(r5) <= 0.5),
        ("C=5 / ABF <= 1.0 on every disk, one under 1k faces among them",
         bool(r5) and max(r5) <= 1.0 and bool(small)),
        ("auto's certified C < every peer's max distortion", bool(ok_c) and all(ok_c)),
        ("auto's certified C < the max distortion of every peer whose map does not overlap "
         "itself (overlapping peers' maps left out; a disk with none passes)",
         bool(ok_c1) and all(ok_c1)),
        ("auto's mean <= 1.05 x ABF's", bool(ok_mean) and all(ok_mean)),
        ("one piece per disk at auto and at C = 5", bool(ok_one) and all(ok_one)),
    ]
    return lines, crit


def closed_table(paths, res):
    lines = ["| closed mesh | faces | seams auto s | xatlas s | ratio | bd peak MB | xatlas peak MB "
             "| bd-uv charts, seams |", "|---|---|---|---|---|---|---|---|"]
    ratios, certified = [], []
    for p in paths:
        bd, xa = res[(p, "bd-seams-auto")], res[(p, "xatlas")]
        if "seconds" not in bd or "seconds" not in xa:
            lines.append(f"| {os.path.basename(p)} | error: {bd.get('error') or xa.get('error')} |")
            ratios.append(float("inf"))
            continue
        x = bd["seconds"] / xa["seconds"]
        ratios.append(x)
        certified.append(bd.get("certified_c") is not None and bd.get("flips") == 0)
        lines.append(f"| {os.path.basename(p)} | {bd['faces']} | {bd['seconds']:.3f} | "
                     f"{xa['seconds']:.3f} | {x:.2f} | {bd['rss_peak_mb']:.0f} | "
                     f"{xa['rss_peak_mb']:.0f} | {bd['note']} |")
    if ratios:
        lines.append(f"| median | | | | {statistics.median(ratios):.2f} | | | |")
    crit = [("seams auto / xatlas <= 1.0 on every closed mesh", bool(ratios) and max(ratios) <= 1.0),
            ("every seams-auto chart certified, 0 flips", bool(certified) and all(certified))]
    return lines, crit


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--meshes", default=MESHES)
    ap.add_argument("--disks", nargs="*", default=DISKS)
    ap.add_argument("--patches", nargs="*", default=PATCHES, metavar="NAME:FACES")
    ap.add_argument("--closed", nargs="*", default=CLOSED)
    ap.add_argument("--subdivide", nargs="*", default=SUBDIVIDED, metavar="NAME:TIMES")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--cap", type=float, default=900.0, help="cancel a bd-uv call after this")
    ap.add_argument("--out", help="also write the tables here (markdown)")
    a = ap.parse_args(argv)
    disks = [os.path.join(a.meshes, d) for d in a.disks]
    for spec in a.patches:
        name, faces = spec.rsplit(":", 1)
        disks.insert(0, patch(os.path.join(a.meshes, name), int(faces)))
    closed = [os.path.join(a.meshes, c) for c in a.closed]
    for spec in a.subdivide:
        name, times = spec.rsplit(":", 1)
        closed.append(subdivided(os.path.join(a.meshes, name), int(times)))
    load0 = os.getloadavg()
    res = measure(disks, DISK_METHODS, a.rounds, a.cap) if disks else {}
    res.update(measure(closed, CLOSED_METHODS, a.rounds, a.cap) if closed else {})
    out = [f"Command: `python benchmarks/bench_no_waiting.py {' '.join(argv or sys.argv[1:])}`",
           f"Load average (1, 5, 15 min) before {load0[0]:.1f} {load0[1]:.1f} {load0[2]:.1f}, "
           f"after {os.getloadavg()[0]:.1f}; least time of {a.rounds} interleaved rounds, "
           "largest peak.", ""]
    crit = []
    if disks:
        lines, c = disk_table(disks, res)
        out += lines + [""]
        crit += c
    if closed:
        lines, c = closed_table(closed, res)
        out += lines + [""]
        crit += c
    out += [f"- {'PASS' if ok else 'FAIL'}: {what}" for what, ok in crit]
    text = "\n".join(out)
    print(text)
    if a.out:
        with open(a.out, "w", encoding="utf-8") as fh:
            fh.write(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
