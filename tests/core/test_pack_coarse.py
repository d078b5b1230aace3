"""The nesting's coarse outlines and the budget of a set one chart dominates (issue 18,
benchmarks/results/issue18-packtime13-2026-11-28.md): the coarse outlines hold the exact ones
within their tolerance (distances recomputed here), layouts nested from them are certified by
``packing_checks.check_layout`` (exact triangle overlap, brute-force gaps, inside the square, one
density), and the budget's share rule is recomputed from the areas."""
import numpy as np
import pytest

import bd_uv.packing.atlas as atlas
import bd_uv.packing.square as square
from bd_uv.packing import PackOptions, pack_islands
from bd_uv.packing.options import DOMINANT_MAX_CHARTS, DOMINANT_SHARE
from packing_checks import check_layout


def _wavy_discs(k, seed, n=240, big=None):
    """k flat discs with wavy rims of n points each (long outlines, as charts of many faces
    have), fanned from their centres; their 3D copies at other scales. ``big``: the first disc's
    radius (a dominant chart)."""
    rng = np.random.default_rng(seed)
    Vs, Fs, uvs = [], [], []
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    for i in range(k):  # per chart
        r = rng.uniform(0.3, 1.0) if big is None or i else big
        rim = r * (1 + 0.08 * np.sin(rng.integers(3, 9) * t + rng.uniform(0, 6)))
        P = np.r_[[[0.0, 0.0]], np.c_[rim * np.cos(t), rim * np.sin(t)] * rng.uniform(0.6, 1.4,
                                                                                   2)]
        T = np.array([[0, 1 + j, 1 + (j + 1) % n] for j in range(n)])
        Vs.append(np.c_[P * rng.uniform(0.5, 2.0), np.zeros(len(P))])
        Fs.append(T + sum(len(v) for v in Vs[:-1]))
        uvs.append((P * rng.uniform(0.2, 3.0) + rng.uniform(-4, 4, 2))[T])
    return (np.concatenate(Vs), np.concatenate(Fs), np.concatenate(uvs),
            np.repeat(np.arange(k), n))


def _shares(V, F, lab):
    """Each chart's share of the charts' 3D area (recomputed here)."""
    P = V[F]
    a = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    s = np.bincount(lab, a)
    return s / s.sum()


def test_coarse_outline_holds_every_exact_point_within_its_tolerance():
    """Every point of the exact outline within tol of the coarse ring (GEOS distance), and the
    coarse ring has far fewer points."""
    import shapely
    t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    r = 1 + 0.05 * np.sin(7 * t)
    exact = [np.c_[r * np.cos(t), r * np.sin(t)], np.c_[2 * np.cos(t), 0.5 * np.sin(t)]]
    tol = 0.01
    coarse, got = square._coarse(exact, tol)
    assert got == tol
    for xy, c in zip(exact, coarse):  # per outline
        assert len(c) < 0.5 * len(xy)
        ring = shapely.LinearRing(c)
        d = shapely.distance(shapely.points(xy), ring)
        assert d.max() <= tol * (1 + 1e-9)
        assert shapely.Polygon(c).exterior.is_ccw and shapely.Polygon(c).is_valid


@pytest.mark.parametrize("k, seed, res, pad", [(8, 1, 1024, 4), (14, 2, 2048, 8),
                                               (20, 3, 512, 2)])
def test_layouts_nested_from_coarse_outlines_are_certified(k, seed, res, pad, monkeypatch):
    """Up to COARSE_MAX_CHARTS charts of long outlines: spyrrow nests the coarse ones and the
    layout is refitted onto the exact ones (both seen here), and it keeps the padding between
    the true charts."""
    calls, refits = [], []
    real, refit = square._coarse, square.refitted
    monkeypatch.setattr(square, "_coarse", lambda ex, tol: calls.append(tol) or real(ex, tol))
    monkeypatch.setattr(square, "refitted", lambda *a: refits.append(1) or refit(*a))
    V, F, uv, lab = _wavy_discs(k, seed)
    options = PackOptions(resolution=res, padding_px=pad, seed=seed)
    packed = pack_islands(V, F, uv, lab, options)
    assert len(calls) == 1 and len(refits) == 1
    cert = check_layout(V, F, uv, lab, packed, options)
    assert 0.3 < cert.coverage < 1.0


