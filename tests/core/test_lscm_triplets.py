"""``lscm.lscm_pinned`` in the vertices' ranks hands the factorisation its system's triplets as
they are (no scipy matrix made and unpacked): the same map, bit for bit, as through the canonical
matrix (``Upper.csc``, unpacked in column order, as before); and ``Upper.csc_arrays`` are that
matrix's arrays."""
import numpy as np
import pytest

from bd_uv.mesh import checked_islands
from bd_uv.solvers import ordered_ldl
from bd_uv.solvers.lscm import _lscm_system, face_geometry, lscm_pinned, ranked_triplet_solver
from helpers import grid, load_off
from qdldl_marks import needs_ordered_ldl

pytestmark = needs_ordered_ldl


@pytest.fixture(autouse=True)
def _fresh_lib():
    ordered_ldl._lib.cache_clear()
    yield


def _cases():
    V, F = load_off("nefertiti.off")
    yield V, F
    yield grid(9, 6, lambda x, y: 0.3 * np.sin(3 * x) * np.cos(2 * y))


def _through_the_matrix(cbw, cb, tris, n, idx, val, ranks):
    """The map as ``lscm_pinned`` made it before: the canonical csc matrix, unpacked to
    triplets in column order for the ordered factorisation."""
    A, rhs, u, free = _lscm_system(cbw, cb, tris, n, idx, val)
    cols = np.repeat(np.arange(A.shape[0], dtype=np.int64), np.diff(A.indptr))
    solve = ranked_triplet_solver(A.indices.astype(np.int64), cols, A.data, ranks[free])
    x = solve(rhs)
    nf = len(free)
    u[free] = x[:nf] + 1j * x[nf:]
    return u


def test_the_ranked_map_from_the_triplets_is_the_map_through_the_matrix():
    for V, F in _cases():
        (isl,) = checked_islands(V, np.asarray(F, np.int64))
        g = face_geometry(V, np.asarray(F)[isl.faces])
        n = len(isl.vertices)
        ranks = ordered_ldl.vertex_ranks(isl.tris, n)
        loop = isl.loops[0]
        for idx, val in (((loop[0], loop[len(loop) // 2]), [0.0, 1.0]),
                         ((loop[0], loop[1], loop[5]), [0.0, 0.5, 0.3 + 0.4j])):
            idx, val = np.array(idx), np.array(val, complex)
            want = _through_the_matrix(g.cbw(), g.cb, isl.tris, n, idx, val, ranks)
            got = lscm_pinned(g.cbw(), g.cb, isl.tris, n, idx, val, ranks=ranks)
            assert got.tobytes() == want.tobytes()
            assert np.array_equal(got[idx], val)


def test_the_upper_triangles_arrays_are_its_canonical_matrixs():
    for V, F in _cases():
        (isl,) = checked_islands(V, np.asarray(F, np.int64))
        g = face_geometry(V, np.asarray(F)[isl.faces])
        A = _lscm_system(g.cbw(), g.cb, isl.tris, len(isl.vertices), isl.loops[0][:2],
                         np.array([0.0, 1.0], complex), triplets=True)[0]
        M, arrays = A.csc(), A.csc_arrays()
        assert arrays.shape == M.shape and arrays.nnz == M.nnz
        assert arrays.indptr.tobytes() == M.indptr.astype(np.int64).tobytes()
        assert arrays.indices.tobytes() == M.indices.astype(np.int64).tobytes()
        assert arrays.data.tobytes() == M.data.tobytes()
