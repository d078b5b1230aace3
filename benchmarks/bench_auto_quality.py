"""``bound="auto"`` on the small disks the issue 21 passes compare search variants on: certified C,
area-weighted mean distortion, the bound search's iterations and the least CPU time of N calls.

    PYTHONPATH=<tree> python benchmarks/bench_auto_quality.py [--reps N] [--bound C] [NAME ...]

``--bound 5`` gives the same table for a given bound (the default method's C = 5) instead of
``auto``, with the island's max distortion beside the certified C and its flags.

NAME is ``grid8``, ``grid9``, ``grid12`` (height-field grids of 98, 112 and 242 faces), ``patch``
(face.obj's 223-face patch, as ``bench_no_waiting``'s), a shared mesh (``nefertiti.off``) or a
ring patch of one (``face.obj:800``: ``assets.patch``); by default the 18 disks of the earlier
passes' quality tables (benchmarks/results/issue21-small5-2026-11-27.md). Run it with PYTHONPATH
pointing at two trees to compare a change of the search with main: C, mean and iterations are
deterministic, so any difference in them is the change's. Prints one markdown row per disk.
``time.process_time`` (see ``bench_cpu_small``); meshes above 1000 faces are timed once.
"""
import argparse
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402
import trimesh  # noqa: E402

from assets import patch  # noqa: E402
from bench_no_waiting import MESHES  # noqa: E402

DISKS = ["grid8", "grid9", "grid12", "patch", "nefertiti.off", "three_peaks.off:500",
         "face.obj:800", "hemisphere.obj:400", "mushroom.off:500", "lion-head.off:600",
         "mannequin-devil.off:700", "face.obj:100", "lion-head.off:300", "three_peaks.off:250",
         "face.obj:1500", "three_peaks.off", "hemisphere.obj", "mushroom.off"]
# height fields z(x, y) over [0, 1] x [0, 0.8] (the surfaces of tests/core's grids)
GRIDS = {"grid8": (8, 8, lambda x, y: 0.3 * np.sin(5 * x) * np.cos(4 * y)),
         "grid9": (9, 8, lambda x, y: 0.3 * np.sin(4 * x) * np.cos(3 * y)),
         "grid12": (12, 12, lambda x, y: 0.4 * np.sin(3 * x) * np.sin(2 * y))}


def grid(nx, ny, z):
    """A triangulated height-field grid, (V, F): two triangles a cell."""
    xs, ys = np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 0.8, ny))
    V = np.stack([xs.ravel(), ys.ravel(), z(xs, ys).ravel()], 1)
    i = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = i[:-1, :-1].ravel(), i[:-1, 1:].ravel(), i[1:, :-1].ravel(), i[1:, 1:].ravel()
    return V, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])


def load(name, meshes=MESHES):
    """(V, F) of a disk named as in the module's docstring."""
    if name in GRIDS:
        return grid(*GRIDS[name])
    if name == "patch":
        path = patch(os.path.join(meshes, "face.obj"), 200)
    elif ":" in name:
        mesh, faces = name.rsplit(":", 1)
        path = patch(os.path.join(meshes, mesh), int(faces))
    else:
        path = os.path.join(meshes, name)
    m = trimesh.load(path, process=False, force="mesh")
    return np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)


def main(argv=None):
    import bd_uv

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("names", nargs="*", default=DISKS)
    ap.add_argument("--reps", type=int, default=5, help="calls per disk under 1000 faces")
    ap.add_argument("--meshes", default=MESHES)
    ap.add_argument("--bound", default="auto", help="auto (default) or a number")
    a = ap.parse_args(argv)
    bound = a.bound if a.bound == "auto" else float(a.bound)
    bd_uv.unwrap(*load("grid8"), bound=bound)     # first-call costs out of the first row
    print(f"| disk | faces | {a.bound} C | max | mean | iterations | CPU ms | flags |")
    print("|---|---|---|---|---|---|---|---|")
    for name in a.names:
        V, F = load(name, a.meshes)
        best = np.inf
        for _ in range(a.reps if len(F) < 1000 else 1):
            t = time.process_time()
            r = bd_uv.unwrap(V, F, bound=bound)
            best = min(best, time.process_time() - t)
        isl = r.islands[0]
        print(f"| {name} | {len(F)} | {isl.bound_certified:.5f} | {isl.max_distortion:.5f} | "
              f"{isl.mean_distortion:.5f} | {isl.iterations} | {1e3 * best:.1f} | "
              f"{' '.join(isl.flags)} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