def test_more_charts_are_nested_from_their_own_outlines(monkeypatch):
    """Above COARSE_MAX_CHARTS charts the coarse outlines are not made."""
    calls = []
    monkeypatch.setattr(square, "_coarse", lambda ex, tol: calls.append(tol))
    k = square.COARSE_MAX_CHARTS + 1
    V, F, uv, lab = _wavy_discs(k, 5, n=24)
    options = PackOptions(seed=0)
    check_layout(V, F, uv, lab, pack_islands(V, F, uv, lab, options), options)
    assert not calls


def test_outlines_the_simplification_barely_shortens_are_nested_as_they_are(monkeypatch):
    """Rectangles keep all their points coarse (more than COARSE_KEEP): spyrrow nests the
    outlines as given (the coarse layout's refit onto the exact outlines is never asked)."""
    from packing_sets import chart_set
    made, refits = [], []
    real = square._coarse
    monkeypatch.setattr(square, "_coarse", lambda ex, tol: made.append(tol) or real(ex, tol))
    monkeypatch.setattr(square, "refitted", lambda *a: refits.append(a))
    V, F, uv, lab = chart_set("boxes", 10, seed=3)
    options = PackOptions(seed=0)
    check_layout(V, F, uv, lab, pack_islands(V, F, uv, lab, options), options)
    assert len(made) == 1 and not refits


def test_budget_shrinks_by_the_largest_charts_share_above_the_threshold():
    """Up to DOMINANT_MAX_CHARTS charts, the adaptive time times DOMINANT_SHARE / largest share
    above DOMINANT_SHARE (rocker-arm's 10 charts of 20,088 faces, largest 0.43: 0.6 s -> 0.419
    s); at or below the share, above the chart count or with a time given: unchanged."""
    auto = PackOptions()
    assert auto.search_seconds(10, 20088) == pytest.approx(0.6)
    assert auto.search_seconds(10, 20088, 0.43) == pytest.approx(0.6 * 0.3 / 0.43)
    assert auto.search_seconds(10, 20088, DOMINANT_SHARE) == pytest.approx(0.6)
    assert auto.search_seconds(6, 634, 0.6) == pytest.approx(0.5 * 0.3 / 0.6)   # the floor too
    many = DOMINANT_MAX_CHARTS + 1
    assert auto.search_seconds(many, 10 ** 4, 0.9) == auto.search_seconds(many, 10 ** 4)
    assert PackOptions(solve_seconds=0.7).search_seconds(10, 20088, 0.43) == 0.7
    assert auto.search_seconds(1, 100, 1.0) == 0.0


def test_pack_gives_the_nesting_the_budget_of_its_largest_chart(monkeypatch):
    """pack_islands asks the budget with the largest chart's share of the 3D area (recomputed
    here from the faces), and the layout stays certified."""
    seen = []
    real = atlas.square_layout
    monkeypatch.setattr(atlas, "square_layout",
                        lambda o, opt, tol, s, ex, **kw: seen.append(s) or real(o, opt, tol, s, ex,
                                                                                  **kw))
    V, F, uv, lab = _wavy_discs(9, 4, n=60, big=3.0)
    share = _shares(V, F, lab).max()
    assert share > DOMINANT_SHARE
    options = PackOptions(seed=1)
    packed = pack_islands(V, F, uv, lab, options)
    assert seen == [pytest.approx(options.search_seconds(9, len(F)) * DOMINANT_SHARE / share)]
    check_layout(V, F, uv, lab, packed, options)


