"""``solvers.forest.component_count``: the roots of QDLDL's elimination tree counted as the
connected components of a graph (``one_disk.find``'s one-piece test) must be the count of
``geometry.components``' hooking (and scipy's), on random graphs and on a disk with a torus."""
import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from bd_uv.geometry import components
from bd_uv.solvers import forest, ordered_ldl
from qdldl_marks import needs_ordered_ldl

pytestmark = needs_ordered_ldl


@pytest.fixture(autouse=True)
def _fresh_lib():
    ordered_ldl._lib.cache_clear()
    yield


def test_the_forests_roots_are_the_graphs_components():
    rng = np.random.default_rng(7)
    for _ in range(400):
        n = int(rng.integers(1, 80))
        k = int(rng.integers(0, 2 * n))
        a, b = rng.integers(0, n, k), rng.integers(0, n, k)     # loops and repeats included
        G = sp.coo_matrix((np.ones(k), (a, b)), shape=(n, n))
        want = connected_components(G, directed=False)[0]
        assert forest.component_count(a, b, n) == want == components(n, a, b)[0]


def test_a_long_path_and_a_star_in_any_order_are_one_piece():
    rng = np.random.default_rng(3)
    n = forest.FOREST_VERTICES
    p = rng.permutation(n)
    assert forest.component_count(p[:-1], p[1:], n) == 1
    assert forest.component_count(np.zeros(n - 1, np.int64), p[p != 0], n) == 1
    # one edge less: two pieces
    assert forest.component_count(p[:-2], p[1:-1], n) == 2


def test_above_its_size_or_without_the_ordered_factorisation_it_gives_way(monkeypatch):
    n = forest.FOREST_VERTICES + 1
    assert forest.component_count(np.arange(n - 1), np.arange(1, n), n) is None
    monkeypatch.setattr(ordered_ldl, "available", lambda: False)
    assert forest.component_count(np.array([0]), np.array([1]), 2) is None
