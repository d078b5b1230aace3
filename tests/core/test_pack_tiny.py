"""bd_uv.packing.tiny: mostly tiny charts packed as the others alone with the tiny ones dropped
into the free space; every layout checked by code that shares nothing with the packer
(``check_layout``: exact triangle overlaps, brute-force gaps)."""
import numpy as np

from bd_uv.packing import PackOptions, pack_islands
from bd_uv.packing.tiny import _drop, tiny_charts
from packing_checks import check_layout, inside, placed
from packing_sets import RECT, annulus, segment_distances


def _charts(sizes, holes=(), seed=0):
    """Rectangles (an annulus for the indices in ``holes``) of the given (k,2) sizes: 3D and UV
    the same shape, the UVs turned and moved anywhere."""
    rng = np.random.default_rng(seed)
    Vs, Fs, uvs, labs = [], [], [], []
    n = 0
    for i, s in enumerate(sizes):  # per chart
        P, T = annulus() if i in holes else RECT
        local = P * s
        Vs.append(np.c_[local, np.zeros(len(P))])
        th = rng.uniform(0, 2 * np.pi)
        R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
        uvs.append((local @ R.T + rng.uniform(-5, 5, 2))[T])
        Fs.append(T + n)
        labs.append(np.full(len(T), i))
        n += len(P)
    return np.concatenate(Vs), np.concatenate(Fs), np.concatenate(uvs), np.concatenate(labs)


def test_the_gate():
    """Tiny charts dropped when most charts (60 %) are tiny, hold little area and leave two
    others or more; else nothing."""
    many = np.r_[np.ones(4), np.full(40, 1e-4)]
    assert np.array_equal(tiny_charts(many), np.arange(4, 44))
    assert np.array_equal(tiny_charts(np.r_[np.ones(15), np.full(45, 1e-4)]),
                          np.arange(15, 60))                              # 75 % tiny
    assert np.array_equal(tiny_charts(np.r_[np.ones(27), np.full(56, 1e-4)]),
                          np.arange(27, 83))                              # 67 %: Wuson.off's
    assert tiny_charts(np.r_[np.ones(30), np.full(40, 1e-4)]) is None   # 57 % tiny
    assert tiny_charts(np.r_[np.ones(1), np.full(40, 1e-4)]) is None    # one left to pack
    assert tiny_charts(np.r_[np.ones(2), np.full(100, 2e-3)]) is None   # 9 % of the area
    # long thin charts of little area are not tiny (assimp's regr01.obj: no free box takes
    # them): with 20 of the 40 reaching 0.05 of the square root of the area, 20 of 44 are left
    ext = np.r_[np.full(4, 0.5), np.full(20, 0.2), np.full(20, 0.01)]
    assert tiny_charts(many, ext) is None
    assert np.array_equal(tiny_charts(many, np.r_[np.full(4, 0.5), np.full(40, 0.049)]),
                          np.arange(4, 44))


def test_many_tiny_charts_are_dropped_into_the_free_space():
    """4 large charts (one with a hole) and 60 tiny ones: the large ones laid out without a
    nesting solve (few.py), the tiny ones around them; certified by the independent checks,
    every tiny chart inside the square, and the square no larger than the large charts'
    own one from pack_islands."""
    rng = np.random.default_rng(3)
    sizes = np.r_[rng.uniform(0.5, 1.0, (4, 2)), rng.uniform(0.01, 0.03, (60, 2))]
    V, F, uv, lab = _charts(sizes, holes=(1,))
    options = PackOptions(seed=1)
    packed = pack_islands(V, F, uv, lab, options)
    assert packed.solves == 0
    check_layout(V, F, uv, lab, packed, options)
    big = lab < 4
    alone = pack_islands(V, F[big], uv[big], lab[big], options)
    # the same large charts' layout (few.py is deterministic), the tiny ones in its free space
    # (the outlines' simplification tolerance follows the total area: a hair apart)
    assert np.isclose(packed.texel_density, alone.texel_density, rtol=1e-5)


def _nestings(monkeypatch):
    """The (count of outlines, seconds) of every ``square_layout`` call ``tiny`` makes from
    now on, recorded as they run."""
    import bd_uv.packing.tiny as tiny
    seen = []
    real = tiny.square_layout

    def spy(outlines, options, tol, seconds, *rest, **kw):
        seen.append((len(outlines), seconds))
        return real(outlines, options, tol, seconds, *rest, **kw)

    monkeypatch.setattr(tiny, "square_layout", spy)
    return seen


def test_the_others_nest_for_their_own_time_with_a_dominant_one_cut(monkeypatch):
    """Seven large charts, one of them holding 0.6 of their area, and 14 tiny ones (67 %): the
    seven are nested for ``OTHERS_TIME`` times the time of their own count and faces, cut as a
    dominant chart cuts it (``search_seconds`` with its share, recomputed from the sizes), the
    layout certified."""
    import bd_uv.packing.tiny as tiny
    seen = _nestings(monkeypatch)
    sizes = np.r_[[[3.0, 3.0]], np.full((6, 2), 1.0), np.full((14, 2), 0.03)]
    V, F, uv, lab = _charts(sizes, seed=2)
    options = PackOptions(seed=0)
    packed = pack_islands(V, F, uv, lab, options)
    check_layout(V, F, uv, lab, packed, options)
    share = 9.0 / (9.0 + 6.0)     # the large chart's share of the seven's area
    assert len(seen) == 1 and seen[0][0] == 7
    assert tiny.OTHERS_TIME == 2.0
    assert np.isclose(seen[0][1], 2.0 * options.search_seconds(7, 7 * 2, share))
    assert options.search_seconds(7, 7 * 2, share) < options.search_seconds(7, 7 * 2)


def test_drop_keeps_the_separation_and_gives_up_without_room():
    """A large square chart and boxes dropped around it: each box at least the separation from
    the square and from each other (brute-force segment distances), inside the square with half
    of it; with the large chart filling the square, None."""
    side, sep = 10.0, 0.1
    square = 3.0 * np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    box = 0.2 * np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 0.5]])
    outlines = [square] + [box] * 12
    angle, shift = np.zeros(13), np.zeros((13, 2))
    shift[0] = (3.5, 3.5)
    got = _drop(outlines, np.array([0]), np.arange(1, 13), angle, shift, side, sep,
                PackOptions(rotate="any"))
    assert got is not None
    rings = placed(outlines, *got)
    for a in range(13):  # per pair of charts
        assert rings[a].min() >= 0.5 * sep and rings[a].max() <= side - 0.5 * sep
        for b in range(a + 1, 13):
            p, q = rings[a], rings[b]
            I, J = np.meshgrid(np.arange(len(p)), np.arange(len(q)), indexing="ij")
            d = segment_distances(p[I.ravel()], np.roll(p, -1, 0)[I.ravel()], q[J.ravel()],
                                  np.roll(q, -1, 0)[J.ravel()])
            assert d.min() >= sep
            assert not inside(q[0], p) and not inside(p[0], q)   # neither inside the other
    full = (side / 2 - 0.6 * sep) / 3.0 * square
    shift[0] = (side / 2, side / 2)
    assert _drop([full, box], np.array([0]), np.array([1]), np.zeros(2), shift[:2].copy(),
                 side, sep, PackOptions()) is None
