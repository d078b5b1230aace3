"""Issue 9's whole benchmark in one command: the seven disk meshes, then scale and many islands.

    python benchmarks/run_all.py OUT_DIR [--reuse-peers DIR] [--skip-scale] [--bd-cap SECONDS]

Writes ``OUT_DIR/main.md``, ``main.json`` (``bench_unwrap.py`` on nefertiti, three_peaks,
hemisphere, mushroom, lion-head, mannequin-devil and face from ``../shared/meshes``; every
method but BD-ARAP, which issue 9 does not judge: ``--with-arap`` adds it) and
``OUT_DIR/scale.md``, ``scale.json``, ``scale.png`` (``bench_scale.py``), and ``OUT_DIR/load.txt``
(``uptime`` before and after each part). With ``--reuse-peers DIR`` the Blender and libigl rows
come from ``DIR/main.json`` and ``DIR/scale.json`` (e.g. the committed baseline in
``benchmarks/results``), so only bd-uv runs: the peers do not depend on this repository's code.
Everything runs one process at a time under ``nice``.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
MESHES = next((p for p in (os.path.normpath(os.path.join(REPO, "..", "shared", "meshes")),
                           "/work/shared/meshes") if os.path.isdir(p)), "../shared/meshes")
DISKS = ["nefertiti.off", "three_peaks.off", "hemisphere.obj", "mushroom.off", "lion-head.off",
         "mannequin-devil.off", "face.obj"]


def _uptime(log, label):
    out = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    with open(log, "a", encoding="utf-8") as fh:
        fh.write(f"{label}: {out}\n")
    print(f"{label}: {out}", file=sys.stderr)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out_dir")
    ap.add_argument("--meshes", default=MESHES, help=f"the shared meshes (default {MESHES})")
    ap.add_argument("--reuse-peers", metavar="DIR",
                    help="folder with main.json and scale.json of an earlier run")
    ap.add_argument("--skip-scale", action="store_true", help="only the seven disk meshes")
    ap.add_argument("--skip-main", action="store_true", help="only scale and many islands")
    ap.add_argument("--with-arap", action="store_true",
                    help="also run BD-ARAP C=5 on the disk meshes (not among issue 9's criteria)")
    ap.add_argument("--bd-cap", type=float, default=1800.0,
                    help="cancel a bd-uv call after this many seconds (default 1800)")
    a = ap.parse_args(argv)
    os.makedirs(a.out_dir, exist_ok=True)
    log = os.path.join(a.out_dir, "load.txt")
    nice = ["nice", "-n", "10"] if os.name == "posix" else []
    py = [sys.executable]
    rc = 0
    if not a.skip_main:
        cmd = nice + py + [os.path.join(HERE, "bench_unwrap.py")]
        cmd += [os.path.join(a.meshes, m) for m in DISKS]
        cmd += ["--methods", "blender-abf", "blender-lscm", "blender-minstretch", "igl-slim",
                "bd-init-lscm", "bd-lscm-5", "bd-lscm-auto"] + (["bd-arap-5"] if a.with_arap
                                                                  else [])
        cmd += ["--out", os.path.join(a.out_dir, "main.md"),
                "--json", os.path.join(a.out_dir, "main.json"), "--max-seconds", str(a.bd_cap)]
        if a.reuse_peers:
            cmd += ["--reuse-peers", os.path.join(a.reuse_peers, "main.json")]
        _uptime(log, "main start")
        rc |= subprocess.call(cmd, cwd=REPO)
        _uptime(log, "main end")
    if not a.skip_scale:
        cmd = nice + py + [os.path.join(HERE, "bench_scale.py"), "--meshes", a.meshes,
                           "--out", os.path.join(a.out_dir, "scale.md"),
                           "--json", os.path.join(a.out_dir, "scale.json"),
                           "--cap", f"bd-lscm-5={a.bd_cap:g}"]
        if a.reuse_peers:
            cmd += ["--reuse-peers", os.path.join(a.reuse_peers, "scale.json")]
        _uptime(log, "scale start")
        rc |= subprocess.call(cmd, cwd=REPO)
        _uptime(log, "scale end")
    return rc


if __name__ == "__main__":
    sys.exit(main())
