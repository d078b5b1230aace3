"""CPU time of small disks in one process: Blender's ABF operator call against ``bd_uv.unwrap`` at
C = 5 and ``bound="auto"`` (issue 21 item 2), least of N interleaved repetitions.

    PYTHONPATH=<tree> python benchmarks/bench_cpu_small.py [N] [patch | NAME.off ...]

``time.process_time`` (every thread of the process) rather than wall time: on a machine shared by
many processes the wall time of a call of a few milliseconds says more about the scheduler than
about the code (a call shorter than a time slice is seldom preempted, a longer one is). Run it with
PYTHONPATH pointing at two trees, one after the other and interleaved, to compare code versions.
Prints one markdown row per mesh: faces, ABF ms, C=5 ms, auto ms, the two ratios, auto's C.
"""
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402
import trimesh  # noqa: E402

import peers  # noqa: E402
from assets import patch  # noqa: E402
from bench_no_waiting import MESHES  # noqa: E402
from methods import bd_warmup  # noqa: E402


def main(argv):
    import bd_uv

    n = int(argv[0]) if argv else 15
    names = argv[1:] or ["patch", "nefertiti.off"]
    bd_warmup()
    for name in names:
        path = (patch(os.path.join(MESHES, "face.obj"), 200) if name == "patch"
                else os.path.join(MESHES, name))
        m = trimesh.load(path, process=False, force="mesh")
        V, F = np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
        best = {"abf": np.inf, "c5": np.inf, "auto": np.inf}

        def abf(bpy):
            t = time.process_time()
            res = bpy.ops.uv.unwrap(method="ANGLE_BASED", margin=0.0)
            best["abf"] = min(best["abf"], time.process_time() - t)
            return res
        for _ in range(n):
            peers.blender_operator(V, F, abf)
            t = time.process_time()
            bd_uv.unwrap(V, F, bound=5.0)
            best["c5"] = min(best["c5"], time.process_time() - t)
            t = time.process_time()
            r = bd_uv.unwrap(V, F, bound="auto")
            best["auto"] = min(best["auto"], time.process_time() - t)
        c = r.islands[0].bound_certified
        print(f"| {name} | {len(F)} | {1e3 * best['abf']:.1f} | {1e3 * best['c5']:.1f} | "
              f"{1e3 * best['auto']:.1f} | {best['c5'] / best['abf']:.2f} | "
              f"{best['auto'] / best['abf']:.2f} | {c:.4f} |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
