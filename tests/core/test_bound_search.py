"""``solvers.bound_search``: the per-face projection onto a framed cone, and the search over C that
``bound="auto"`` runs without a conic solve.

The projection is checked by Moreau's characterisation of the projection onto a closed convex cone
(the point is in the cone, the residual is orthogonal to it and lies in the polar cone); the
search's maps by distortion recomputed from their UVs (``helpers.reference_distortion``).
"""
import numpy as np
import pytest

from bd_uv.frames import frames_from_map
from bd_uv.mesh import islands
from bd_uv.solvers.bound_search import BoundSearch, framed_cone_projection
from bd_uv.unwrapping.problem import IslandProblem

from helpers import grid, load_off, reference_distortion

NO_PINS = (np.zeros(0, np.int64), np.zeros((0, 2)))


@pytest.mark.parametrize("kappa", [0.02, 0.3, 1.0, 4.0])
def test_framed_cone_projection_is_the_nearest_point_of_the_cone(kappa):
    rng = np.random.default_rng(3)
    q = rng.standard_normal((3, 4000)) * rng.choice([1e-3, 1.0, 1e3], size=4000)
    t = rng.uniform(0, 2 * np.pi, 100)   # and some points inside
    q[:, :100] = np.stack([np.ones(100), 0.5 * kappa * np.cos(t), 0.5 * kappa * np.sin(t)])
    x, br, bi = framed_cone_projection(q[0], q[1], q[2], kappa)
    p = np.stack([x, br, bi])
    scale = np.abs(q).max(axis=0)
    # in the cone
    assert np.all(np.hypot(p[1], p[2]) <= kappa * p[0] + 1e-12 * scale)
    r = q - p
    # the residual is orthogonal to the projection ...
    assert np.all(np.abs(np.sum(r * p, axis=0)) <= 1e-10 * scale ** 2)
    # ... and makes an obtuse angle with every point of the cone (the polar cone)
    for t in np.linspace(0, 2 * np.pi, 13):
        y = np.array([1.0, kappa * np.cos(t), kappa * np.sin(t)])
        assert np.all(y @ r <= 1e-10 * scale)
    # points inside stay where they are
    inside = np.hypot(q[1], q[2]) <= kappa * q[0]
    assert inside[:100].all() and np.array_equal(p[:, inside], q[:, inside])


def _map_distortion(V, isl, u):
    uv = np.stack([u.real, u.imag], axis=1)
    D, flipped = reference_distortion(V[isl.vertices], isl.tris, uv[isl.tris])
    return D, flipped


def test_search_lowers_the_conformal_maps_max_with_a_certified_map():
    """nefertiti: the LSCM map's max 1.443 comes down below Blender ABF's 1.405 (and the bound
    search's C, recomputed from the UVs, is its own max); the held vertex does not move."""
    V, F = load_off("nefertiti.off")
    isl = islands(V, F)[0]
    prob = IslandProblem(isl, V, NO_PINS, "lscm", "soc", None)
    u0 = prob.fallback_map()
    D0, flipped0 = _map_distortion(V, isl, u0)
    assert not flipped0.any()
    fixed = isl.loops[0][:1]
    bs = BoundSearch(prob.ops, prob.nv, isl.tris, fixed)
    u, D, out_of_time = bs.search(u0, lambda v: frames_from_map(prob.alpha(v)))
    Dr, flipped = _map_distortion(V, isl, u)
    assert not out_of_time and not flipped.any()
    assert Dr.max() == pytest.approx(D, rel=1e-9)
    assert D < 1.3 < 1.405 < D0.max()
    assert u[fixed] == pytest.approx(u0[fixed], abs=0)
    assert bs.iterations > 0
    # an island is one connected piece: told so, the search is the same to the bit
    one = BoundSearch(prob.ops, prob.nv, isl.tris, fixed, connected=True)
    u1, D1, _ = one.search(u0, lambda v: frames_from_map(prob.alpha(v)))
    assert one.solver.n_components == bs.solver.n_components == 1
    assert np.array_equal(one.solver.component, bs.solver.component)
    assert np.array_equal(u1, u) and D1 == D and one.iterations == bs.iterations


