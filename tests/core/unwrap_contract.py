"""Independent checks of the ``bd_uv.unwrap`` contract, shared by the bad-input and fuzz tests.

Nothing here calls ``bd_uv.metrics``: each face's Jacobian is rebuilt from its own orthonormal 3D
frame and the singular values come from ``numpy.linalg.svd``, so a certified island is re-verified
by code that shares no line with the certifier it checks.
"""
import json
import pathlib
import shutil
import tempfile

import numpy as np
from hypothesis import example

import bd_uv
from overlap_shapes import overlapping_triangle_pairs

DATA = pathlib.Path(__file__).resolve().parents[1] / "data"

# bd_uv certifies with a relative tolerance of 1e-6 (metrics.certify); the independent recomputation
# may differ from it by rounding, hence a little more headroom here.
RTOL = 2e-6

ISLAND_ERRORS = (bd_uv.ClosedIslandError, bd_uv.NonManifoldError, bd_uv.DegenerateFacesError,
                 bd_uv.NonFiniteError, bd_uv.TopologyError, bd_uv.OrientationError,
                 bd_uv.DuplicateFacesError, bd_uv.InfeasibleError, bd_uv.SolverError)


def strict_json(text):
    """A report's text parsed as strict JSON: NaN and Infinity (Python's json writes them,
    strict readers refuse them) fail the test, naming the value."""
    def refuse(constant):
        raise AssertionError(f"the JSON report holds {constant}, which is not JSON")
    return json.loads(text, parse_constant=refuse)


def read_off(path):
    """Vertices (n,3) float64 and triangles (m,3) int64 of an OFF file (own reader, no trimesh)."""
    words = []
    for line in pathlib.Path(path).read_text().splitlines():
        words += line.split("#", 1)[0].split()
    assert words[0] == "OFF", path
    n, m = int(words[1]), int(words[2])
    vals = words[4:]
    V = np.array(vals[:3 * n], dtype=np.float64).reshape(n, 3)
    rows = np.array(vals[3 * n:3 * n + 4 * m], dtype=np.int64).reshape(m, 4)
    assert np.all(rows[:, 0] == 3), "triangles only"
    return V, rows[:, 1:].copy()


def face_jacobians_2x2(V, F, corner_uv):
    """Jacobian (m,2,2) of each face's affine map from its own 2D frame to UV.

    The frame of face (p0, p1, p2): x along p1 - p0, y in the face plane towards p2, so corner 2
    always has a positive y and a positive det(J) means the UV triangle keeps the orientation.
    """
    P = np.asarray(V, dtype=np.float64)[F]
    e1 = P[:, 1] - P[:, 0]
    e2 = P[:, 2] - P[:, 0]
    x = e1 / np.linalg.norm(e1, axis=1, keepdims=True)
    n = np.cross(e1, e2)
    y = np.cross(n, e1)
    y /= np.linalg.norm(y, axis=1, keepdims=True)
    X = np.empty((len(F), 2, 2))                    # columns: the two edges in the face frame
    X[:, 0, 0] = np.linalg.norm(e1, axis=1)
    X[:, 1, 0] = 0.0
    X[:, 0, 1] = np.einsum("ij,ij->i", e2, x)
    X[:, 1, 1] = np.einsum("ij,ij->i", e2, y)
    uv = np.asarray(corner_uv, dtype=np.float64)
    U = np.stack([uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]], axis=2)   # columns: UV edges
    return U @ np.linalg.inv(X)


