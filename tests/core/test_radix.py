"""``solvers.radix``: the orders and unique keys numpy's own sorts give, at each bound's
number of 16-bit passes (one, two, numpy's beyond 2**32), ties kept in input order."""
import numpy as np
import pytest

from bd_uv.solvers import radix


@pytest.mark.parametrize("bound", [1, 2, 300, 1 << 16, (1 << 16) + 1, 70_000 ** 2, 1 << 32,
                                   (1 << 32) + 5, 1 << 50])
def test_order_and_unique_are_numpys(bound):
    rng = np.random.default_rng(bound % 1000)
    for n in (0, 1, 7, 5000):
        # Many ties (a few distinct values) and keys at both ends of the range.
        key = rng.integers(0, bound, n, dtype=np.int64)
        if n > 10:
            key[:4] = (0, bound - 1, bound - 1, 0)
            key[4:n // 2] = key[rng.integers(0, 4, n // 2 - 4)]
        o = radix.order(key, bound)
        assert o.dtype == np.intp and np.array_equal(o, np.argsort(key, kind="stable"))
        u, inv, cnt = radix.unique(key, bound)
        eu, einv, ecnt = np.unique(key, return_inverse=True, return_counts=True)
        assert np.array_equal(u, eu) and np.array_equal(inv, einv.ravel())
        assert np.array_equal(cnt, ecnt) and np.array_equal(u[inv], key)