def test_search_keeps_the_pins():
    """A bumpy grid with two pins: the search holds them exactly and never returns a map above
    its start."""
    V, F = grid(9, 8, z=lambda x, y: 0.3 * np.sin(4 * x) * np.cos(3 * y))
    pins = (np.array([0, 3 * 40 + 2]), np.array([[0.0, 0.0], [1.0, 0.7]]))
    isl = islands(V, F)[0]
    prob = IslandProblem(isl, V, pins, "lscm", "soc", None)
    u0 = prob.fallback_map()
    D0, _ = _map_distortion(V, isl, u0)
    bs = BoundSearch(prob.ops, prob.nv, isl.tris, prob.pin_idx)
    u, D, _ = bs.search(u0, lambda v: frames_from_map(prob.alpha(v)))
    Dr, flipped = _map_distortion(V, isl, u)
    assert not flipped.any() and Dr.max() == pytest.approx(D, rel=1e-9)
    assert D <= D0.max()
    np.testing.assert_array_equal(u[prob.pin_idx], u0[prob.pin_idx])
    np.testing.assert_allclose(u[prob.pin_idx], prob.pin_val, atol=1e-12)


def test_a_cancelled_search_stops_at_once():
    V, F = load_off("nefertiti.off")
    isl = islands(V, F)[0]
    prob = IslandProblem(isl, V, NO_PINS, "lscm", "soc", None)
    u0 = prob.fallback_map()

    class Set:
        def is_set(self):
            return True
    bs = BoundSearch(prob.ops, prob.nv, isl.tris, isl.loops[0][:1])
    u, D, _ = bs.search(u0, lambda v: frames_from_map(prob.alpha(v)), cancel=Set())
    assert bs.iterations == 0 and np.array_equal(u, u0)


def test_the_paired_solve_gives_the_searchs_iterates_to_the_bit():
    """A small island's iterations back-solve u and v in one call where the factor has it
    (``ordered_ldl``'s ``paired``): the same maps, bits and iterations as one solve a half."""
    from bd_uv.solvers.ordered_ldl import available, vertex_ranks
    if not available():
        pytest.skip("qdldl's module does not export QDLDL here")
    V, F = load_off("nefertiti.off")
    isl = islands(V, F)[0]
    prob = IslandProblem(isl, V, NO_PINS, "lscm", "soc", None)
    u0 = prob.fallback_map()
    ranks = vertex_ranks(isl.tris, prob.nv)
    fixed = isl.loops[0][:1]
    paired = BoundSearch(prob.ops, prob.nv, isl.tris, fixed, connected=True, ranks=ranks)
    u1, D1, _ = paired.search(u0)
    assert hasattr(paired.solver.factorize(), "paired")
    halves = BoundSearch(prob.ops, prob.nv, isl.tris, fixed, connected=True, ranks=ranks)
    solve = halves.solver.factorize()

    def one_half(b):
        return solve(b)
    one_half.vector = solve.vector          # no ``paired``: a solve a half
    halves.solver._solve = one_half
    u2, D2, _ = halves.search(u0)
    assert np.array_equal(u1, u2) and D1 == D2 and paired.iterations == halves.iterations > 0
    Dr, flipped = _map_distortion(V, isl, u1)
    assert not flipped.any() and Dr.max() == pytest.approx(D1, rel=1e-9)


