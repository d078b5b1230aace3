"""Projection iterations (bd_uv.solvers.projection) on real disk meshes: iterations, time,
certification and distortion, from the LSCM map (flips and all) and from the harmonic map.

Every figure is recomputed from the resulting corner UVs by ``measure.uv_stats`` (an independent
SVD of each face's map). Prints markdown tables; nothing is asserted.

    python3.11 benchmarks/bench_projection.py                    # the 7 disk meshes, C = 5 and 2
    python3.11 benchmarks/bench_projection.py --backends         # factorisation back-ends
    python3.11 benchmarks/bench_projection.py --big face.obj     # subdivided twice: time, memory
    python3.11 benchmarks/bench_projection.py --islands 1000 --bounds 1.5   # many islands at once
"""
from __future__ import annotations

import argparse
import os
import resource
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)

from measure import corner_uv_from_vertex_uv, load_mesh_by_index, uv_stats  # noqa: E402

from bd_uv.energies import jacobian_operators  # noqa: E402
from bd_uv.frames import harmonic_map, lscm_map  # noqa: E402
from bd_uv.geometry import face_areas, local_coordinates  # noqa: E402
from bd_uv.mesh import islands  # noqa: E402
from bd_uv.solvers.flip_free import flip_free_map  # noqa: E402
from bd_uv.solvers.factor import factor_spd  # noqa: E402
from bd_uv.solvers.projection import ProjectionSolver  # noqa: E402

MESHES = "/work/shared/meshes"
DISKS = ["nefertiti.off", "three_peaks.off", "hemisphere.obj", "mushroom.off", "lion-head.off",
         "mannequin-devil.off", "face.obj"]
# Blender 5.0.1 Angle Based unwrap, area-weighted mean distortion (issue 9's table).
ABF_MEAN = {"lion-head.off": 1.071, "face.obj": 1.029, "mannequin-devil.off": 1.074,
            "three_peaks.off": 1.353}


def island_problem(V, F):
    """The one island of a disk mesh, normalised like the pipeline does (centre, unit area)."""
    isl = islands(V, F)
    if len(isl) != 1 or isl[0].error is not None:
        raise SystemExit("expected one valid disk island")
    isl = isl[0]
    Vi = V[isl.vertices]
    Vn = (Vi - Vi.mean(axis=0)) / np.sqrt(face_areas(Vi, isl.tris).sum())
    return Vn, isl, local_coordinates(Vn, isl.tris)


def stats(Vn, tris, u):
    return uv_stats(Vn, tris, corner_uv_from_vertex_uv(tris, np.stack([u.real, u.imag], 1)))


def fmt(x):
    return "inf" if not np.isfinite(x) else f"{x:.4g}"


