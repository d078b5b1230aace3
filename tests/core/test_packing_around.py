"""Pinned charts stay bit for bit and the rest pack into the free space around their shapes;
charts grouped by material or object pack as one region per group. Every figure is recomputed
here by code that shares nothing with the packer (``packing_checks``: exact triangle overlap
test, brute-force edge distances, densities and turns from the corners)."""
import numpy as np
import pytest
import shapely

from bd_uv.errors import PackError
from bd_uv.packing import PackOptions, pack_islands
from bd_uv.packing.around import pinned_cells
from overlap_shapes import overlapping_triangle_pairs
from packing_checks import check_layout
from packing_sets import chart_set, least_gap


def _pin_ring(uv, lab, charts):
    """Put ``charts`` on a ring of the square (an L along the bottom and the left, and one in the
    middle): the free space left is no square, so the bounding-box method wastes most of it."""
    spots = [((0.02, 0.02), 0.3), ((0.4, 0.02), 0.3), ((0.02, 0.4), 0.3), ((0.45, 0.45), 0.12)]
    for c, (at, size) in zip(charts, spots):
        P = uv[lab == c]
        lo, hi = P.reshape(-1, 2).min(0), P.reshape(-1, 2).max(0)
        uv[lab == c] = (P - lo) * (size / (hi - lo).max()) + at
    return uv


@pytest.mark.parametrize("kind, k, res, pad, rotate", [
    ("boxes", 16, 512, 6, "any"),
    ("holes", 10, 1024, 4, "90"),
    ("slivers", 12, 2048, 8, "none"),
])
def test_pinned_charts_keep_their_uvs_and_the_rest_fill_around_them(kind, k, res, pad, rotate):
    V, F, uv, lab = chart_set(kind, k, seed=k + 1)
    uv = _pin_ring(uv, lab, [0, 1, 2, 3])
    pinned = np.zeros(k, bool)
    pinned[:4] = True
    before = uv.copy()
    options = PackOptions(resolution=res, padding_px=pad, rotate=rotate, solve_seconds=1)
    packed = pack_islands(V, F, uv, lab, options, pinned=pinned)
    assert np.array_equal(uv, before)                                  # input untouched
    keep = pinned[lab]
    # bit for bit, compared as bytes
    assert packed.corner_uv[keep].tobytes() == before[keep].tobytes()
    check_layout(V, F, uv, lab, packed, options, pinned=pinned)
    # the moving charts are apart from the pinned ones by an exact test: no triangle of one
    # meets a triangle of the other (separating axes) and the least gap is the padding
    out = packed.corner_uv.astype(np.float32).astype(np.float64)
    pairs = overlapping_triangle_pairs(out)
    assert not np.any(keep[pairs[:, 0]] != keep[pairs[:, 1]])
    mixed = np.where(keep, 0, 1)
    assert least_gap(out, mixed, reach=2 * pad / res + 1e-9) * res >= pad * (1 - 1e-4)
    # and they use the free space beside the pinned charts: some lie in the L's bay, where the
    # largest free square beside the pinned boxes (x, y >= 0.57) never reaches
    moved_lo = np.array([out[lab == c].reshape(-1, 2).min(0) for c in range(4, k)])
    assert (moved_lo.min(axis=1) < 0.5).any()


def test_around_pinned_covers_more_than_the_largest_free_square():
    """Twenty boxes, four pinned on a ring: the density of the moved charts beats the previous
    method's (every moved chart in the largest square beside the pinned boxes: at most that
    square's side / sqrt(moving area), whatever the nesting)."""
    V, F, uv, lab = chart_set("boxes", 20, seed=4)
    uv = _pin_ring(uv, lab, [0, 1, 2, 3])
    pinned = np.zeros(20, bool)
    pinned[:4] = True
    options = PackOptions(resolution=1024, padding_px=4, solve_seconds=1)
    packed = pack_islands(V, F, uv, lab, options, pinned=pinned)
    check_layout(V, F, uv, lab, packed, options, pinned=pinned)
    P = V[F]
    a3 = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    moving_area = a3[~pinned[lab]].sum()
    # the largest free square beside the boxes: x >= 0.57 or y >= 0.57 with the padding
    side = 1 - 0.57 - 4 / 1024
    assert packed.texel_density / 1024 > 1.2 * side / np.sqrt(moving_area)


def test_pinned_cells_hold_every_cell_within_half_the_padding():
    """The raster is conservative: every cell centre within half the padding (plus half a cell's
    diagonal) of a pinned triangle is occupied, measured by brute force."""
    tri = shapely.Polygon([(0.2, 0.2), (0.7, 0.3), (0.3, 0.8)])
    n, pad = 64, 0.05
    occ = pinned_cells(tri, pad, n)
    c = (np.arange(n) + 0.5) / n
    x, y = np.meshgrid(c, c)
    d = shapely.distance(tri, shapely.points(x, y))
    assert np.all(occ[d <= 0.5 * pad + np.sqrt(0.5) / n])


def _groups_apart(out, lab, group_of_chart, pad, res):
    """Each group's convex hull: no chart of another group enters it, and hulls are at least
    the padding apart (shapely, exact on the float64 coordinates)."""
    g = group_of_chart[lab]
    names = np.unique(g)
    hulls = [shapely.convex_hull(shapely.multipoints(out[g == b].reshape(-1, 2)))
             for b in names]
    for a in range(len(hulls)):
        for b in range(a + 1, len(hulls)):
            assert hulls[a].distance(hulls[b]) * res >= pad * (1 - 1e-4)
    for b, hull in zip(names, hulls):
        others = shapely.polygons(out[g != b])
        assert not shapely.intersects(hull, others).any()


