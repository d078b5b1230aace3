"""Clarabel vs the Schur-complement interior-point method on real bounded-distortion programs.

Usage::

    python3.11 benchmarks/bench_solvers.py [--bound 2] [--frames lscm|harmonic] MESH...

Per mesh (its first island) the program is built as the pipeline builds it: area-1 island, frames
from the LSCM map (the harmonic map when LSCM flips, or with ``--frames harmonic``), sigma = 1,
objective scaled to order 1, vertex 0 pinned. Printed per mesh and solver: outcome, iterations,
seconds, objective, and for the IPM the seconds spent in numeric factorisations per iteration and the
symbolic analysis; then a warm start from the IPM's own solution at a looser bound (C + 1), i.e. a
bisection step. One run, one process: timings on a shared machine are noisy.
"""
import argparse
import os
import sys
import time

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from bd_uv.energies import energy, jacobian_operators  # noqa: E402
from bd_uv.frames import frames_from_map, harmonic_map, lscm_map  # noqa: E402
from bd_uv.geometry import face_areas, local_coordinates  # noqa: E402
from bd_uv.mesh import islands  # noqa: E402
from bd_uv.meshio import load_mesh  # noqa: E402
from bd_uv.solvers import conic, ipm  # noqa: E402
from bd_uv.spaces import bounded_distortion_space  # noqa: E402


def program(V, F, C, frames="lscm"):
    """(P, q, A, b, cones, info) of F_C for the largest island of (V, F)."""
    isls = islands(V, F)
    isl = max(isls, key=lambda i: len(i.tris))
    Vi = V[isl.vertices]
    Vn = (Vi - Vi.mean(axis=0)) / np.sqrt(face_areas(Vi, isl.tris).sum())
    nv = len(Vi)
    Z = local_coordinates(Vn, isl.tris)
    ops = jacobian_operators(Z, isl.tris, nv)

    def alpha_beta(u):
        x = np.concatenate([u.real, u.imag])
        return ops.Are @ x + 1j * (ops.Aim @ x), ops.Bre @ x + 1j * (ops.Bim @ x)

    used = frames
    u = lscm_map(Z, isl.tris, nv, isl.loops) if frames == "lscm" else None
    if u is not None:
        a, b_ = alpha_beta(u)
        if not np.all(np.abs(a) > np.abs(b_)):
            u = None
    if u is None:
        u, used = harmonic_map(Z, isl.tris, nv, isl.loops), "harmonic"
    u = u - u[0]
    a, b_ = alpha_beta(u)
    D0 = float(np.max((np.abs(a) + np.abs(b_)) / (np.abs(a) - np.abs(b_))))
    w = frames_from_map(a)
    x = np.concatenate([u.real, u.imag])
    xs = x / np.real(w * a).min()
    P, q, _ = energy("lscm", ops, w)
    P = P / max(0.5 * xs @ (P @ xs), 1e-6)
    A, b, cones = bounded_distortion_space(ops, w, C, 1.0)
    free = np.setdiff1d(np.arange(2 * nv), [0, nv])
    info = dict(faces=len(isl.tris), vertices=nv, frames=used, D0=D0)
    return sp.csc_matrix(P)[free][:, free], q[free], A[:, free], b, cones, info


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--bound", type=float, default=2.0)
    ap.add_argument("--frames", default="lscm", choices=("lscm", "harmonic"))
    ap.add_argument("--backend", default="auto", choices=("auto", "qdldl", "splu"))
    ap.add_argument("--no-clarabel", action="store_true")
    args = ap.parse_args(argv)
    load = os.getloadavg()
    print(f"load average at start: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} "
          f"({os.cpu_count()} cores); C = {args.bound}; IPM backend {args.backend}")
    hdr = (f"{'mesh':<22}{'faces':>8} {'solver':<16}{'outcome':<11}{'iter':>5}{'seconds':>9}"
           f"{'objective':>15}{'fact/it':>9}{'symb':>7}")
    print(hdr)
    print("-" * len(hdr))
    for path in args.meshes:
        mesh = load_mesh(path)
        V, F = mesh.V, mesh.F
        name = os.path.basename(path)
        t = time.perf_counter()
        P, q, A, b, cones, info = program(np.asarray(V, float), np.asarray(F), args.bound,
                                          args.frames)
        build = time.perf_counter() - t
        print(f"{name:<22}{info['faces']:>8} (frames {info['frames']}, initial max distortion "
              f"{info['D0']:.3g}, program built in {build:.2f} s)")

        def row(label, sol, fact="", symb=""):
            print(f"{'':<22}{'':>8} {label:<16}{sol.outcome:<11}{sol.iterations:>5}"
                  f"{sol.seconds:>9.2f}{sol.objective:>15.8g}{fact:>9}{symb:>7}")

        if not args.no_clarabel:
            row("clarabel", conic.solve_conic(P, q, A, b, cones))
        t = time.perf_counter()
        solver = ipm.SchurIPM(P, A, cones, backend=args.backend)
        symb = time.perf_counter() - t
        sol = solver.solve(P, q, A, b, cones)
        f = solver.factor
        row(f"ipm ({f.backend})", sol, f"{f.seconds / max(f.count, 1):.3f}", f"{symb:.2f}")
        if sol.outcome == "solved":
            # a bisection step: C + 1 from the solution at C (strictly feasible there)
            P2, q2, A2, b2, cones2, _ = program(np.asarray(V, float), np.asarray(F),
                                                args.bound + 1.0, args.frames)
            if not args.no_clarabel:
                row("clarabel C+1", conic.solve_conic(P2, q2, A2, b2, cones2))
            f.seconds, f.count = 0.0, 0
            row("ipm C+1 cold", solver.solve(P2, q2, A2, b2, cones2),
                f"{f.seconds / max(f.count, 1):.3f}")
            f.seconds, f.count = 0.0, 0
            row("ipm C+1 warm", solver.solve(P2, q2, A2, b2, cones2, x0=sol.x),
                f"{f.seconds / max(f.count, 1):.3f}")


if __name__ == "__main__":
    main()