def test_the_right_hand_sides_gathered_product_is_the_scattered_one_to_the_bit(monkeypatch):
    """The free iterations' right-hand side is a product with the lift's transpose in rows of
    its own (``free_admm.transposed``): to the bit the product scattering the lift's rows (each
    unknown's terms added in the same order), and the transpose's product recomputed densely;
    the search's maps and iterations as with the scattering product."""
    from scipy.sparse._sparsetools import csc_matvec
    from bd_uv.solvers import free_admm
    V, F = load_off("nefertiti.off")
    isl = islands(V, F)[0]
    prob = IslandProblem(isl, V, NO_PINS, "lscm", "soc", None)
    u0 = prob.fallback_map()
    bs = BoundSearch(prob.ops, prob.nv, isl.tris, isl.loops[0][:1], connected=True)
    assert bs.on_free
    u1, D1, _ = bs.search(u0)
    lift = bs._free_lift()
    k, nf = lift.k, lift.nf
    rng = np.random.default_rng(3)
    w = np.exp(1j * rng.uniform(0.0, 2.0 * np.pi, k))
    _, wdt, _ = lift.framed(w)
    wd = lift._framed[1]                    # the same data in the lift's rows' order
    dense = np.zeros((4 * k, 2 * nf))
    rows = np.arange(4 * k).repeat(np.diff(lift.indptr))
    np.add.at(dense, (rows, lift.indices), wd)
    for _ in range(3):
        T = rng.normal(size=4 * k)
        start = rng.normal(size=2 * nf)
        scattered, gathered = start.copy(), start.copy()
        csc_matvec(2 * nf, 4 * k, lift.indptr, lift.indices, wd, T, scattered)
        lift.rhs(wdt, T, gathered)
        assert np.array_equal(scattered, gathered)
        assert np.allclose(gathered, start + dense.T @ T, rtol=1e-12, atol=1e-12)

    # the search with the scattering product: the same maps and iterations
    class Scattering(free_admm.FreeLift):
        def __init__(self, *a):
            super().__init__(*a)
            self.rhs = free_admm.sparse_product("csc", (2 * self.nf, 4 * self.k),
                                                self.indptr, self.indices)

        def framed(self, w):
            d, _, lf = super().framed(w)
            return d, self._framed[1], lf
    import bd_uv.solvers.search_lift as search_lift
    monkeypatch.setattr(search_lift, "FreeLift", Scattering)
    other = BoundSearch(prob.ops, prob.nv, isl.tris, isl.loops[0][:1], connected=True)
    u2, D2, _ = other.search(u0)
    assert np.array_equal(u1, u2) and D1 == D2 and bs.iterations == other.iterations > 0


@pytest.mark.parametrize("n", [20, 36])
def test_auto_on_a_flat_disk_does_not_search_round_off(n):
    """A flat disk's conformal map is an isometry up to round-off: ``auto`` certifies it without
    search iterations (20 x 20: the one-disk path; 36 x 36, 2450 faces: the general path), at
    the bound that keeps the storage headroom above it, and the UVs recomputed are an isometry."""
    import bd_uv
    rng = np.random.default_rng(5)
    V, F = grid(n, n)
    V[:, :2] += rng.uniform(-0.2, 0.2, (len(V), 2)) / n       # irregular triangles, still flat
    Q = np.linalg.qr(rng.standard_normal((3, 3)))[0]
    V = V @ Q.T + [3.0, -1.0, 2.0]                              # a plane in general position
    r = bd_uv.unwrap(V, F, bound="auto")
    isl = r.islands[0]
    assert r.certified and len(r.islands) == 1
    assert isl.iterations == 0 and "initial_map" in isl.flags
    assert 1.0 < isl.bound_certified <= 1.0 + 2.001e-4
    D, flipped = reference_distortion(V, F, r.corner_uv)
    assert not flipped.any() and D.max() <= 1.0 + 1e-9


def test_auto_on_a_small_disk_keeps_to_its_effort_budget(monkeypatch):
    """``bound="auto"`` on an unpinned disk of up to EFFORT_FACES faces, with no time budget,
    iterates at most EFFORT_PER_FACE a face (``target_watch.effort``); the same call gives the
    same UVs bit for bit (an iteration count, no clock), certified from the UVs recomputed here;
    unbounded (EFFORT_FACES 0) the search runs longer, to a C no higher."""
    from bd_uv.solvers import target_watch
    V, F = grid(11, 11, z=lambda x, y: 0.3 * np.sin(4 * x) * np.cos(3 * y))
    budget = max(target_watch.EFFORT_MIN, int(target_watch.EFFORT_PER_FACE * len(F)))
    bounded, free, runs = _bounded_and_unbounded(monkeypatch, V, F, 0, budget)
    assert free.bound_certified <= bounded.bound_certified
    for r in (runs[0], runs[2]):
        (isl,) = r.islands
        D, flipped = reference_distortion(V, F, r.corner_uv.reshape(-1, 3, 2))
        assert r.certified and not flipped.any()
        assert D.max() <= isl.bound_certified * (1 + 1e-9)


