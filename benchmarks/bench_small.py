"""Fixed costs on small disks: bd-uv at C = 5 end to end against Blender's ABF, in one process.

    python benchmarks/bench_small.py [MESH ...] [--repeat 15]

Issue 21, item 2: a small disk (500 faces) unwraps at C = 5 in no more time than ABF on it. Per
mesh (default: a 512-face bumpy grid made here, and ``nefertiti.off`` from the shared meshes when
present), the two methods run alternately ``--repeat`` times in the same process after an untimed
warm-up; each line gives the minimum of each (the machine is shared: minima of interleaved runs
are the figures least disturbed by other load) and their ratio.

- bd-uv: ``bd_uv.unwrap(V, F, bound=5.0)`` then ``layout.stored_layout(..., pack=True,
  dtype=float32)``: validation, islands, start map, certification, the overlap certificate,
  packing into the unit square and the re-certification of the UVs as stored, i.e. what the
  command line and the operator do before writing.
- Blender ABF: ``bpy.ops.uv.unwrap(method="ANGLE_BASED", margin=0)`` on the whole mesh (it packs
  into the unit square too); only the operator call is timed (``peers.blender_unwrap``).

It is a measurement, not a test: nothing here asserts a time.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, HERE)
if REPO not in sys.path:
    sys.path.insert(1, REPO)

import peers  # noqa: E402

SHARED = os.path.normpath(os.path.join(REPO, "..", "shared", "meshes"))


def bumpy_grid(n=17):
    """An n x n vertex grid over the unit square, lifted by a smooth bump: 2 (n-1)^2 faces."""
    g = np.linspace(0.0, 1.0, n)
    x, y = np.meshgrid(g, g)
    V = np.c_[x.ravel(), y.ravel(), 0.3 * np.sin(3 * x.ravel()) * np.cos(2 * y.ravel())]
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1))
    a = (j * n + i).ravel()
    F = np.r_[np.c_[a, a + 1, a + n + 1], np.c_[a, a + n + 1, a + n]].astype(np.int64)
    return V, F


def bd_end_to_end(V, F):
    """bd-uv at C = 5 with packing and the stored (float32) certificate; returns seconds."""
    import bd_uv
    from bd_uv.layout import stored_layout

    t0 = time.perf_counter()
    res = bd_uv.unwrap(V, F, bound=5.0)
    lay = stored_layout(V, F, res, pack=True, dtype=np.float32)
    seconds = time.perf_counter() - t0
    if not all(c.certified for c in lay.certificates):
        raise RuntimeError("bd-uv did not certify the small disk")
    return seconds


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("meshes", nargs="*", help="OBJ/OFF/PLY disks (default: a 512-face grid and "
                                              "nefertiti.off when the shared meshes are there)")
    ap.add_argument("--repeat", type=int, default=15)
    a = ap.parse_args(argv)
    from bd_uv.meshio import load_mesh

    cases = [("bumpy grid 17x17", *bumpy_grid())]
    paths = a.meshes or [p for p in [os.path.join(SHARED, "nefertiti.off")] if os.path.exists(p)]
    for p in paths:
        mesh = load_mesh(p)
        cases.append((os.path.basename(p), mesh.V, mesh.F))
    print(f"load average {os.getloadavg()[0]:.1f}; minimum of {a.repeat} interleaved runs each\n")
    print("| mesh | faces | bd-uv C=5 end to end (ms) | Blender ABF (ms) | bd / ABF |")
    print("|---|---|---|---|---|")
    ratios = []
    for name, V, F in cases:
        bd_end_to_end(V, F)                       # warm-up: imports, first calls
        peers.blender_unwrap(V, F, "ANGLE_BASED")
        bd, abf = [], []
        for _ in range(a.repeat):
            bd.append(bd_end_to_end(V, F))
            abf.append(peers.blender_unwrap(V, F, "ANGLE_BASED")[1])
        r = min(bd) / min(abf)
        ratios.append(r)
        print(f"| {name} | {len(F)} | {1e3 * min(bd):.2f} | {1e3 * min(abf):.2f} | {r:.2f} |")
    print(f"\nmedian bd / ABF: {statistics.median(ratios):.2f}; "
          f"load average {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
