"""One AMD order of an island's vertices, shared by ``bound="auto"``'s conformal map and its bound
search (``solvers.ordered_ldl.vertex_ranks``, ``solver_in_order``), must solve what qdldl's own
order solves:

- the ranks are a permutation of the vertices, the same from any copy of the triangles, and None
  above ``RANKED_VERTICES``;
- a matrix factorised in its own order solves to scipy's solution, one right-hand side or many,
  and its in-place ``vector`` solve and its ``paired`` solve of two gives the same numbers;
- the conformal map in the ranks' order equals qdldl's to rounding;
- the global step with ranks numbers its free vertices in their order and solves the same
  least-squares step as without.
"""
import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from bd_uv.energies import jacobian_operators
from bd_uv.geometry import local_coordinates
from bd_uv.mesh import checked_islands
from bd_uv.solvers import ordered_ldl
from bd_uv.solvers.global_step import GlobalStep
from bd_uv.solvers.lscm import face_geometry, lscm_pinned
from helpers import grid, load_off
from qdldl_marks import needs_ordered_ldl

pytestmark = needs_ordered_ldl


@pytest.fixture(autouse=True)
def _fresh_lib():
    """``ordered_ldl._lib`` found anew: a test that replaced qdldl's release may have left its
    answer (None) cached (``test_seams_orders``' unchecked release: its last line reads
    ``available()`` while its ``_version`` is still replaced)."""
    ordered_ldl._lib.cache_clear()
    yield


def _island(V, F):
    (isl,) = checked_islands(V, np.asarray(F, np.int64))
    return isl


def test_the_ranks_are_a_permutation_of_the_vertices_and_depend_on_the_triangles_alone():
    V, F = load_off("nefertiti.off")
    isl = _island(V, F)
    n = len(isl.vertices)
    r = ordered_ldl.vertex_ranks(isl.tris, n)
    assert r.dtype == np.int64 and np.array_equal(np.sort(r), np.arange(n))
    assert np.array_equal(r, ordered_ldl.vertex_ranks(isl.tris.copy(), n))
    # the faces in another order: the same graph, the same canonical pattern, the same order
    assert np.array_equal(r, ordered_ldl.vertex_ranks(isl.tris[::-1].copy(), n))
    big = ordered_ldl.RANKED_VERTICES + 1
    assert ordered_ldl.vertex_ranks(np.array([[0, 1, 2]]), big) is None


@pytest.mark.parametrize("name", ["nefertiti", "grid"])
def test_a_disks_ranks_from_its_edges_are_the_triangles_ranks(name):
    """``one_disk.Disk.ranks`` orders the graph of the edges it found (each once, unsorted:
    ``edge_ranks``): the same order as ``vertex_ranks`` of the island's triangles."""
    from bd_uv.unwrapping import one_disk
    V, F = (load_off("nefertiti.off") if name == "nefertiti" else
            grid(9, 8, z=lambda x, y: 0.3 * np.sin(4 * x) * np.cos(3 * y)))
    disk = one_disk.find(np.asarray(V, float), np.asarray(F, np.int64))
    n = len(disk.island.vertices)
    # every edge once: the interior ones and the loop's
    assert len(disk.twins[0]) + len(disk.loop) == len(np.unique(np.sort(
        np.concatenate([disk.island.tris[:, [0, 1]], disk.island.tris[:, [1, 2]],
                        disk.island.tris[:, [2, 0]]]), axis=1), axis=0))
    assert np.array_equal(disk.ranks, ordered_ldl.vertex_ranks(disk.island.tris, n))


def test_a_matrix_factorised_in_its_own_order_solves_to_scipys_solution():
    V, F = grid(9, 8, z=lambda x, y: 0.3 * np.sin(4 * x) * np.cos(3 * y))
    isl = _island(V, F)
    n = len(isl.vertices)
    ops = jacobian_operators(local_coordinates(V[isl.vertices], isl.tris), isl.tris, n)
    g = GlobalStep(ops, n, isl.loops[0][:1], isl.tris, connected=True)
    L = g.global_matrix()
    solve = ordered_ldl.solver_in_order(L)
    rng = np.random.default_rng(1)
    b, B = rng.standard_normal(L.shape[0]), rng.standard_normal((L.shape[0], 3))
    ref = spla.spsolve(sp.csc_matrix(L), b)
    assert np.allclose(solve(b), ref, rtol=0, atol=1e-10 * np.abs(ref).max())
    assert np.allclose(solve(B), spla.spsolve(sp.csc_matrix(L), B), rtol=0,
                       atol=1e-10 * np.abs(ref).max() * 10)
    x = solve.vector(b).copy()
    assert np.array_equal(x, solve(b))
    # the upper triangle alone gives the same factor
    assert np.array_equal(ordered_ldl.solver_in_order(sp.triu(L, format="csc"))(b), solve(b))
    # the paired solve (both halves of a (2n,) vector in one call, in place) is two solves
    # bit for bit, and scipy's solution of the block-diagonal system
    c = rng.standard_normal(L.shape[0])
    pair = solve.paired()
    assert pair is solve.paired()               # made once
    pair.buffer[...] = np.concatenate([b, c])
    pair()
    assert np.array_equal(pair.buffer, np.concatenate([solve(b), solve(c)]))
    both = spla.spsolve(sp.csc_matrix(sp.block_diag([L, L])), np.concatenate([b, c]))
    assert np.allclose(pair.buffer, both, rtol=0, atol=1e-10 * np.abs(both).max())


def test_the_conformal_map_in_the_ranks_order_is_qdldls_to_rounding():
    V, F = load_off("nefertiti.off")
    isl = _island(V, F)
    n = len(isl.vertices)
    g = face_geometry(V[isl.vertices], isl.tris)
    idx, val = isl.loops[0][[0, len(isl.loops[0]) // 2]], np.array([0.0, 1.0], complex)
    u0 = lscm_pinned(g.cbw(), g.cb, isl.tris, n, idx, val)
    u1 = lscm_pinned(g.cbw(), g.cb, isl.tris, n, idx, val,
                     ranks=ordered_ldl.vertex_ranks(isl.tris, n))
    assert np.allclose(u1, u0, rtol=0, atol=1e-11)
    assert u1[idx[0]] == 0 and u1[idx[1]] == 1


def test_the_global_step_with_ranks_solves_the_same_step():
    V, F = load_off("nefertiti.off")
    isl = _island(V, F)
    n = len(isl.vertices)
    ops = jacobian_operators(local_coordinates(V[isl.vertices], isl.tris), isl.tris, n)
    fixed = isl.loops[0][:1]
    plain = GlobalStep(ops, n, fixed, isl.tris, connected=True)
    ranks = ordered_ldl.vertex_ranks(isl.tris, n)
    ranked = GlobalStep(ops, n, fixed, isl.tris, connected=True, ranks=ranks)
    assert np.array_equal(np.sort(ranked.free), plain.free)
    assert np.all(np.diff(ranks[ranked.free]) > 0)           # in elimination order
    rhs = np.random.default_rng(2).standard_normal(len(plain.free))
    x0 = plain.factorize()(rhs)                             # indexed by plain.free
    pos = np.searchsorted(plain.free, ranked.free)          # ranked.free's places in plain.free
    x1 = ranked.factorize()(rhs[pos])
    assert ranked.backend == "qdldl-ordered"
    assert np.allclose(x1, x0[pos], rtol=0, atol=1e-10 * np.abs(x0).max())