def _bounded_and_unbounded(monkeypatch, V, F, gate, budget):
    """``bound="auto"`` twice with the effort budget (the same UVs bit for bit: a count, no
    clock), then with ``target_watch.EFFORT_FACES`` at ``gate`` (no budget for this disk): the
    bounded run within ``budget`` iterations, the unbounded one past it. Returns (bounded
    island, unbounded island, [the three results])."""
    import bd_uv
    from bd_uv.solvers import bound_search, target_watch
    # the budget alone: the stop after two fruitless targets off (``bound_search.ZERO_SMALL``,
    # ``test_two_fruitless_targets_end_the_search``: on these grids it ends the unbounded
    # search within the budget)
    monkeypatch.setattr(bound_search, "ZERO_SMALL", False)
    runs = [bd_uv.unwrap(V, F, bound="auto") for _ in range(2)]
    assert np.array_equal(runs[0].corner_uv, runs[1].corner_uv)
    monkeypatch.setattr(target_watch, "EFFORT_FACES", gate)
    runs.append(bd_uv.unwrap(V, F, bound="auto"))
    (bounded,), (free,) = runs[0].islands, runs[2].islands
    assert 0 < bounded.iterations <= budget < free.iterations
    return bounded, free, runs


def test_auto_budget_grows_slower_beyond_its_knee_up_to_its_gate():
    """``target_watch.effort``: EFFORT_PER_FACE a face up to EFFORT_KNEE faces, then
    EFFORT_PER_FACE_BEYOND a face, never falling as the island grows, up to EFFORT_FACES faces
    (above: no budget), and none from a start over EFFORT_START."""
    from bd_uv.solvers import target_watch as T
    ks = list(range(1, T.EFFORT_FACES + 1))
    budgets = [T.effort(k, 1.5) for k in ks]
    assert all(b is not None for b in budgets) and budgets == sorted(budgets)
    assert budgets[0] == T.EFFORT_MIN
    assert T.effort(T.EFFORT_KNEE, 1.5) == int(T.EFFORT_PER_FACE * T.EFFORT_KNEE)
    k = T.EFFORT_KNEE + 1000
    assert T.effort(k, 1.5) == int(T.EFFORT_PER_FACE * T.EFFORT_KNEE
                                   + T.EFFORT_PER_FACE_BEYOND * 1000)
    assert T.effort(T.EFFORT_FACES + 1, 1.5) is None
    assert T.effort(100, T.EFFORT_START * 1.01) is None


def test_auto_on_a_disk_over_a_thousand_faces_keeps_to_its_effort_budget(monkeypatch):
    """A 1,152-face curved grid (over FIRST_STALL_FACES and EFFORT_KNEE, under EFFORT_FACES):
    ``bound="auto"`` iterates within ``target_watch.effort`` (89: 78 up to the knee, 0.02 a face
    beyond); the same call gives the same UVs bit for bit (a count, no clock); with the gate at
    1000 faces (unbounded here) the search runs longer, to a C no higher; both certified from
    the UVs recomputed here, the bounded C within 0.2 % of the unbounded one."""
    from bd_uv.solvers import target_watch
    V, F = grid(25, 25, z=lambda x, y: 0.3 * np.sin(4 * x) * np.cos(3 * y))
    assert len(F) > max(target_watch.FIRST_STALL_FACES, target_watch.EFFORT_KNEE)
    budget = target_watch.effort(len(F), 1.0)
    bounded, free, runs = _bounded_and_unbounded(monkeypatch, V, F, 1000, budget)
    assert free.bound_certified <= bounded.bound_certified <= 1.002 * free.bound_certified
    for r in (runs[0], runs[2]):
        (isl,) = r.islands
        D, flipped = reference_distortion(V, F, r.corner_uv.reshape(-1, 3, 2))
        assert r.certified and not flipped.any()
        assert D.max() <= isl.bound_certified * (1 + 1e-9)