def run_meshes(names, bounds, margin):
    print(f"margin {margin}; seconds = setup + factorisation + iterations, wall (process CPU); "
          "one boundary vertex fixed")
    print()
    print("| mesh | faces | start | start max / mean (flips) | C | iters | s (CPU s) | certified | "
          "max (flips) | mean | mean / start | mean / ABF |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in names:
        V, F = load_mesh_by_index(os.path.join(MESHES, name))
        Vn, isl, Z = island_problem(V, F)
        nv = len(Vn)
        t = time.perf_counter()
        ul = lscm_map(Z, isl.tris, nv, isl.loops)
        t_lscm = time.perf_counter() - t
        uh = harmonic_map(Z, isl.tris, nv, isl.loops)
        uh = uh * np.sqrt(stats_area(Z, isl.tris, ul) / stats_area(Z, isl.tris, uh))
        ops = jacobian_operators(Z, isl.tris, nv)
        for start, u0 in (("lscm", ul), ("harmonic", uh)):
            s0 = stats(Vn, isl.tris, u0)
            for C in bounds:
                t, c = time.perf_counter(), time.process_time()
                S = ProjectionSolver(ops, nv, [isl.loops[0][0]], tris=isl.tris)
                r = S.project(u0, C, margin=margin)
                dt, dc = time.perf_counter() - t, time.process_time() - c
                s = stats(Vn, isl.tris, r.u)
                ok = s.flips == 0 and s.max_distortion <= C * (1 + 1e-6)
                abf = ABF_MEAN.get(name)
                print(f"| {name} | {len(isl.tris)} | {start} | {fmt(s0.max_distortion)} / "
                      f"{s0.mean_distortion:.4f} ({s0.flips}) | {C:g} | {r.iterations} | "
                      f"{dt:.3f} ({dc:.3f}) | {'yes' if ok else 'no'} | "
                      f"{fmt(s.max_distortion)} ({s.flips}) | "
                      f"{s.mean_distortion:.4f} | {s.mean_distortion / s0.mean_distortion:.4f} | "
                      f"{'' if abf is None else f'{s.mean_distortion / abf:.4f}'} |")
        print(f"<!-- {name}: LSCM {t_lscm:.3f} s -->")
    sys.stdout.flush()


def stats_area(Z, tris, u):
    """Total unsigned UV area."""
    uv = u[tris]
    return float(np.sum(np.abs(((uv[:, 1] - uv[:, 0]).conj() * (uv[:, 2] - uv[:, 0])).imag)) / 2)


def run_backends(name):
    V, F = load_mesh_by_index(os.path.join(MESHES, name))
    Vn, isl, Z = island_problem(V, F)
    nv = len(Vn)
    ops = jacobian_operators(Z, isl.tris, nv)
    S = ProjectionSolver(ops, nv, [isl.loops[0][0]], tris=isl.tris, backend="splu")
    M = S.global_matrix()
    B = np.random.default_rng(0).normal(size=(M.shape[0], 4))
    print(f"{name}: {M.shape[0]} unknowns, {M.nnz} non-zeros")
    print("| backend | factorise s | back-solve 4 columns s | residual |")
    print("|---|---|---|---|")
    for backend in ("cholespy", "qdldl", "splu"):
        try:
            t = time.perf_counter()
            solve, _ = factor_spd(M, backend)
            tf = time.perf_counter() - t
        except ImportError:
            print(f"| {backend} | not installed | | |")
            continue
        solve(B)
        t = time.perf_counter()
        for _ in range(10):
            X = solve(B)
        ts = (time.perf_counter() - t) / 10
        res = np.abs(M @ X - B).max() / np.abs(B).max()
        print(f"| {backend} | {tf:.3f} | {ts:.4f} | {res:.1e} |")


def lscm_factored(Z, tris, nv, loops, backend="auto"):
    """The LSCM map of ``frames.lscm_map`` (same two pins), solved with ``factor_spd`` instead of
    SuperLU on the 2nv system: what the LSCM start would cost with the projection's factoriser."""
    import scipy.sparse as sp

    from bd_uv.frames import _far_pair

    ops = jacobian_operators(Z, tris, nv)
    W = sp.diags_array(ops.area)
    Q = (ops.Bre.T @ W @ ops.Bre + ops.Bim.T @ W @ ops.Bim).tocsr()
    idx, val = _far_pair(Z, tris, nv, loops[0])
    fixed = np.concatenate([idx, idx + nv])
    xF = np.concatenate([val.real, val.imag])
    free = np.setdiff1d(np.arange(2 * nv), fixed)
    Qf = Q[free]
    solve, _ = factor_spd(sp.csc_array(Qf[:, free]), backend)
    x = np.empty(2 * nv)
    x[fixed] = xF
    x[free] = solve(-(Qf[:, fixed] @ xF))
    return x[:nv] + 1j * x[nv:]


def run_big(name, subdivisions, C, margin, factored_lscm):
    import trimesh

    V, F = load_mesh_by_index(os.path.join(MESHES, name))
    for _ in range(subdivisions):
        V, F = trimesh.remesh.subdivide(V, F)
    V, F = np.asarray(V, np.float64), np.asarray(F, np.int64)
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    t0, c0 = time.perf_counter(), time.process_time()
    Vn, isl, Z = island_problem(V, F)
    nv = len(Vn)
    t1, c1 = time.perf_counter(), time.process_time()
    ul = (lscm_factored(Z, isl.tris, nv, isl.loops) if factored_lscm
          else lscm_map(Z, isl.tris, nv, isl.loops))
    t2, c2 = time.perf_counter(), time.process_time()
    rss_lscm = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    u, info = flip_free_map(Z, isl.tris, nv, isl.loops, ul, C, margin=margin)
    t3, c3 = time.perf_counter(), time.process_time()
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    s0 = stats(Vn, isl.tris, ul)
    s = stats(Vn, isl.tris, u) if u is not None else None
    print(f"{name} subdivided {subdivisions}x: {len(F)} faces, {nv} vertices")
    how = "factor_spd" if factored_lscm else "frames.lscm_map"
    print("  wall s (process CPU s):")
    print(f"  islands + local coordinates {t1 - t0:.2f} ({c1 - c0:.2f}); LSCM ({how}) "
          f"{t2 - t1:.2f} ({c2 - c1:.2f}) "
          f"(max {fmt(s0.max_distortion)}, mean {s0.mean_distortion:.4f}, flips {s0.flips})")
    print(f"  projection to C = {C:g}: start {info['start']}, {info['iterations']} iterations, "
          f"{t3 - t2:.2f} ({c3 - c2:.2f}), factorisation {info['factor_seconds']:.2f} s wall")
    if s is not None:
        print(f"  result max {fmt(s.max_distortion)}, mean {s.mean_distortion:.4f}, "
              f"flips {s.flips}")
    print(f"  peak RSS {rss:.0f} MB (after loading and subdividing: {rss0:.0f} MB, after LSCM: "
          f"{rss_lscm:.0f} MB)")


def many_islands(n, nx=4, seed=0):
    """n small bumpy patches (nx x nx vertex grids, random heights), as one vertex/face array."""
    rng = np.random.default_rng(seed)
    xs, ys = np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 1, nx))
    i = np.arange(nx * nx).reshape(nx, nx)
    a, b, c, d = i[:-1, :-1].ravel(), i[:-1, 1:].ravel(), i[1:, :-1].ravel(), i[1:, 1:].ravel()
    f = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    z = rng.normal(scale=0.1, size=(n, nx * nx))
    V = np.stack([np.broadcast_to(xs.ravel(), (n, nx * nx)),
                  np.broadcast_to(ys.ravel(), (n, nx * nx)), z], -1)
    V = (V + 2.0 * np.arange(n)[:, None, None] * np.array([1.0, 0, 0])).reshape(-1, 3)
    F = (f[None] + (nx * nx) * np.arange(n)[:, None, None]).reshape(-1, 3)
    return V, F, f, nx * nx


