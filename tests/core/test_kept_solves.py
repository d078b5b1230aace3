"""Work kept or made without scipy's matrices, checked against the scipy arithmetic it replaces,
bit for bit (issue 21, items 1-2):

- ``ordered_ldl.Factor(keep=True).refill``: another system of the same triplets' places
  factorised without the conversions and the elimination tree; ``disk_conformal.conformal`` in
  the disk's vertex order with ``rebuilt`` (``capped.unfold``'s solves after its first);
- ``frames._loop_lengths`` without the sparse edge-length lookup;
- ``energy_within.lowest_energy``'s lift and right-hand side as bare compressed rows;
- ``IslandProblem``'s alpha, beta and face distortion by the compiled products straight.
Each is compared with the scipy products or the new factorisation it stands for, recomputed here.
"""
import numpy as np
import pytest
import scipy.sparse as sp

from bd_uv.frames import _edge_length_lookup, _far_pair, _loop_lengths, frames_from_map
from bd_uv.geometry import corner_angles, gradient_operators
from bd_uv.mesh import check_arrays, checked_islands
from bd_uv.solvers import ordered_ldl
from bd_uv.solvers.face_operators import gradient_rows
from bd_uv.solvers.global_step import GlobalStep
from bd_uv.solvers.lscm import lscm_pinned, face_geometry_of
from bd_uv.unwrapping import disk_conformal, energy_within, one_disk
from bd_uv.unwrapping.capped import from_angles
from bd_uv.unwrapping.problem import IslandProblem
from helpers import load_off, rings
from test_over_bound import _sphere_with_a_hole

pytestmark = pytest.mark.skipif(not ordered_ldl.available(), reason="no ordered factorisation")


def _ranked_disk():
    V, F = rings(*load_off("cow.off"), 5243, 400)
    disk = one_disk.find(V, F)
    assert disk is not None and disk.ranks is not None
    return V, disk


def _moved(disk, Z, faces, rng):
    """Z with the faces ``faces`` rebuilt from moved corner angles at their own areas."""
    A = np.abs(corner_angles(Z[faces])) * rng.uniform(0.85, 1.15, (len(faces), 3))
    Z = Z.copy()
    Z[faces] = from_angles(A * (np.pi / A.sum(axis=1))[:, None], disk.area[faces])
    return Z


def test_a_refilled_ordered_factor_is_a_new_ones_bits():
    """Triplets of an SPD matrix's upper triangle in a shuffled order, an elimination order:
    ``refill`` with other values (the same places) factorises and solves to the bits of a new
    ``Factor`` of them, and both solve the dense matrix's system."""
    rng = np.random.default_rng(5)
    n = 60
    M = sp.random(n, n, density=0.08, random_state=7)
    M = (M + M.T + sp.identity(n) * 4.0).tocoo()
    up = M.row <= M.col
    rows, cols = M.row[up].astype(np.int64), M.col[up].astype(np.int64)
    shuffle = rng.permutation(len(rows))
    rows, cols = rows[shuffle], cols[shuffle]
    perm = rng.permutation(n).astype(np.int64)
    vals = M.data[up][shuffle]
    kept = ordered_ldl.Factor(rows, cols, vals, n, perm, keep=True)
    assert kept.factor()
    b = rng.normal(size=n)
    for scale in (1.0, 1.7):
        vals2 = vals * scale + np.where(rows == cols, rng.uniform(0, 1, len(rows)), 0.0)
        f = kept.refill(vals2)
        new = ordered_ldl.Factor(rows, cols, vals2, n, perm)
        assert f.factor() and new.factor()
        x = f.solve(b)
        assert x.tobytes() == new.solve(b).tobytes()
        dense = np.zeros((n, n))
        dense[rows, cols] = vals2
        dense = dense + np.triu(dense, 1).T
        assert np.allclose(dense @ x, b, rtol=0, atol=1e-10)
    assert ordered_ldl.Factor(rows, cols, vals, n, perm).refill(vals) is None   # not kept


