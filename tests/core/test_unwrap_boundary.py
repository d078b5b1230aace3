"""bd_uv.unwrap(boundary=...) and --boundary: each island's outer boundary on a circle, a rectangle
or its pinned polygon (Lipman 2012, section 5), checked independently of bd_uv's metrics: SVD of
each face's map, the boundary's positions against the shape, UV area against the polygon's area,
and every pair of UV triangles for overlap."""
import argparse
import json
import os

import numpy as np
import pytest

import bd_uv
from bd_uv import batch
from bd_uv.boundary import oriented_loop
from bd_uv.cli import main
from helpers import DATA, load_off, reference_distortion
from overlap_shapes import overlapping_triangle_pairs

NEFERTITI = os.path.join(DATA, "nefertiti.off")


def boundary_vertices(F):
    """Vertices on edges used by one face only."""
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    e, n = np.unique(E, axis=0, return_counts=True)
    return np.unique(e[n == 1])


def area_3d(V, F):
    P = V[F]
    return 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1).sum()


def uv_area(corner_uv):
    e1, e2 = corner_uv[:, 1] - corner_uv[:, 0], corner_uv[:, 2] - corner_uv[:, 0]
    return 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum()


def vertex_uv(V, F, corner_uv):
    """One UV per mesh vertex (the test meshes are single disks), checked consistent."""
    uv = np.full((len(V), 2), np.nan)
    uv[F.ravel()] = corner_uv.reshape(-1, 2)
    assert np.allclose(uv[F], corner_uv, rtol=0, atol=1e-12)
    return uv


def outer_loop(V, F):
    """The boundary loop in mesh vertex ids, faces on its left (counter-clockwise in UV)."""
    isl = bd_uv.islands(V, F)[0]
    return isl.vertices[oriented_loop(isl.tris, isl.loops[0])]


def circle_fit(P):
    """Least-squares circle (Kasa): centre (2,), radius, max |distance - radius|."""
    A = np.column_stack([2 * P, np.ones(len(P))])
    (a, b, c), *_ = np.linalg.lstsq(A, (P ** 2).sum(1), rcond=None)
    R = np.sqrt(c + a * a + b * b)
    return np.array([a, b]), R, np.abs(np.linalg.norm(P - [a, b], axis=1) - R).max()


def check_bijective_disk(V, F, corner_uv, bound):
    """0 flips and distortion <= bound (SVD), 0 overlapping pairs, UV area = 3D area."""
    D, flipped = reference_distortion(V, F, corner_uv)
    assert flipped.sum() == 0
    assert D.max() <= bound * (1 + 1e-6)
    assert len(overlapping_triangle_pairs(corner_uv)) == 0


@pytest.fixture(scope="module")
def nefertiti():
    return load_off("nefertiti.off")


def test_circle(nefertiti):
    V, F = nefertiti
    res = bd_uv.unwrap(V, F, boundary="circle", bound=5.0)
    r = res.islands[0]
    assert res.certified and r.bijective is True and r.summary()["bijective"] is True
    check_bijective_disk(V, F, res.corner_uv, 5.0)
    uv = vertex_uv(V, F, res.corner_uv)
    b = boundary_vertices(F)
    centre, R, off = circle_fit(uv[b])
    assert off < 1e-9 * R                                     # every boundary vertex on it
    assert R == pytest.approx(np.sqrt(area_3d(V, F) / np.pi), rel=1e-9)
    inner = np.setdiff1d(np.arange(len(V)), b)
    assert np.linalg.norm(uv[inner] - centre, axis=1).max() < R
    # The triangles tile the boundary polygon exactly: no fold, no gap.
    P = uv[outer_loop(V, F)]
    shoelace = 0.5 * np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1])
    assert uv_area(res.corner_uv) == pytest.approx(shoelace, rel=1e-9)


def test_rectangle(nefertiti):
    V, F = nefertiti
    res = bd_uv.unwrap(V, F, boundary="rectangle", bound=5.0)
    r = res.islands[0]
    assert res.certified and r.bijective is True
    check_bijective_disk(V, F, res.corner_uv, 5.0)
    uv = vertex_uv(V, F, res.corner_uv)
    P = uv[boundary_vertices(F)]
    lo, hi = P.min(0), P.max(0)
    d = np.abs(np.column_stack([P - lo, P - hi]))             # distance to each of the 4 sides
    assert d.min(1).max() < 1e-12 * (hi - lo).max()
    assert np.all((d < 1e-12 * (hi - lo).max()).sum(0) >= 2)  # every side carries vertices
    w, h = hi - lo
    assert w * h == pytest.approx(area_3d(V, F), rel=1e-9)
    assert uv_area(res.corner_uv) == pytest.approx(w * h, rel=1e-9)  # tiles the rectangle