def run_islands(n, C, margin, nx):
    """LSCM of every island and projection to C, all islands in one system each."""
    V, F, f, per = many_islands(n, nx)
    t0 = time.perf_counter()
    Z = local_coordinates(V, F)
    # LSCM of the union in one solve: two boundary corners of each patch pinned at their 3D
    # distance apart (any two pins give the island's LSCM map up to a similarity).
    base = np.arange(n) * per
    p0, p1 = base, base + per - 1  # opposite corners of each grid
    dist = np.linalg.norm(V[p1] - V[p0], axis=1)
    idx = np.concatenate([p0, p1])
    val = np.concatenate([np.zeros(n), dist]).astype(np.complex128) + 3.0j * np.concatenate(
        [np.arange(n), np.arange(n)])
    ul = lscm_map(Z, F, len(V), [np.array([0])], pins=(idx, val))
    t1 = time.perf_counter()
    ops = jacobian_operators(Z, F, len(V))
    S = ProjectionSolver(ops, len(V), p0, tris=F)
    r = S.project(ul, C, margin=margin)
    t2 = time.perf_counter()
    s0 = stats(V, F, ul)
    s = stats(V, F, r.u)
    bad0 = np.bincount(np.repeat(np.arange(n), len(f)), weights=~(s0.distortion <= C),
                       minlength=n) > 0
    print(f"{n} islands, {len(F)} faces: LSCM of all {t1 - t0:.3f} s (max {fmt(s0.max_distortion)}"
          f", flips {s0.flips}, islands above C = {C:g}: {int(bad0.sum())})")
    print(f"  projection: {r.iterations} iterations, {t2 - t1:.3f} s (setup "
          f"{S.setup_seconds:.3f} s, factorisation {S.factor_seconds:.3f} s), certified islands "
          f"{int(r.converged.sum())}/{n}; max {fmt(s.max_distortion)}, flips {s.flips}, "
          f"mean {s0.mean_distortion:.4f} -> {s.mean_distortion:.4f}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("meshes", nargs="*", default=DISKS)
    ap.add_argument("--bounds", type=float, nargs="+", default=[5.0, 2.0])
    ap.add_argument("--margin", type=float, default=0.9)
    ap.add_argument("--backends", action="store_true", help="compare factorisations on face.obj")
    ap.add_argument("--big", metavar="MESH", help="subdivide MESH and time LSCM + flip_free_map")
    ap.add_argument("--subdivisions", type=int, default=2)
    ap.add_argument("--factored-lscm", action="store_true",
                    help="with --big: LSCM solved by factor_spd instead of frames.lscm_map")
    ap.add_argument("--islands", type=int, metavar="N", help="N small bumpy patches at once")
    ap.add_argument("--patch-grid", type=int, default=3,
                    help="with --islands: vertices per side of a patch (3: 8 faces, as issue 9)")
    a = ap.parse_args(argv)
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    if a.backends:
        run_backends("face.obj")
    elif a.islands:
        run_islands(a.islands, a.bounds[0], a.margin, a.patch_grid)
    elif a.big:
        run_big(a.big, a.subdivisions, a.bounds[0], a.margin, a.factored_lscm)
    else:
        run_meshes(a.meshes, a.bounds, a.margin)
    return 0


if __name__ == "__main__":
    sys.exit(main())