def test_conformal_solves_in_the_vertex_order_with_faces_rebuilt_are_lscm_pinneds_bits():
    """In the disk's vertex order, ``conformal(..., rebuilt=)`` (the system patched, the factor
    refilled) gives ``lscm_pinned``'s map of the same shapes (a new assembly and factor), bit for
    bit, through three solves of faces moved again and again."""
    V, disk = _ranked_disk()
    isl = disk.island
    rng = np.random.default_rng(11)
    edge = np.isin(isl.tris, isl.loops[0]).any(axis=1).nonzero()[0]
    Z, rebuilt = disk.Z, None
    for faces in (edge[:6], edge[3:12], np.array([], np.int64)):
        Z = _moved(disk, Z, faces, rng)
        G = gradient_operators(Z)
        u = disk_conformal.conformal(V, disk, Z, G, disk.ranks, rebuilt=rebuilt)
        geom = face_geometry_of(Z, G, disk.area)
        idx = disk_conformal._far_pair(V.take(isl.vertices, axis=0), isl.loops[0])
        anew = lscm_pinned(geom.cbw(), geom.cb, isl.tris, len(isl.vertices), idx,
                           np.array([0.0, 1.0], complex),
                           (disk.twins[0], disk.twins[1], disk.loop), disk.ranks)
        assert np.isfinite(u).all() and u.tobytes() == anew.tobytes()
        assert disk.factors["ranked"][0].lnz > 0
        rebuilt = faces


def test_loop_lengths_are_the_sparse_lookups_to_the_bit():
    """Every boundary loop (outer and holes) of a sphere with a hole and of a cow disk: the
    lengths are ``E[a, b] + E[b, a]`` of the sparse edge-length lookup, bit for bit."""
    V, F = rings(*load_off("cow.off"), 5243, 400)
    cases = [(V, F)]
    cases.append(_sphere_with_a_hole(2))
    for V, F in cases:
        for isl in checked_islands(*check_arrays(V, F)):
            from bd_uv.geometry import local_coordinates
            Z = local_coordinates(V[isl.vertices], isl.tris)
            nv = len(isl.vertices)
            E = _edge_length_lookup(Z, isl.tris, nv)
            E = E + E.T
            for loop in isl.loops:
                want = np.asarray(E[loop, np.roll(loop, -1)]).ravel()
                got = _loop_lengths(Z, isl.tris, nv, loop)
                assert got.tobytes() == want.tobytes() and (got > 0).all()


def _problem():
    V, F = _sphere_with_a_hole(2)
    (isl,) = checked_islands(V, F)
    return IslandProblem(isl, V, (np.zeros(0, np.int64), np.zeros((0, 2))), "lscm", "soc", None)


def _lowest_energy_scipy(prob, us, C, iterations, tau):
    """``lowest_energy`` as written with scipy's matrices (the arithmetic it replaces)."""
    ops, nv, k = prob.ops, prob.nv, len(prob.ops.area)
    idx, _ = _far_pair(prob.Z, prob.island.tris, nv, prob.island.loops[0])
    gs = GlobalStep(ops, nv, idx, prob.island.tris, connected=True, ranks=prob.ranks)
    solve = gs.factorize()
    free, fixed, G = gs.free, gs.fixed, gs.G
    GTA = sp.csr_array(G.T) @ sp.diags(np.concatenate([gs.area, gs.area]), format="csr")
    U = np.stack([us.real, us.imag], axis=1)
    share = gs.fixed_share(U[fixed])
    w = frames_from_map(prob.alpha(us))
    wr, wi = w.real, w.imag
    kappa = (C - 1.0) / (C + 1.0)
    s = np.sqrt(1.0 + tau)
    ks = kappa * s
    lam = np.zeros((4, k))
    P = np.empty((2 * k, 2))

    def lift():
        g = G @ U
        ux, uy, vx, vy = g[:k, 0], g[k:, 0], g[:k, 1], g[k:, 1]
        return np.array([0.5 * (ux + vy), 0.5 * (vx - uy), 0.5 * (ux - vy), 0.5 * (vx + uy)])
    J = lift()
    for _ in range(iterations):
        q = J + lam
        X = wr * q[0] - wi * q[1]
        Y = wr * q[1] + wi * q[0]
        br, bi = q[2] / s, q[3] / s
        nb = np.hypot(br, bi)
        t = np.maximum(X + ks * nb, 0.0) / (1.0 + ks * ks)
        f = np.minimum(ks * t / np.maximum(nb, 1e-300), 1.0) / s
        X = np.where(nb <= ks * X, X, t)
        z = np.array([wr * X + wi * Y, wr * Y - wi * X, f * br, f * bi])
        z -= lam
        P[:k, 0], P[k:, 0] = z[0] + z[2], z[3] - z[1]
        P[:k, 1], P[k:, 1] = z[1] + z[3], z[0] - z[2]
        rhs = (GTA @ P)[free] - share
        U[free, 0] = solve(np.ascontiguousarray(rhs[:, 0]))
        U[free, 1] = solve(np.ascontiguousarray(rhs[:, 1]))
        J = lift()
        lam = J - z
    return U[:, 0] + 1j * U[:, 1]