@pytest.mark.parametrize("kind, k, groups, res, pad, rotate, density", [
    ("boxes", 24, 3, 1024, 4, "any", None),
    ("holes", 12, 2, 512, 8, "90", None),
    ("slivers", 15, 4, 2048, 6, "none", None),
    ("boxes", 30, 3, 1024, 4, "any", 60.0),
    ("boxes", 30, 10, 1024, 4, "any", None),        # many groups: columns in rows
    ("huge_tiny", 9, 6, 2048, 2, "90", None),        # groups of one chart (no nesting)
])
def test_grouped_charts_pack_one_region_per_group(kind, k, groups, res, pad, rotate, density):
    V, F, uv, lab = chart_set(kind, k, seed=k + groups)
    rng = np.random.default_rng(k)
    chart_group = rng.permutation(np.arange(k) % groups)
    material = (10 * chart_group + 3)[lab]            # any labels: not 0..g-1
    options = PackOptions(resolution=res, padding_px=pad, rotate=rotate, group="material",
                          texel_density=density, udim=density is not None, solve_seconds=1)
    packed = pack_islands(V, F, uv, lab, options, face_labels={"material": material})
    tiles = sorted(set(packed.tile.tolist()))
    check_layout(V, F, uv, lab, packed, options, tiles=tiles)
    out = packed.corner_uv.astype(np.float32).astype(np.float64)
    for t in tiles:   # per tile, each group's charts form one region
        on = np.isin(lab, np.flatnonzero(packed.tile == t))
        sub = np.where(on, lab, -1)
        present = np.unique(chart_group[lab[on]])
        if len(present) > 1:
            _groups_apart(out[on], sub[on], chart_group, pad, res)
    if density is None:
        _groups_apart(out, lab, chart_group, pad, res)
        # fitted to the square, each group is a column: the groups' bounding boxes are apart
        g = chart_group[lab]
        boxes = [(out[g == b].reshape(-1, 2).min(0), out[g == b].reshape(-1, 2).max(0))
                 for b in range(groups)]
        for a in range(groups):
            for b in range(a + 1, groups):
                (lo_a, hi_a), (lo_b, hi_b) = boxes[a], boxes[b]
                apart = np.maximum(lo_b - hi_a, lo_a - hi_b).max()
                assert apart * res >= pad * (1 - 1e-4)


def test_a_chart_across_two_materials_goes_with_most_of_its_area():
    V, F, uv, lab = chart_set("boxes", 6, seed=2)
    material = np.where(lab < 3, 0, 1)
    material[lab == 0] = np.r_[1, 0]                  # chart 0's two triangles: one each
    V = V.copy()
    V[F[lab == 0][0, 1], 2] += 5.0    # its triangle of material 1 made larger in 3D
    P = V[F[lab == 0]]
    a3 = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    assert a3[0] > 2 * a3[1]
    options = PackOptions(group="material", solve_seconds=0)
    packed = pack_islands(V, F, uv, lab, options, face_labels={"material": material})
    check_layout(V, F, uv, lab, packed, options)
    _groups_apart(packed.corner_uv, lab, np.array([1, 0, 0, 1, 1, 1]), 4, 1024)


def test_grouping_needs_the_faces_groups_and_refuses_pins_and_bad_names():
    V, F, uv, lab = chart_set("boxes", 4, seed=3)
    with pytest.raises(PackError, match="needs each face's object"):
        pack_islands(V, F, uv, lab, PackOptions(group="object"))
    with pytest.raises(PackError, match="needs each face's material"):
        pack_islands(V, F, uv, lab, PackOptions(group="material"), face_labels={"object": lab})
    with pytest.raises(PackError, match="group must be one of"):
        PackOptions(group="colour")
    uv = _pin_ring(uv, lab, [0])
    with pytest.raises(PackError, match="not grouped around pinned"):
        pack_islands(V, F, uv, lab, PackOptions(group="object"), face_labels={"object": lab},
                     pinned=np.array([True, False, False, False]))
    # one group is the same as no grouping: accepted, one region
    one = pack_islands(V, F, uv, lab, PackOptions(group="object", solve_seconds=0),
                       face_labels={"object": np.zeros(len(lab), int)})
    check_layout(V, F, uv, lab, one, PackOptions())


def test_the_free_square_is_kept_when_the_raster_reaches_less(monkeypatch):
    """On a 16-cell grid the raster wastes most of the room (whole cells of 1/16): the largest
    free square beside the pinned box (nested by spyrrow) reaches further and is kept; the layout
    is certified the same way and the pinned chart stays bit for bit."""
    import bd_uv.packing.around as around
    V, F, uv, lab = chart_set("boxes", 8, seed=6)
    P = uv[lab == 0]
    lo, hi = P.reshape(-1, 2).min(0), P.reshape(-1, 2).max(0)
    uv[lab == 0] = (P - lo) * (0.2 / (hi - lo).max()) + 0.01       # small, in a corner
    pinned = np.zeros(8, bool)
    pinned[0] = True
    options = PackOptions(resolution=1024, padding_px=4, solve_seconds=0.5)
    fine = pack_islands(V, F, uv, lab, options, pinned=pinned)
    monkeypatch.setattr(around, "GRIDS", (16,))
    coarse = pack_islands(V, F, uv, lab, options, pinned=pinned)
    check_layout(V, F, uv, lab, coarse, options, pinned=pinned)
    check_layout(V, F, uv, lab, fine, options, pinned=pinned)
    assert coarse.solves >= 1              # spyrrow's free square, not the raster (0 solves)
    assert fine.texel_density > 0 and coarse.texel_density > 0