def test_auto_starts_no_target_it_has_too_little_budget_for(monkeypatch):
    """Within auto's iteration budget no target starts with fewer than ``LEAST_RUN`` iterations
    left (a new target's first iterates rise above the best). Every target's start is recorded
    here: with LEAST_RUN 1 the search starts one with fewer left on these disks, with the product's
    value none does, and it ends with fewer iterations at the best the shorter run had reached:
    its UVs, recomputed here, are certified at its C."""
    import bd_uv
    from bd_uv.solvers import target_watch
    starts = []
    run = BoundSearch.run

    def recording(self, *a, **k):
        starts.append((self.budget, self.iterations))
        return run(self, *a, **k)
    monkeypatch.setattr(BoundSearch, "run", recording)
    shorter = 0
    for n, z in ((8, lambda x, y: 0.3 * np.sin(4 * x) * np.cos(3 * y)),
                 (9, lambda x, y: 0.25 * np.cos(3 * x) * np.sin(5 * y)),
                 (10, lambda x, y: 0.2 * np.sin(5 * x + 2 * y))):
        V, F = grid(n, n, z=z)
        got = {}
        for least in (1, target_watch.LEAST_RUN):
            monkeypatch.setattr(target_watch, "LEAST_RUN", least)
            starts.clear()
            r = bd_uv.unwrap(V, F, bound="auto")
            (isl,) = r.islands
            assert starts and all(b is not None and b - i >= least for b, i in starts)
            D, flipped = reference_distortion(V, F, r.corner_uv.reshape(-1, 3, 2))
            assert r.certified and not flipped.any()
            assert D.max() <= isl.bound_certified * (1 + 1e-9)
            got[least] = (isl.iterations, isl.bound_certified,
                          min(b - i for b, i in starts))
        (it1, c1, left1), (it6, c6, _) = got[1], got[target_watch.LEAST_RUN]
        assert it6 <= it1
        if left1 < target_watch.LEAST_RUN:      # the rule stopped a short last target
            shorter += 1
            assert it6 < it1 and c6 >= c1
        else:
            assert (it6, c6) == (it1, c1)
    assert shorter >= 1


def test_two_fruitless_targets_end_the_search(monkeypatch):
    """Two targets in a row that fall short gaining less than SMALL of D - 1, nothing included,
    end the search (``bound_search.ZERO_SMALL``): fewer iterations, each map certified, C within
    0.5 % of the search that goes on halving its step (measured: 58 against 89 iterations,
    1.0292 against 1.0269)."""
    import bd_uv
    from bd_uv.solvers import bound_search
    V, F = grid(25, 25, z=lambda x, y: 0.3 * np.sin(4 * x) * np.cos(3 * y))
    res = {}
    for zero in (False, True):
        monkeypatch.setattr(bound_search, "ZERO_SMALL", zero)
        res[zero] = bd_uv.unwrap(V, F, bound="auto").islands[0]
    for isl in res.values():
        D, flipped = reference_distortion(V[isl.vertices], isl.tris,
                                          isl.uv.take(isl.tris, axis=0))
        assert isl.status == "certified" and not flipped.any()
        assert D.max() <= isl.bound_certified
    assert res[True].iterations < res[False].iterations
    assert res[True].bound_certified <= 1.005 * res[False].bound_certified


def _three_peaks_strip():
    """619 faces of tests/data/three_peaks.off round its path along x (listed in
    tests/data/three-peaks-strip-faces.txt), unreferenced vertices dropped."""
    import os
    from helpers import DATA
    V, F = load_off("three_peaks.off")
    F = F[np.loadtxt(os.path.join(DATA, "three-peaks-strip-faces.txt"), dtype=np.int64)]
    used, inv = np.unique(F, return_inverse=True)
    return V[used], inv.reshape(-1, 3)


