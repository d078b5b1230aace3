"""pack_islands: every island in the unit square, one common scale, no two islands overlapping
(checked with layout_overlaps and the independent triangle test)."""
import numpy as np
import pytest

from bd_uv.overlap import layout_overlaps
from bd_uv.pack import island_boxes, pack_islands
from overlap_shapes import overlapping_triangle_pairs


def boxes(k, seed=0):
    rng = np.random.default_rng(seed)
    base = np.array([[[0, 0], [1, 0], [1, 1]], [[0, 0], [1, 1], [0, 1]]], float)
    size = rng.uniform(0.05, 3.0, (k, 2))
    where = rng.uniform(-5, 5, (k, 2))           # islands start anywhere, overlapping
    uv = (base[None] * size[:, None, None, :] + where[:, None, None, :]).reshape(-1, 3, 2)
    return uv, np.repeat(np.arange(k), 2)


@pytest.mark.parametrize("k, margin", [(1, 0.005), (7, 0.001), (60, 0.01), (300, 0.002)])
def test_packed_islands_fit_do_not_overlap_and_keep_relative_scale(k, margin):
    uv, lab = boxes(k)
    if k <= 60:  # before packing, layout_overlaps agrees with the independent triangle test
        tri = lab[overlapping_triangle_pairs(uv)]
        tri = {(int(a), int(b)) for a, b in np.sort(tri, axis=1) if a != b}
        assert {tuple(p) for p in layout_overlaps(uv, lab).tolist()} == tri
    out = pack_islands(uv, lab, margin=margin)
    assert out.min() >= margin * (1 - 1e-6) - 1e-12 and out.max() <= 1 - margin + 1e-9
    assert len(layout_overlaps(out, lab)) == 0
    if k <= 60:
        assert len(overlapping_triangle_pairs(out)) == 0
    # one common scale and a translation per island: edge vectors all scale by the same s
    e_in = uv[:, 1] - uv[:, 0]
    e_out = out[:, 1] - out[:, 0]
    s = np.linalg.norm(e_out, axis=1) / np.linalg.norm(e_in, axis=1)
    assert np.allclose(s, s[0], rtol=1e-9)
    assert np.allclose(e_out, s[0] * e_in, rtol=1e-9, atol=1e-12)
    # margins between islands: boxes are at least (almost) ``margin`` apart
    lo, hi = island_boxes(out, lab)
    i, j = np.triu_indices(k, 1)
    gap = np.maximum(lo[j] - hi[i], lo[i] - hi[j]).max(axis=1)
    assert k == 1 or gap.min() >= margin * (1 - 1e-6) - 1e-12
    # a reasonable use of the square (shelf packing of random boxes)
    if k >= 60:
        assert ((hi - lo).prod(axis=1)).sum() > 0.5


def test_unlabelled_and_nan_faces_are_left_alone():
    uv, lab = boxes(3)
    lab = lab.copy()
    lab[0] = -1
    uv[2] = np.nan
    out = pack_islands(uv, lab)
    assert np.array_equal(out[0], uv[0]) and np.isnan(out[2]).all()
    assert np.isfinite(out[lab >= 0][3:]).all()


def test_bad_margin():
    uv, lab = boxes(2)
    with pytest.raises(ValueError):
        pack_islands(uv, lab, margin=0.5)