def test_pinned_polygon_keeps_the_pins(nefertiti):
    V, F = nefertiti
    corners = outer_loop(V, F)[[0, 9, 17, 26]]
    square = np.array([[0, 0], [2, 0], [2, 2], [0, 2]], float)
    face, k = np.nonzero(F == corners[:, None, None])[1:]   # first corner of each pinned vertex
    _, first = np.unique(F[face, k], return_index=True)
    order = np.argsort(np.argsort(corners))                 # match unique's sorted order
    pc = (3 * face + k)[first][order]
    res = bd_uv.unwrap(V, F, boundary="pinned", pin_corners=pc, pin_uv=square, bound=5.0)
    assert res.certified and res.islands[0].bijective is True
    assert np.array_equal(res.corner_uv.reshape(-1, 2)[pc], square)
    check_bijective_disk(V, F, res.corner_uv, 5.0)
    P = vertex_uv(V, F, res.corner_uv)[boundary_vertices(F)]
    side = np.min(np.abs(np.column_stack([P, P - 2])), axis=1)
    assert side.max() < 1e-12 and np.all((P >= -1e-12) & (P <= 2 + 1e-12))


def test_pinned_needs_three_pins_the_island_fails(nefertiti):
    V, F = nefertiti
    res = bd_uv.unwrap(V, F, boundary="pinned", bound=5.0)
    r = res.islands[0]
    assert r.status == "failed" and isinstance(r.error, bd_uv.InfeasibleError)
    assert r.bijective is False and "at least 3" in r.message
    assert np.isnan(res.corner_uv).all()


def test_free_is_unchanged_and_not_claimed_bijective(nefertiti):
    V, F = nefertiti
    a = bd_uv.unwrap(V, F, bound=3.0)
    b = bd_uv.unwrap(V, F, bound=3.0, boundary="free")
    assert np.array_equal(a.corner_uv, b.corner_uv)
    assert a.islands[0].bijective is None and a.islands[0].summary()["bijective"] is None


@pytest.mark.parametrize("kwargs", [dict(boundary="square"), dict(boundary="circle", bound="auto"),
                                    dict(boundary="circle", frames="conformal"),
                                    dict(boundary="circle", seams="auto")])
def test_bad_options(nefertiti, kwargs):
    V, F = nefertiti
    with pytest.raises(ValueError):
        bd_uv.unwrap(V, F, **kwargs)


@pytest.mark.parametrize("boundary,bound", [("free", 1.2), ("circle", 5.0)])
def test_biharmonic_certifies(nefertiti, boundary, bound):
    V, F = nefertiti
    res = bd_uv.unwrap(V, F, method="biharmonic", boundary=boundary, bound=bound)
    r = res.islands[0]
    assert res.certified and res.method == "biharmonic"
    C = r.bound_certified
    assert C >= bound
    check_bijective_disk(V, F, res.corner_uv, C)


def test_cli_boundary_circle_writes_certified_uvs(tmp_path, nefertiti):
    V0, F0 = nefertiti
    out, rep = tmp_path / "n.obj", tmp_path / "n.json"
    assert main(["unwrap", NEFERTITI, "-o", str(out), "--boundary", "circle",
                 "--report", str(rep)]) == 0
    corner = batch_read_uv(out, F0)
    check_bijective_disk(V0, F0, corner, 5.0)
    _, R, off = circle_fit(vertex_uv(V0, F0, corner)[boundary_vertices(F0)])
    assert off < 1e-6 * R                                     # packed, stored as written text
    isl = json.loads(rep.read_text())["islands"][0]
    assert isl["status"] == "certified" and isl["bijective"] is True


