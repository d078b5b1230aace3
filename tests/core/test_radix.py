"""``solvers.radix``: the orders and unique keys numpy's own sorts give, at each bound's
number of 16-bit passes (one, two, numpy's beyond 2**32), ties kept in input order."""
import numpy as np
import pytest

from bd_uv.solvers import radix


@pytest.mark.parametrize("bound", [1, 2, 300, 1 << 16, (1 << 16) + 1, 70_000 ** 2, 1 << 32,
                                   (1 << 32) + 5, 1 << 50])
def test_order_and_unique_are_numpys(bound):
    rng = np.random.default_rng(bound % 1000)
    for n in (0, 1, 7, 5000, radix.LARGE + 1):
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


def test_more_passes_and_the_sweeps_orders_are_lexsorts():
    """Up to four 16-bit passes; the Fiedler sweep's order and each chart's least score
    (``split._sweep_order``, ``split._least_per_group``) equal the lexsorts they replace, with
    ties, infinite scores and the NaN fallback."""
    from bd_uv.seams.split import _least_per_group, _sweep_order
    rng = np.random.default_rng(5)
    for bound in (1 << 40, 1 << 48, (1 << 62) + 3):
        key = rng.integers(0, bound, 3000, dtype=np.int64)
        key[:1000] = key[rng.integers(0, 50, 1000)]
        assert np.array_equal(radix.order(key, bound, passes=4), np.argsort(key, kind="stable"))
    for g in (1, 3, 70_000):
        size = rng.integers(0, 8, g) if g > 3 else rng.integers(1, 4000, g)
        group = np.repeat(np.arange(g), size)
        k = len(group)
        r = np.round(rng.standard_normal(k) * 1e9 / 4)
        r[rng.random(k) < 0.3] = 7.0                      # ties within charts
        assert np.array_equal(_sweep_order(r, group, g), np.lexsort((np.arange(k), r, group)))
        s = np.round(rng.random(k) * 50)
        s[rng.random(k) < 0.2] = np.inf
        if g == 3:
            s[group == 1] = np.inf                          # a chart with no finite score
        for t in (s, np.where(rng.random(k) < 0.01, np.nan, s)):
            best = np.lexsort((np.arange(k), t, group))
            want = best[np.r_[True, group[best][1:] != group[best][:-1]]]
            assert np.array_equal(_least_per_group(t, group, g), want)
    r = np.array([np.nan, 1.0, 2.0 ** 40])                  # not radix-able: numpy's lexsort
    assert np.array_equal(_sweep_order(r, np.zeros(3, np.int64), 1),
                          np.lexsort((np.arange(3), r, np.zeros(3))))