def distortion_and_flips(V, F, corner_uv):
    """Conformal distortion sigma_max / sigma_min per face (inf when flipped) and the flip mask."""
    J = face_jacobians_2x2(V, F, corner_uv)
    s = np.linalg.svd(J, compute_uv=False)
    flipped = ~(np.linalg.det(J) > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        D = s[:, 0] / s[:, 1]
    D[flipped | ~np.isfinite(D)] = np.inf
    return D, flipped


def assert_disk_with_holes(tris, label="island"):
    """The triangles (k,3) form one connected, consistently oriented manifold of genus 0 with at
    least one boundary loop: the only kind of surface that can be flattened without cutting."""
    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import connected_components
    tris = np.asarray(tris, dtype=np.int64)
    nv = int(tris.max()) + 1
    assert len(np.unique(tris)) == nv, f"{label}: unused island vertices"
    assert np.all(tris[:, 0] != tris[:, 1]) and np.all(tris[:, 1] != tris[:, 2]) \
        and np.all(tris[:, 2] != tris[:, 0]), f"{label}: a triangle repeats a vertex"
    assert len(np.unique(np.sort(tris, axis=1), axis=0)) == len(tris), f"{label}: duplicate faces"
    a = tris.ravel()
    b = np.roll(tris, -1, axis=1).ravel()
    directed = np.stack([a, b], 1)
    assert len(np.unique(directed, axis=0)) == len(directed), \
        f"{label}: an edge is used twice in the same direction (orientation flip or non-manifold)"
    undirected, count = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    assert count.max() <= 2, f"{label}: non-manifold edge"
    key = a * nv + b
    boundary = ~np.isin(key, b * nv + a)
    assert boundary.any(), f"{label}: closed"
    deg = np.bincount(a[boundary], minlength=nv) + np.bincount(b[boundary], minlength=nv)
    assert np.all((deg == 0) | (deg == 2)), f"{label}: boundary is not a set of simple loops"
    n_faces_conn, _ = connected_components(coo_array(
        (np.ones(len(a)), (a, b)), shape=(nv, nv)), directed=False)
    assert n_faces_conn == 1, f"{label}: not connected"
    bg = coo_array((np.ones(int(boundary.sum())), (a[boundary], b[boundary])), shape=(nv, nv))
    n_comp, comp = connected_components(bg, directed=False)
    loops = len(np.unique(comp[deg > 0]))
    euler = nv - len(undirected) + len(tris)
    assert euler == 2 - loops, f"{label}: genus {(2 - loops - euler) / 2} with {loops} loops"


def assert_one_simple_disk(V, F, uv, r, island):
    """The one island ``r`` (an ``IslandResult``) of a disk ``island`` (``mesh.Island``) with
    corner UVs ``uv`` (m,3,2): its max and area-weighted mean distortion as reported (recomputed
    by SVD), and its UV boundary one simple polygon, counter-clockwise, whose inside is the
    triangles' union (no overlap: the union's area is the sum of the triangles'; shapely).
    Returns each face's distortion."""
    import pytest
    import shapely
    D, _ = distortion_and_flips(V, F, uv)
    assert D.max() == pytest.approx(r.max_distortion, rel=1e-9)
    area = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    assert r.mean_distortion == pytest.approx((area * D).sum() / area.sum(), rel=1e-9)
    vuv = np.zeros((len(island.vertices), 2))
    vuv[island.tris.ravel()] = uv.reshape(-1, 2)
    ring = shapely.Polygon(vuv[island.loops[0]])
    assert ring.is_valid and ring.exterior.is_ccw
    tris = shapely.polygons(uv)
    union = shapely.union_all(tris)
    assert shapely.area(union) == pytest.approx(shapely.area(tris).sum(), rel=1e-9)
    assert shapely.area(ring) == pytest.approx(shapely.area(union), rel=1e-9)
    return D


def assert_overlap_free(corner_uv, label="island", max_faces=4000):
    """No two UV triangles overlap (independent separating-axis test, overlap_shapes.py); above
    ``max_faces`` the product's boundary check stands in (the pairwise test grows as m^2)."""
    if len(corner_uv) <= max_faces:
        pairs = overlapping_triangle_pairs(corner_uv)
        assert len(pairs) == 0, f"{label}: {len(pairs)} overlapping UV triangle pairs certified"
    else:
        from bd_uv.overlap import island_overlaps
        F = np.arange(3 * len(corner_uv)).reshape(-1, 3)
        ov = island_overlaps(_shared_corners(corner_uv), corner_uv, np.zeros(len(F), int), 1)
        assert ov.overlap_free[0], f"{label}: {int(ov.crossings[0])} boundary crossings certified"


def _shared_corners(corner_uv):
    """Vertex ids for corners: equal UVs, one vertex (the UV-connected mesh)."""
    flat = np.ascontiguousarray(corner_uv.reshape(-1, 2))
    _, ids = np.unique(flat, axis=0, return_inverse=True)
    return ids.reshape(-1, 3)


def snapshot(*arrays):
    """Byte-exact copies of the inputs (None passes through)."""
    return [None if a is None else (np.asarray(a).dtype, np.asarray(a).shape,
                                    np.asarray(a).tobytes()) for a in arrays]


def assert_unchanged(before, *arrays):
    """Every input array is byte-for-byte what it was before the call."""
    after = snapshot(*arrays)
    for i, (b, a) in enumerate(zip(before, after)):
        assert b == a, f"input argument {i} was modified by unwrap"


def assert_contract(res, V, F, pin_corners=None, pin_uv=None):
    """Check an UnwrapResult against the contract; return the island statuses in island order.

    - the islands partition the faces and ``face_island`` agrees with them;
    - a failed island has a typed IslandError naming it, NaN corner UVs and no UV, no bound;
    - a certified island's UVs are finite, match ``corner_uv``, keep every pin exactly, and,
      recomputed independently, have no flipped face and max distortion <= ``bound_certified``;
      its triangles are a consistently oriented disk with holes (so nothing invalid got through);
      one "unfolded" (a lower C sought where its map within C lay over itself) is within the
      numeric bound asked.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    m = len(F)
    assert res.corner_uv.shape == (m, 3, 2) and res.corner_uv.dtype == np.float64
    assert res.face_island.shape == (m,)
    seen = np.zeros(m, dtype=int)
    statuses = []
    for i, isl in enumerate(res.islands):
        assert isl.index == i
        seen[isl.faces] += 1
        assert np.all(res.face_island[isl.faces] == i)
        assert np.array_equal(np.asarray(isl.vertices)[isl.tris], F[isl.faces]), \
            "island triangles do not map back to the input faces"
        statuses.append(isl.status)
        if isl.status == "failed":
            assert isinstance(isl.error, ISLAND_ERRORS), repr(isl.error)
            assert isl.error.island == i
            assert isl.message == str(isl.error) and f"island {i}" in isl.message
            assert isl.uv is None and isl.bound_certified is None
            assert np.all(np.isnan(res.corner_uv[isl.faces])), "a failed island has UVs"
            continue
        assert isl.status == "certified", isl.status
        assert isl.error is None
        assert isl.uv is not None and np.all(np.isfinite(isl.uv))
        cuv = res.corner_uv[isl.faces]
        assert np.array_equal(cuv, isl.uv[isl.tris])
        D, flipped = distortion_and_flips(V, F[isl.faces], cuv)
        assert not flipped.any(), f"island {i}: {int(flipped.sum())} flipped faces certified"
        C = isl.bound_certified
        assert C is not None and np.isfinite(C) and C >= 1.0
        assert D.max() <= C * (1 + RTOL), f"island {i}: max distortion {D.max()} > bound {C}"
        assert np.isclose(isl.max_distortion, D.max(), rtol=1e-5), (isl.max_distortion, D.max())
        assert isl.flipped == 0
        assert_disk_with_holes(isl.tris, f"certified island {i}")
        assert_overlap_free(cuv, f"certified island {i}")
        if hasattr(isl, "overlap_free"):   # IslandResult gains it once the pipeline certifies it
            assert isl.overlap_free is True, f"island {i}: certified but not overlap-free"
        if "unfolded" in (isl.flags or ()):   # a lower C, sought where the map within C overlapped
            assert isl.bound_requested != "auto" and "cut" not in isl.flags
            assert C <= float(isl.bound_requested) * (1 + RTOL), (C, isl.bound_requested)
        assert np.all(np.isfinite(V[F[isl.faces]])), f"island {i}: non-finite vertex certified"
    dup = getattr(res, "duplicate_of", None)
    if dup is not None:
        # seams_mode="needed": a duplicate face is in no island; it carries its twin's island and,
        # vertex by vertex, its twin's UVs
        d = np.flatnonzero(dup >= 0)
        assert np.all(seen[d] == 0), "a duplicate face is in an island"
        seen[d] = 1
        tw = dup[d]
        assert np.all(res.face_island[d] == res.face_island[tw])
        for f, t in zip(d, tw):  # per duplicate face (few)
            assert sorted(F[f]) == sorted(F[t]), "duplicate_of names a face of other vertices"
            for c in range(3):
                j = int(np.flatnonzero(F[t] == F[f, c])[0])
                assert np.array_equal(res.corner_uv[f, c], res.corner_uv[t, j], equal_nan=True)
    assert np.all(seen == 1), "islands do not partition the faces"
    assert res.certified == all(s == "certified" for s in statuses)
    # The JSON report (CLI, batch tool) must be strict JSON: no NaN or inf, whatever failed.
    report = json.loads(json.dumps(res.report(), allow_nan=False))
    assert [r["status"] for r in report["islands"]] == statuses
    if pin_corners is not None and len(pin_corners):
        pc = np.asarray(pin_corners, dtype=np.int64)
        face = pc // 3
        ok = np.isin(res.face_island[face], [i for i, s in enumerate(statuses) if s == "certified"])
        got = res.corner_uv.reshape(-1, 2)[pc[ok]]
        assert np.array_equal(got, np.asarray(pin_uv, dtype=np.float64)[ok]), "pins moved"
    return statuses


def unwrap_checked(V, F, **kw):
    """``bd_uv.unwrap`` with the input-unchanged and result-contract checks around it."""
    args = (V, F, kw.get("seams"), kw.get("pin_corners"), kw.get("pin_uv"), kw.get("initial_uv"))
    before = snapshot(*args)
    try:
        res = bd_uv.unwrap(V, F, **kw)
    finally:
        assert_unchanged(before, *args)
    assert_contract(res, V, F, kw.get("pin_corners"), kw.get("pin_uv"))
    return res


def with_examples(found):
    """A fuzz contract's kept examples (its ``FOUND`` scenarios) run first, in their order, then
    hypothesis's own."""
    def wrap(test):
        for sc in reversed(found):
            test = example(sc=sc)(test)
        return test
    return wrap


def in_fresh_dir(check, sc, prefix):
    """``check(sc, root)`` in a new temporary directory, removed after whatever happens."""
    root = pathlib.Path(tempfile.mkdtemp(prefix=prefix))
    try:
        check(sc, root)
    finally:
        shutil.rmtree(root, ignore_errors=True)