def test_the_guessed_density_follows_the_search_time():
    """1 up to GUESS_SEARCH seconds a chart, 1 + GUESS_GAIN ln(x / GUESS_SEARCH) above it,
    GUESS_MAX at most (recomputed here)."""
    g = square.GUESS_SEARCH
    assert square.searched_density(0.0) == 1.0 and square.searched_density(g) == 1.0
    assert square.searched_density(-1.0) == 1.0
    assert square.searched_density(2 * g) == pytest.approx(1 + square.GUESS_GAIN * np.log(2))
    assert square.searched_density(100 * g) == pytest.approx(square.GUESS_MAX)
    assert square.GUESS_MAX == pytest.approx(0.70 / 0.63)


def test_a_longer_search_nests_a_tighter_strip(monkeypatch):
    """On the coarse path, a search of more than GUESS_SEARCH seconds a chart asks spyrrow for a
    strip whose square is smaller by sqrt of the factor (recomputed from the time asked) than the
    adaptive budget's, whose factor is 1; both layouts are certified."""
    sides = []
    real = square._solve_all
    monkeypatch.setattr(square, "_solve_all",
                        lambda o, s, *a, **kw: sides.append(list(s)) or real(o, s, *a, **kw))
    k, seconds = 8, 1.2
    V, F, uv, lab = _wavy_discs(k, 2)
    for solve in (None, seconds):  # the adaptive budget, then a longer one
        options = PackOptions(seed=0, solve_seconds=solve)
        check_layout(V, F, uv, lab, pack_islands(V, F, uv, lab, options), options)
    auto = PackOptions().search_seconds(k, len(F), float(_shares(V, F, lab).max()))
    assert (0.5 * auto - square.START_PER_CHART * k) / k <= square.GUESS_SEARCH
    # (the long search is not short: its first placement is START_PER_CHART a chart)
    x = (0.5 * seconds - square.START_PER_CHART * k) / k
    f = 1 + square.GUESS_GAIN * np.log(x / square.GUESS_SEARCH)
    assert sides[1][0] / sides[0][0] == pytest.approx(1 / np.sqrt(f), rel=2e-3)


@pytest.mark.parametrize("cores", [1, 2, 3, 8])
def test_the_coarse_nesting_leaves_a_core_to_the_rest(monkeypatch, cores):
    """On the coarse path each solve at once searches on (cores - SPARE_CORES) // solves workers,
    at least one; off it (21 charts and more) on cores // solves; on one up to FEW_CHARTS charts
    (spyrrow's workers meet after every step: one without a core holds the others up). The
    counts are recomputed here; whether the coarse outlines were nested is recomputed from the
    points they keep; the packs stay certified."""
    asked, kept = [], []
    real, simplify = square.nest, square._coarse
    monkeypatch.setattr(square.os, "cpu_count", lambda: cores)
    monkeypatch.setattr(square, "nest",
                        lambda *a, **kw: asked.append(a[6]) or real(*a, **kw))

    def spy(exact, tol):
        fewer, wider = simplify(exact, tol)
        kept.append(sum(map(len, fewer)) / sum(map(len, exact)))
        return fewer, wider
    monkeypatch.setattr(square, "_coarse", spy)
    # few charts; the coarse path, one solve and three (two at once first); 21 charts
    for k, n, solves in ((3, 60, 1), (8, 240, 1), (8, 240, 3), (21, 60, 1)):
        V, F, uv, lab = _wavy_discs(k, 2, n=n)
        options = PackOptions(seed=0, solve_seconds=0.1, solves=solves)
        asked.clear()
        kept.clear()
        check_layout(V, F, uv, lab, pack_islands(V, F, uv, lab, options), options)
        # (the exact outlines have at least as many points as the nested ones at 0.1 texel)
        coarse = k <= square.COARSE_MAX_CHARTS and bool(kept) and kept[0] <= square.COARSE_KEEP
        assert coarse == (k < 21)    # the cases are what they say
        first = (solves + 1) // 2     # the first round's solves at once
        spare = square.SPARE_CORES if coarse else 0
        want = 1 if k <= square.FEW_CHARTS else max(1, (cores - spare) // first)
        assert asked and asked[0] == want