def test_batch_boundary_rectangle(tmp_path, nefertiti):
    V0, F0 = nefertiti
    parser = argparse.ArgumentParser()
    batch.add_batch_parser(parser.add_subparsers())
    args = parser.parse_args(["batch", NEFERTITI, "-o", str(tmp_path), "--jobs", "1",
                              "--boundary", "rectangle"])
    assert args.func(args) == 0
    item = json.loads((tmp_path / "report.json").read_text())["items"][0]
    assert item["status"] == "certified" and item["islands"][0]["bijective"] is True
    check_bijective_disk(V0, F0, batch_read_uv(tmp_path / "nefertiti.obj", F0), 5.0)


def batch_read_uv(path, F0):
    """Corner UVs of an OBJ written as ``f v/vt`` with the input's faces in order."""
    vt, fv, ft = [], [], []
    for line in open(path):
        p = line.split()
        if p and p[0] == "vt":
            vt.append([float(t) for t in p[1:3]])
        elif p and p[0] == "f":
            fv.append([int(t.split("/")[0]) - 1 for t in p[1:]])
            ft.append([int(t.split("/")[1]) - 1 for t in p[1:]])
    assert np.array_equal(np.array(fv), F0)
    return np.array(vt)[np.array(ft)]


def holed_domain(outer):
    """A bumpy disk ("circle") or square of half-width 1 with two holes (Triangle):
    (V (n,3), F, outer boundary vertex ids)."""
    from planar import circle, mesh_polygon, square
    holes = [circle(12, 0.3, (0.2, 0.1))[::-1], circle(10, 0.2, (-0.5, -0.4))[::-1]]
    poly = circle(40) if outer == "circle" else square(8)
    V2, F = mesh_polygon(poly, holes, [[0.2, 0.1], [-0.5, -0.4]], area=0.01)
    V = np.column_stack([V2, 0.3 * np.exp(-2 * (V2 ** 2).sum(1))])
    b = boundary_vertices(F)
    far = np.linalg.norm(V2[b], axis=1) if outer == "circle" else np.abs(V2[b]).max(1)
    return V, F, b[far > 0.9]  # the holes reach 0.84 from the centre at most


@pytest.mark.parametrize("shape", ["circle", "rectangle"])
def test_holes_stay_free_inside_the_target(shape):
    V, F, outer = holed_domain(shape)
    res = bd_uv.unwrap(V, F, boundary=shape, bound=5.0)
    r = res.islands[0]
    assert res.certified and r.bijective is True and r.bound_certified == 5.0
    assert len(bd_uv.islands(V, F)[0].loops) == 3
    check_bijective_disk(V, F, res.corner_uv, 5.0)
    uv = vertex_uv(V, F, res.corner_uv)
    hole = np.setdiff1d(boundary_vertices(F), outer)
    if shape == "circle":
        centre, R, off = circle_fit(uv[outer])
        assert off < 1e-9 * R and R == pytest.approx(np.sqrt(area_3d(V, F) / np.pi), rel=1e-9)
        assert np.linalg.norm(uv[hole] - centre, axis=1).max() < R  # holes inside, not on it
    else:
        lo, hi = uv[outer].min(0), uv[outer].max(0)
        d = np.abs(np.column_stack([uv[outer] - lo, uv[outer] - hi])).min(1)
        assert d.max() < 1e-12 * (hi - lo).max()
        assert np.all((uv[hole] > lo) & (uv[hole] < hi))
    # the triangles cover the target minus the holes: less UV area than the target's
    assert uv_area(res.corner_uv) < area_3d(V, F) * (1 + 1e-9)


def test_a_hole_stays_a_hole_under_a_rectangle():
    """A disk's boundary on a rectangle with two holes: before the holes were filled during the
    solve, a hole crossed the outer boundary here (Theorem 5.2's premises failed, the island was
    cut). Filled with orientation-preserving triangles, the disk maps bijectively (Theorem 5.1),
    so the holes stay inside: one bijective island, 0 overlapping pairs."""
    V, F, outer = holed_domain("circle")
    for overlap in ("cut", "fail"):
        res = bd_uv.unwrap(V, F, boundary="rectangle", bound=5.0, overlap=overlap)
        (r,) = res.islands
        assert res.certified and r.bijective is True and "cut" not in r.flags
        check_bijective_disk(V, F, res.corner_uv, 5.0)
    uv = vertex_uv(V, F, res.corner_uv)
    hole = np.setdiff1d(boundary_vertices(F), outer)
    lo, hi = uv[outer].min(0), uv[outer].max(0)
    assert np.all((uv[hole] > lo) & (uv[hole] < hi))