def test_lowest_energys_iterate_is_the_scipy_products_one_to_the_bit():
    """From the harmonic map of a sphere with a hole (flip-free), at two bounds: the iterate
    equals the scipy-matrix iteration's bit for bit, its lift's rows (``gradient_rows``, and
    ``GlobalStep``'s G, Gx, Gy made from them) are the operators' sums' (scipy's), and it lowers
    the conformal energy (recomputed from beta)."""
    from bd_uv.unwrapping.initial import start_map
    prob = _problem()
    h = start_map(prob, "harmonic", None, lambda *_: None)
    assert np.isfinite(h.D)
    o, nv = prob.ops, prob.nv
    G = sp.csr_array(sp.vstack([sp.csr_array((o.Are + o.Bre)[:, :nv]),
                                sp.csr_array((o.Bim - o.Aim)[:, :nv])]))
    gs = GlobalStep(o, nv, [0], prob.island.tris, connected=True)
    for ptr, ind, dat in (gradient_rows(o.gx, o.gy, prob.island.tris),
                          (gs.G.indptr, gs.G.indices, gs.G.data)):
        assert (np.array_equal(ptr, G.indptr) and np.array_equal(ind, G.indices)
                and dat.tobytes() == G.data.tobytes())
    for mine, theirs in ((gs.Gx, (o.Are + o.Bre)[:, :nv]), (gs.Gy, (o.Bim - o.Aim)[:, :nv])):
        theirs = sp.csr_array(theirs)
        assert (np.array_equal(mine.indptr, theirs.indptr)
                and np.array_equal(mine.indices, theirs.indices)
                and mine.data.tobytes() == theirs.data.tobytes())
    for C, it in ((h.D, 25), (0.5 * (1.0 + h.D), 7)):
        y = energy_within.lowest_energy(prob, h.u, C, it)
        assert y.tobytes() == _lowest_energy_scipy(prob, h.u, C, it, energy_within.TAU).tobytes()
    e = [float(prob.ops.area @ np.abs(prob.beta(v)) ** 2) for v in (h.u, y)]
    assert e[1] < e[0]


def test_the_problems_jacobians_and_distortion_are_scipys_products_bits():
    """alpha, beta and the face distortion of random maps (one with a flipped face) equal the
    scipy operators' products and ``(|a| + |b|) / (|a| - |b|)``, bit for bit."""
    prob = _problem()
    o = prob.ops
    rng = np.random.default_rng(2)
    for _ in range(3):
        u = rng.normal(size=prob.nv) + 1j * rng.normal(size=prob.nv)
        x = np.concatenate([u.real, u.imag])
        a, b = o.Are @ x + 1j * (o.Aim @ x), o.Bre @ x + 1j * (o.Bim @ x)
        assert prob.alpha(u).tobytes() == a.tobytes() and prob.beta(u).tobytes() == b.tobytes()
        na, nb = np.abs(a), np.abs(b)
        with np.errstate(divide="ignore", invalid="ignore"):
            D = np.where(na > nb, (na + nb) / (na - nb), np.inf)
        assert prob.face_distortion(u).tobytes() == D.tobytes()
        assert np.isinf(D).any() and np.isfinite(D).any()
