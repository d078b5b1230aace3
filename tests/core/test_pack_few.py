"""A few charts (bd_uv.packing.few): 1-6 charts of every shape the fast path meets, at paddings
0-16 px and 256-8192 px, checked by ``packing_checks.check_layout`` (exact triangle overlap, brute
force gaps, inside the square, one density, turns never mirrors, then the product's
certificate); true shapes, not boxes; deterministic."""
import numpy as np
import pytest

from bd_uv.packing import PackOptions, pack_islands
from bd_uv.packing import few
from packing_checks import check_layout


def _grid_chart(mask):
    """A chart of unit cells where ``mask`` (rows, cols) is set: corners and triangles."""
    mask = np.asarray(mask, bool)
    rows, cols = mask.shape
    P = np.array([(x, y) for y in range(rows + 1) for x in range(cols + 1)], float)
    T = []
    for y, x in zip(*np.nonzero(mask)):  # per cell
        a = y * (cols + 1) + x
        b, c, d = a + 1, a + cols + 2, a + cols + 1
        T += [[a, b, c], [a, c, d]]
    return P, np.array(T)


def _band(inner=1.0, outer=1.6, turn=np.pi, n=24):
    """Half of a torus's band: an annular sector (concave on its inner side)."""
    t = np.linspace(0, turn, n + 1)
    P = np.concatenate([np.c_[inner * np.cos(t), inner * np.sin(t)],
                        np.c_[outer * np.cos(t), outer * np.sin(t)]])
    T = [[i, n + 2 + i, i + 1] for i in range(n)] + [[i, n + 1 + i, n + 2 + i] for i in range(n)]
    return P, np.array(T)


SHAPES = {
    "square": _grid_chart([[1]]),
    "L": _grid_chart([[1, 0], [1, 1]]),
    "band": _band(),
    "sliver": (np.array([[0, 0], [30, 0], [30, 0.4], [0, 0.4]], float),
               np.array([[0, 1, 2], [0, 2, 3]])),
    "hole": _grid_chart([[1, 1, 1], [1, 0, 1], [1, 1, 1]]),
}


def _charts(kinds, seed=0):
    """Charts of the given shapes: each scaled and turned at random in UV, its 3D copy scaled
    otherwise (densities differ before packing). V, F, corner_uv, face_island."""
    rng = np.random.default_rng(seed)
    Vs, Fs, uvs, lab, n = [], [], [], [], 0
    for i, kind in enumerate(kinds):  # per chart
        P, T = SHAPES[kind]
        local = P * rng.uniform(0.5, 1.5)
        Vs.append(np.c_[local * rng.uniform(0.5, 2.0), np.zeros(len(P))])
        th = rng.uniform(0, 2 * np.pi)
        R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
        uvs.append((local @ R.T * rng.uniform(0.2, 3.0) + rng.uniform(-4, 4, 2))[T])
        Fs.append(T + n)
        lab.append(np.full(len(T), i))
        n += len(P)
    return np.concatenate(Vs), np.concatenate(Fs), np.concatenate(uvs), np.concatenate(lab)


CASES = [
    (("square", "square"), 0, 256),
    (("L", "square", "band"), 4, 1024),
    (("band", "band"), 4, 1024),
    (("band", "band"), 16, 256),
    (("sliver", "L", "hole"), 2, 8192),
    (("hole", "square", "square", "L"), 16, 1024),
    (("sliver", "sliver", "band", "square"), 0, 8192),
    (("L", "L", "L", "L"), 8, 256),
    (("hole",), 4, 1024),
    (("band", "hole", "L", "square", "sliver"), 4, 1024),
    (("square", "L", "band", "hole", "sliver", "square"), 16, 8192),
]


@pytest.mark.parametrize("kinds,padding,resolution", CASES)
@pytest.mark.parametrize("rotate", ["any", "90"])
def test_few_charts_certified(kinds, padding, resolution, rotate):
    V, F, uv, lab = _charts(kinds, seed=len(kinds) + padding)
    fast = 2 <= len(kinds) <= few.FEW_MAX
    # (adaptive time where the fast path runs; a short nesting beyond it)
    options = PackOptions(resolution=resolution, padding_px=float(padding), rotate=rotate,
                          solve_seconds=None if fast else 0.2)
    packed = pack_islands(V, F, uv, lab, options)
    check_layout(V, F, uv, lab, packed, options)
    if fast:
        assert packed.solves == 0          # laid out by the fast path, not nested by spyrrow
    if rotate == "90":   # quarter turns only
        assert np.allclose(np.mod(packed.angle + 1e-9, 90.0), 0.0, atol=1e-6)


def test_true_shapes_not_boxes():
    """An L (2x2 less a cell) and a square of 0.9 that fits its notch: packed by shape the pair
    fills its 2x2 box (coverage 3.81 / 4 less the padding); by boxes, at most 3.81 / 2.9^2 =
    0.45."""
    PL, TL = _grid_chart([[1, 0], [1, 1]])
    PS, TS = _grid_chart([[1]])
    PS = PS * 0.9
    V = np.c_[np.concatenate([PL, PS]), np.zeros(len(PL) + len(PS))]
    F = np.concatenate([TL, TS + len(PL)])
    uv = V[F][:, :, :2] + np.array([0.0, 0.0])
    lab = np.r_[np.zeros(len(TL), int), np.ones(len(TS), int)]
    uv[lab == 1] += 5.0                 # apart before packing
    options = PackOptions(resolution=1024, padding_px=2.0)
    packed = pack_islands(V, F, uv, lab, options)
    cert = check_layout(V, F, uv, lab, packed, options)
    assert packed.solves == 0
    assert cert.coverage > 0.9


def test_deterministic():
    V, F, uv, lab = _charts(("band", "L", "hole", "square"), seed=3)
    options = PackOptions(seed=5)
    a = pack_islands(V, F, uv, lab, options)
    b = pack_islands(V, F, uv, lab, options)
    assert np.array_equal(a.corner_uv, b.corner_uv)


def test_no_mirror_on_asymmetric_charts():
    """Turns only: the signed area of every face keeps its sign (an L and a band are not
    symmetric under a flip, so a mirror would show)."""
    V, F, uv, lab = _charts(("L", "band", "L"), seed=7)
    packed = pack_islands(V, F, uv, lab, PackOptions())

    def signed(P):
        e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
        return e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    assert np.all(np.sign(signed(packed.corner_uv)) == np.sign(signed(uv)))


def test_a_search_time_asked_nests_too_and_keeps_the_smaller_square():
    """``solve_seconds`` is not ignored on 2-5 charts: spyrrow nests them too (solves counted)
    and the smaller square is kept, so the coverage is at least the fast path's alone."""
    V, F, uv, lab = _charts(("band", "hole", "L"), seed=11)
    alone = pack_islands(V, F, uv, lab, PackOptions())
    both = pack_islands(V, F, uv, lab, PackOptions(solve_seconds=0.0))
    options = PackOptions(solve_seconds=0.0)
    cert = check_layout(V, F, uv, lab, both, options)
    assert alone.solves == 0 and both.solves >= 1
    ref = check_layout(V, F, uv, lab, alone, PackOptions())
    assert cert.coverage >= ref.coverage * (1 - 1e-9)