def test_every_island_gets_its_own_circle(nefertiti):
    V, F = nefertiti
    V2 = np.concatenate([V, V + [10.0, 0, 0]])
    F2 = np.concatenate([F, F + len(V)])
    res = bd_uv.unwrap(V2, F2, boundary="circle", bound=5.0)
    assert res.certified and [r.bijective for r in res.islands] == [True, True]
    for r in res.islands:
        P = r.uv[np.isin(r.vertices, boundary_vertices(F2))]
        _, R, off = circle_fit(P)
        assert off < 1e-9 * R
        assert R == pytest.approx(np.sqrt(area_3d(V, F) / np.pi), rel=1e-9)


def test_cancel(nefertiti):
    V, F = nefertiti

    class Later:  # set after a few checks: inside the fixed-boundary solve
        n = 0

        def is_set(self):
            self.n += 1
            return self.n > 3
    with pytest.raises(bd_uv.CancelledError):
        bd_uv.unwrap(V, F, boundary="circle", cancel=Later())


def test_premises_sweep_keeps_every_pair_whose_boxes_meet():
    """bijectivity_premises tests only segment pairs whose bounding boxes meet (a sweep, so long
    boundaries stay cheap); recomputed here over all pairs, on grid-snapped segments with ties."""
    from bd_uv.bijectivity import _box_pairs
    rng = np.random.default_rng(3)
    P = np.round(rng.uniform(0, 4, (300, 2)))
    Pn = np.round(P + rng.uniform(-1.5, 1.5, (300, 2)))
    lo, hi = np.minimum(P, Pn), np.maximum(P, Pn)
    i, j = np.triu_indices(len(P), 1)
    meet = np.all((lo[i] <= hi[j]) & (lo[j] <= hi[i]), axis=1)
    want = {(a, b) for a, b in zip(i[meet].tolist(), j[meet].tolist())}
    a, b = _box_pairs(P, Pn)
    got = list(zip(a.tolist(), b.tolist()))
    assert len(got) == len(set(got)) and set(got) == want


def test_rectangle_corners_from_four_pins_are_flagged_as_moved(nefertiti):
    V, F = nefertiti
    corners = outer_loop(V, F)[[2, 11, 19, 28]]
    pc = np.array([3 * np.argwhere(F == v)[0][0] + np.argwhere(F == v)[0][1] for v in corners])
    res = bd_uv.unwrap(V, F, boundary="rectangle", pin_corners=pc, pin_uv=np.zeros((4, 2)),
                       bound=5.0)
    r = res.islands[0]
    assert res.certified and r.bijective is True and "boundary_pins_moved" in r.flags
    got = res.corner_uv.reshape(-1, 2)[pc]                  # the rectangle's four corners
    lo, hi = got.min(0), got.max(0)
    assert {tuple(np.isclose(g, hi, rtol=0, atol=1e-12)) for g in got} == \
        {(False, False), (True, False), (True, True), (False, True)}
    assert np.allclose(lo, 0, atol=1e-12)
    check_bijective_disk(V, F, res.corner_uv, 5.0)


def test_a_face_with_three_corners_on_the_circle_raises_c_at_once():
    """A grid's lone corner triangle has all three corners on the boundary: on the circle its
    distortion is fixed by the targets, so C starts there instead of failing step by step."""
    from helpers import grid
    V, F = grid(8, 7, lambda x, y: 0.1 * x * y)
    b = boundary_vertices(F)
    lone = np.flatnonzero(np.isin(F, b).all(axis=1))
    assert len(lone) == 2                                    # the two single-triangle corners
    r = bd_uv.unwrap(V, F, boundary="circle", bound=1.5, raise_bound=False).islands[0]
    assert r.status == "failed" and isinstance(r.error, bd_uv.InfeasibleError)
    assert "all three corners" in r.message and r.bijective is False
    res = bd_uv.unwrap(V, F, boundary="circle", bound=1.5)
    r = res.islands[0]
    assert res.certified and r.bijective is True and "bound_raised" in r.flags
    D, flipped = reference_distortion(V, F, res.corner_uv)
    assert not flipped.any() and D.max() <= r.bound_certified * (1 + 1e-6)
    assert D[lone].max() > 1.5 and r.bound_certified <= 1.03 * D[lone].max()
    assert len(overlapping_triangle_pairs(res.corner_uv)) == 0