def test_a_fruitless_target_aimed_at_the_widest_step_is_not_counted(monkeypatch):
    """``bound_search.OVERSHOT``: a target aimed at MAX_STEP (reached only by widening after
    targets reached) that finds nothing only halves the step, and is counted neither as small
    nor as short. On this 619-face strip of three_peaks the budgeted search reaches two targets,
    widens to MAX_STEP, and finds nothing there nor at half of it: counted, these two ended it at
    C 1.653 (measured); not counted, the next target, a quarter of the step, is reached and the
    search ends at 1.5704. The max distortion recomputed from each map's UVs (numpy SVD) is within
    its certified C, and the one with OVERSHOT below 1.60 where the other is above 1.64."""
    import bd_uv
    from bd_uv.solvers import bound_search
    V, F = _three_peaks_strip()
    assert len(F) == 619
    res = {}
    for on in (False, True):
        monkeypatch.setattr(bound_search, "OVERSHOT", on)
        r = bd_uv.unwrap(V, F, bound="auto")
        (isl,) = r.islands
        D, flipped = reference_distortion(V, F, r.corner_uv.reshape(-1, 3, 2))
        assert r.certified and isl.status == "certified" and not flipped.any()
        assert D.max() <= isl.bound_certified * (1 + 1e-9)
        res[on] = (D.max(), isl.bound_certified, isl.iterations)
    assert res[True][0] < 1.60 < 1.64 < res[False][0]
    assert res[True][1] < res[False][1] and res[True][2] > res[False][2]


def test_the_first_best_after_a_fruitless_target_is_checked(monkeypatch):
    """``bound_search.CHECK_AFTER_FRUITLESS``: a search given a ``check`` asks it of the first new
    best of a target after one that found nothing (on this grid targets 2 and 3 find nothing,
    target 4 a lower map); True ends the search there, with that map. Every other best is left
    unasked here (``target_watch.CHECK_EVERY`` out of reach)."""
    from bd_uv.solvers import bound_search, target_watch
    monkeypatch.setattr(target_watch, "CHECK_EVERY", 10 ** 9)
    V, F = grid(25, 25, z=lambda x, y: 0.3 * np.sin(4 * x) * np.cos(3 * y))
    isl = islands(V, F)[0]
    prob = IslandProblem(isl, V, NO_PINS, "lscm", "soc", None)
    u0 = prob.fallback_map()

    def searched(answer, on=True):
        monkeypatch.setattr(bound_search, "CHECK_AFTER_FRUITLESS", on)
        bs = BoundSearch(prob.ops, prob.nv, isl.tris, isl.loops[0][:1])
        runs, asked = [], []
        run = bs.run

        def counted(*a, **k):
            out = run(*a, **k)
            runs.append((out[0] is not None, out[1]))
            return out
        bs.run = counted
        bs.check = lambda v: asked.append((v, bs.iterations, len(runs))) or answer
        u, D, _ = bs.search(u0, lambda v: frames_from_map(prob.alpha(v)))
        return u, D, bs.iterations, runs, asked

    u, D, its, runs, asked = searched(False)
    assert [found for found, _ in runs[:4]] == [True, False, False, True]
    assert len(asked) == 1 and asked[0][2] == 3      # asked within the 4th target
    Da, flipped = _map_distortion(V, isl, asked[0][0])
    assert not flipped.any() and runs[3][1] <= Da.max() < runs[0][1]     # a new best
    uc, Dc, itc, _, askedc = searched(True)          # ... which ends the search
    assert len(askedc) == 1 and np.array_equal(uc, askedc[0][0]) and itc == askedc[0][1] < its
    Dr, flipped = _map_distortion(V, isl, uc)
    assert not flipped.any() and Dr.max() == pytest.approx(Dc, rel=1e-9) and D < Dc
    off = searched(True, on=False)
    assert off[4] == [] and off[2] == its and np.array_equal(off[0], u)
