"""Bad input, faults and cancellation (issue 6, core part): every case ends in a certified island or a
typed error whose message names the problem and what to do, the input arrays come back
byte-for-byte unchanged, and no uncertified UV is ever returned.

Each result goes through ``unwrap_contract.assert_contract``, which re-verifies every certified island
with its own Jacobians and SVDs (not ``bd_uv.metrics``) and checks that failed islands are NaN.
"""
import re
import sys
import threading
import types
import warnings

import clarabel

import numpy as np
import pytest

import bd_uv
import bd_uv.solvers.bound_search
import bd_uv.solvers.conic
import bd_uv.unwrapping.strategies
from bd_uv.solvers.conic import ConicSolution
from unwrap_contract import (DATA, assert_unchanged, distortion_and_flips, read_off, snapshot,
                             unwrap_checked)

# The module that defines unwrap() (bd_uv/unwrapping/unwrap.py): found from the function, not by name.
PIPELINE = sys.modules[bd_uv.unwrapping.unwrap.__module__]


# ---------------------------------------------------------------------------------------------
# Small meshes, built so each case is checkable by hand
# ---------------------------------------------------------------------------------------------

def grid(nx=4, ny=4, size=1.0, bump=0.1):
    """A gently curved square patch: (nx+1)(ny+1) vertices, 2 nx ny counter-clockwise triangles.
    Vertex (i, j) has index j (nx+1) + i; face 2 (j nx + i) and the next one fill square (i, j)."""
    xs, ys = np.meshgrid(np.linspace(0, size, nx + 1), np.linspace(0, size, ny + 1))
    x, y = xs.ravel(), ys.ravel()
    V = np.stack([x, y, bump * np.sin(3 * x) * np.cos(2 * y)], axis=1)
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    a = (j * (nx + 1) + i).ravel()
    b, c, d = a + 1, a + nx + 2, a + nx + 1
    F = np.stack([np.stack([a, b, c], 1), np.stack([a, c, d], 1)], 1).reshape(-1, 3)
    return V, F.astype(np.int64)


def torus(nu=12, nv=8, R=2.0, r=0.7):
    """Closed torus; vertex (i, j) has index i nv + j, j running around the tube."""
    u, v = np.meshgrid(np.arange(nu) * 2 * np.pi / nu, np.arange(nv) * 2 * np.pi / nv,
                       indexing="ij")
    V = np.stack([(R + r * np.cos(v)) * np.cos(u), (R + r * np.cos(v)) * np.sin(u),
                  r * np.sin(v)], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    idx = lambda i, j: (i % nu) * nv + (j % nv)
    a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
    F = np.stack([np.stack([a, b, c], -1), np.stack([a, c, d], -1)], -2).reshape(-1, 3)
    return V, F.astype(np.int64)


def annulus(n=8):
    """Flat ring: outer vertices 0..n-1, inner n..2n-1, segment j = faces 2j, 2j+1."""
    t = np.arange(n) * 2 * np.pi / n
    V = np.concatenate([np.stack([2 * np.cos(t), 2 * np.sin(t), 0 * t], 1),
                        np.stack([np.cos(t + 0.2), np.sin(t + 0.2), 0 * t], 1)])
    j = np.arange(n)
    o0, o1, i0, i1 = j, (j + 1) % n, n + j, n + (j + 1) % n
    F = np.stack([np.stack([o0, o1, i0], 1), np.stack([i0, o1, i1], 1)], 1).reshape(-1, 3)
    return V, F.astype(np.int64)


def tetrahedron():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
    F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], dtype=np.int64)
    return V, F


def combine(*parts, gap=5.0):
    """Disjoint union of meshes, each shifted along x so they do not overlap."""
    Vs, Fs, off = [], [], 0
    for k, (V, F) in enumerate(parts):
        Vs.append(V + [k * gap, 0.0, 0.0])
        Fs.append(F + off)
        off += len(V)
    return np.concatenate(Vs), np.concatenate(Fs)


def nefertiti():
    return read_off(DATA / "nefertiti.off")


def area3d(V, F):
    P = V[F]
    return 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1).sum()


def uv_area(corner_uv):
    e1 = corner_uv[:, 1] - corner_uv[:, 0]
    e2 = corner_uv[:, 2] - corner_uv[:, 0]
    return 0.5 * np.sum(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])


def assert_message(text, *words):
    low = text.lower()
    missing = [w for w in words if w.lower() not in low]
    assert not missing, f"message {text!r} lacks {missing}"


def raises_unchanged(exc_type, V, F, **kw):
    """The call raises exactly ``exc_type`` (not a subclass stand-in) and changes no input."""
    args = (V, F, kw.get("seams"), kw.get("pin_corners"), kw.get("pin_uv"))
    before = snapshot(*args)
    with pytest.raises(exc_type) as info:
        bd_uv.unwrap(V, F, **kw)
    assert type(info.value) is exc_type
    assert_unchanged(before, *args)
    return info.value


# ---------------------------------------------------------------------------------------------
# Mesh-level problems: InvalidMeshError, nothing computed
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("V, F", [
    (np.zeros((0, 3)), np.zeros((0, 3), np.int64)),
    (np.eye(3), np.zeros((0, 3), np.int64)),
    (np.eye(3), np.zeros(0, np.int64)),
], ids=["no-vertices-no-faces", "vertices-no-faces", "flat-empty-face-array"])
def test_empty_mesh_raises_invalid_mesh(V, F):
    err = raises_unchanged(bd_uv.InvalidMeshError, V, F)
    assert_message(str(err), "no faces", "nothing to unwrap")


@pytest.mark.parametrize("bad", ["n", -1, 10**12])
def test_face_index_out_of_range_raises_invalid_mesh(bad):
    V, F = grid()
    F = F.copy()
    F[5, 1] = len(V) if bad == "n" else bad
    F[9, 2] = len(V) if bad == "n" else bad
    err = raises_unchanged(bd_uv.InvalidMeshError, V, F)
    assert_message(str(err), "2 face(s)", "outside", f"0..{len(V) - 1}", "faces 5, 9",
                   "fix the face list")


@pytest.mark.parametrize("case", ["quads", "2d-vertices", "fractional-index", "nan-index",
                                  "text-vertices", "complex-vertices", "text-index"])
def test_wrong_shapes_and_types_raise_invalid_mesh(case):
    V, F = grid()
    if case == "quads":
        F, words = np.concatenate([F, F[:, :1]], axis=1), ("(m,3)", "triangulate")
    elif case == "2d-vertices":
        V, words = V[:, :2].copy(), ("(n,3)",)
    elif case == "fractional-index":
        F, words = F.astype(np.float64) + 0.5, ("integers",)
    elif case == "text-vertices":       # issue 22: was a ValueError from numpy, not typed
        V, words = V.astype(str), ("vertex coordinates", "real numbers")
    elif case == "complex-vertices":    # was certified with the imaginary parts dropped
        V, words = V + 1j, ("vertex coordinates", "real numbers")
    elif case == "text-index":
        F, words = F.astype(str), ("face indices", "real numbers")
    else:
        F = F.astype(np.float64)
        F[0, 0] = np.nan
        words = ("integers",)
    err = raises_unchanged(bd_uv.InvalidMeshError, V, F)
    assert_message(str(err), *words)


@pytest.mark.parametrize("case", ["corner-out-of-range", "negative-corner", "nan-pin-uv",
                                  "fewer-pin-uvs", "three-columns", "no-pin-uv",
                                  "fractional-corner", "nan-corner", "text-pin-uv"])
def test_bad_pins_raise_invalid_mesh(case):
    """Issue 22: pins whose arrays do not match (a count, a shape, None, a fraction, text) were a
    ValueError from numpy or from a length check, not a typed error; a fractional corner index
    was truncated to the corner before it."""
    V, F = grid()
    corners = np.array([0, 3 * len(F) if case == "corner-out-of-range" else
                        (-1 if case == "negative-corner" else 5)])
    uv = np.array([[0.0, 0.0], [np.nan if case == "nan-pin-uv" else 1.0, 1.0]])
    if case == "fewer-pin-uvs":
        uv = uv[:1]
    elif case == "three-columns":
        uv = np.zeros((2, 3))
    elif case == "no-pin-uv":
        uv = None
    elif case == "fractional-corner":
        corners = np.array([0.0, 5.5])
    elif case == "nan-corner":
        corners = np.array([0.0, np.nan])
    elif case == "text-pin-uv":
        uv = uv.astype(str)
    err = raises_unchanged(bd_uv.InvalidMeshError, V, F, pin_corners=corners, pin_uv=uv)
    assert_message(str(err), "pin")


@pytest.mark.parametrize("seams", [np.zeros((2, 3), int), np.ones(5, bool), [[0.5, 1.5]],
                                   [[np.nan, 1.0]], [["0", "1"]]])
def test_malformed_seams_raise_invalid_mesh(seams):
    """Issue 22: seams that are not (s,2) integer vertex pairs were cut silently into pairs,
    truncated to integers (NaN to a garbage index), or a ValueError from numpy."""
    V, F = grid()
    seams = np.asarray(seams)
    before = snapshot(V, F, seams)
    with pytest.raises(bd_uv.InvalidMeshError) as info:
        bd_uv.unwrap(V, F, seams=seams)
    assert_message(str(info.value), "seam")
    assert_unchanged(before, V, F, seams)


# ---------------------------------------------------------------------------------------------
# Smallest inputs
# ---------------------------------------------------------------------------------------------

def test_one_triangle_is_certified_conformal_with_its_3d_area():
    V = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 1.0], [0.3, 1.5, -0.4]])
    F = np.array([[0, 1, 2]])
    res = unwrap_checked(V, F)
    (isl,) = res.islands
    assert isl.status == "certified" and isl.bound_certified == 5.0
    D, _ = distortion_and_flips(V, F, res.corner_uv)
    assert D[0] == pytest.approx(1.0, abs=1e-9)                  # a triangle maps without shear
    assert uv_area(res.corner_uv) == pytest.approx(area3d(V, F), rel=1e-9)
    assert np.allclose(res.corner_uv.reshape(-1, 2).min(axis=0), 0.0, atol=1e-12)


def test_single_face_island_next_to_a_real_mesh():
    Vn, Fn = nefertiti()
    tri = (np.array([[0.0, 0.0, 0.0], [1.0, 0.2, 0.0], [0.1, 0.9, 0.3]]), np.array([[0, 1, 2]]))
    V, F = combine((Vn, Fn), tri, gap=20.0)
    res = unwrap_checked(V, F)
    assert [len(i.faces) for i in res.islands] == [len(Fn), 1]
    assert [i.status for i in res.islands] == ["certified", "certified"]
    single = res.islands[1]
    D, _ = distortion_and_flips(V, F[single.faces], res.corner_uv[single.faces])
    assert D[0] == pytest.approx(1.0, abs=1e-9)


# ---------------------------------------------------------------------------------------------
# Island-level problems: the island fails with a typed error, the others are still solved
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf, 1e300, -1e160])
def test_non_finite_coordinates_fail_only_their_island(value):
    """1e300 and 1e160 are finite, but a face's squared edges or area overflow: caught with NaN
    and inf in mesh.islands, not reported as a zero-area face."""
    V, F = combine(grid(), grid())
    V = V.copy()
    V[6, 1] = value
    res = unwrap_checked(V, F)
    bad, good = res.islands
    assert type(bad.error) is bd_uv.NonFiniteError and good.status == "certified"
    uses6 = np.flatnonzero(np.any(F == 6, axis=1))
    assert np.array_equal(np.sort(bad.error.faces), uses6)
    assert_message(bad.message, "island 0", "NaN or infinite", "fix or delete")


@pytest.mark.parametrize("value", [np.inf, -np.inf])
def test_non_finite_one_disk_fails_without_numpy_warnings(value):
    """A mesh that is one disk takes the one-disk path first (glTF's BoxWithInfinites.glb is one):
    two infinite coordinates on one edge (inf - inf is NaN) are refused by name, with no numpy
    RuntimeWarning printed on the way."""
    V, F = grid()
    V = V.copy()
    V[[6, 7], 1] = value
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        res = unwrap_checked(V, F)
    (bad,) = res.islands
    assert type(bad.error) is bd_uv.NonFiniteError
    uses = np.flatnonzero(np.any((F == 6) | (F == 7), axis=1))
    assert np.array_equal(np.sort(bad.error.faces), uses)


def test_non_finite_unreferenced_vertex_is_harmless():
    V, F = grid()
    V = np.concatenate([V, [[np.nan, np.inf, 0.0]]])
    res = unwrap_checked(V, F)
    assert res.certified


@pytest.mark.parametrize("face", [0, 10], ids=["boundary-face", "interior-face"])
@pytest.mark.parametrize("reverse", [False, True], ids=["same-order", "reversed"])
def test_duplicate_face_in_a_mesh(face, reverse):
    V, F = grid()
    dup = F[face, ::-1] if reverse else F[face]
    F = np.concatenate([F, [dup]])
    res = unwrap_checked(V, F)
    pair = [face, len(F) - 1]
    # Face 0 keeps one edge with exactly two faces (itself and its copy), so the pair is one island;
    # interior face 10 has three faces on each edge and its copy ends up an island of its own.
    dup_islands = {int(res.face_island[f]) for f in pair}
    assert len(dup_islands) == (1 if face == 0 else 2)
    found = []
    for i in dup_islands:
        isl = res.islands[i]
        assert type(isl.error) is bd_uv.DuplicateFacesError
        assert_message(isl.message, "repeat the same three vertices", "merge or delete")
        found += isl.error.faces.tolist()
    assert sorted(found) == pair
    # The duplicate's edges now have three faces each: the rest of the patch cannot be flattened
    # through them and reports it as such, with nothing written.
    others = [i for i in res.islands if i.index not in dup_islands]
    assert others and all(type(i.error) is bd_uv.NonManifoldError for i in others)


def test_duplicate_isolated_triangle_leaves_the_other_island_solved():
    tri = (np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
           np.array([[0, 1, 2], [0, 1, 2]]))
    V, F = combine(grid(), tri)
    res = unwrap_checked(V, F)
    assert [i.status for i in res.islands] == ["certified", "failed"]
    assert type(res.islands[1].error) is bd_uv.DuplicateFacesError


def test_isolated_face_repeating_a_vertex_is_degenerate_not_a_duplicate():
    # its two sides of one edge make that edge look shared by two faces (found by comparing
    # mesh.islands' edge-pair shortcuts with the general path)
    tri = (np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]), np.array([[0, 0, 1]]))
    V, F = combine(grid(), tri)
    res = unwrap_checked(V, F)
    assert [i.status for i in res.islands] == ["certified", "failed"]
    assert type(res.islands[1].error) is bd_uv.DegenerateFacesError
    assert np.array_equal(res.islands[1].error.faces, [len(F) - 1])


@pytest.mark.parametrize("case", ["coincident", "collinear"])
def test_zero_area_faces_fail_with_their_indices(case):
    V, F = grid(bump=0.0)
    V = V.copy()
    if case == "coincident":
        V[6] = V[7]                                      # faces using both 6 and 7 collapse
        zero = np.flatnonzero(np.any(F == 6, 1) & np.any(F == 7, 1))
    else:
        V[6] = [0.125, 0.0, 0.0]                         # face (0, 1, 6) becomes a segment
        zero = np.array([0])
    res = unwrap_checked(V, F)
    (isl,) = res.islands
    assert type(isl.error) is bd_uv.DegenerateFacesError
    assert np.array_equal(np.sort(isl.error.faces), zero)
    assert_message(isl.message, "zero-area", "Degenerate Dissolve")


@pytest.mark.parametrize("height", [1e-3, 1e-6, 1e-9])
@pytest.mark.parametrize("bound", [5.0, "auto"])
def test_needle_faces_are_certified(height, bound):
    """Face (0, 1, 6) is a needle with an angle near 180 degrees; it is thin, not degenerate."""
    V, F = grid(bump=0.0)
    V = V.copy()
    V[6] = [0.125, height, 0.0]
    res = unwrap_checked(V, F, bound=bound)
    assert res.certified


def test_non_manifold_edge_fails_the_faces_around_it():
    V, F = grid()
    fin_vertex = len(V)
    V = np.concatenate([V, [[0.3, 0.3, 1.0]]])
    F = np.concatenate([F, [[6, 7, fin_vertex]]])         # edge 6-7 now has three faces
    V, F = combine((V, F), grid())
    res = unwrap_checked(V, F)
    on_edge = np.flatnonzero(np.any(F == 6, 1) & np.any(F == 7, 1))
    assert len(on_edge) == 3
    failed = [i for i in res.islands if i.status == "failed"]
    assert {int(res.face_island[f]) for f in on_edge} == {i.index for i in failed}
    for isl in failed:
        assert type(isl.error) is bd_uv.NonManifoldError
        assert_message(isl.message, "non-manifold edges", "3 or more faces", "seams")
    assert res.islands[-1].status == "certified" and len(res.islands[-1].faces) == 32


def test_bow_tie_vertex_inside_one_island():
    """A ring with one segment removed and its ends pinched into one vertex: the two fans of
    vertex 0 are edge-connected the long way round, so they form one island with a bow-tie."""
    n = 8
    V, F = annulus(n)
    F = F[:-2].copy()
    F[F == n - 1] = 0
    res = unwrap_checked(V, F)
    (isl,) = res.islands
    assert type(isl.error) is bd_uv.NonManifoldError
    assert_message(isl.message, "non-manifold vertex", "vertices 0", "split the vertex")


def test_bow_tie_of_two_separate_triangles_gives_two_islands():
    """Faces that share only a vertex and nothing else are two islands; each is a disk."""
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]], dtype=np.float64)
    F = np.array([[0, 1, 2], [0, 3, 4]])
    res = unwrap_checked(V, F)
    assert [i.status for i in res.islands] == ["certified", "certified"]


def test_inconsistently_oriented_face():
    V, F = grid()
    F = F.copy()
    F[12] = F[12, ::-1]
    res = unwrap_checked(V, F)
    (isl,) = res.islands
    assert type(isl.error) is bd_uv.OrientationError
    assert 12 in isl.error.faces
    assert_message(isl.message, "oriented against their neighbours", "Recalculate")


def test_moebius_strip_is_an_orientation_error():
    n = 12
    a = 2 * np.pi * np.arange(n) / n
    V = np.array([((1 + s * np.cos(t / 2)) * np.cos(t), (1 + s * np.cos(t / 2)) * np.sin(t),
                   s * np.sin(t / 2)) for t in a for s in (-0.3, 0.3)])
    F = []
    for k in range(n):
        a0, b0 = 2 * k, 2 * k + 1
        a1, b1 = (2 * k + 2, 2 * k + 3) if k < n - 1 else (1, 0)    # the half twist
        F += [(a0, a1, b1), (a0, b1, b0)]
    res = unwrap_checked(V, np.array(F))
    (isl,) = res.islands
    assert type(isl.error) is bd_uv.OrientationError


@pytest.mark.parametrize("shape", ["tetrahedron", "torus"])
def test_closed_island_asks_for_seams(shape):
    V, F = tetrahedron() if shape == "tetrahedron" else torus()
    res = unwrap_checked(V, F)
    (isl,) = res.islands
    assert type(isl.error) is bd_uv.ClosedIslandError
    assert_message(isl.message, "closed", "no boundary", "mark seams")


def test_closed_tetrahedron_cut_by_seams_is_certified():
    V, F = tetrahedron()
    res = unwrap_checked(V, F, seams=np.array([[0, 1], [0, 2], [0, 3]]))
    assert res.certified and len(res.islands) == 1


def test_punctured_torus_is_a_topology_error():
    V, F = torus()
    F = F[1:]                                              # one face removed: genus 1, 1 boundary
    res = unwrap_checked(V, F)
    (isl,) = res.islands
    assert type(isl.error) is bd_uv.TopologyError
    assert_message(isl.message, "genus 1", "mark seams across each handle")


@pytest.mark.parametrize("cuts", ["meridian", "meridian+longitude"])
def test_torus_cut_into_a_disk_with_holes_is_certified(cuts):
    nu, nv = 12, 8
    V, F = torus(nu, nv)
    F = F[1:]
    seams = [[j, (j + 1) % nv] for j in range(nv)]           # around the tube at i = 0
    if cuts == "meridian+longitude":
        seams += [[i * nv, ((i + 1) % nu) * nv] for i in range(nu)]
    res = unwrap_checked(V, F, seams=np.array(seams))
    assert res.certified and len(res.islands) == 1


def test_several_components_are_solved_independently():
    Vn, Fn = nefertiti()
    tri = (np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), np.array([[0, 1, 2]]))
    parts = [grid(), tetrahedron(), tri, (Vn, Fn)]
    V, F = combine(*parts, gap=20.0)
    res = unwrap_checked(V, F)
    sizes = [len(p[1]) for p in parts]
    starts = np.cumsum([0] + sizes[:-1])
    assert [len(i.faces) for i in res.islands] == sizes
    assert [int(i.faces.min()) for i in res.islands] == starts.tolist()
    assert [i.status for i in res.islands] == ["certified", "failed", "certified", "certified"]
    assert type(res.islands[1].error) is bd_uv.ClosedIslandError
    assert not res.certified


def test_islands_with_holes_are_certified():
    V, F = grid(8, 8)
    square = lambda i, j: [2 * (j * 8 + i), 2 * (j * 8 + i) + 1]
    holes = square(2, 2) + square(2, 3) + square(5, 5) + square(5, 4) + square(6, 5)
    F2 = np.delete(F, holes, axis=0)
    (isl,) = bd_uv.islands(V, F2)
    assert len(isl.loops) == 3                             # outer boundary and two holes
    res = unwrap_checked(V, F2)
    assert res.certified


def test_real_mesh_with_holes_is_certified():
    V, F = nefertiti()
    rng = np.random.default_rng(7)
    edges = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    _, count = np.unique(edges, axis=0, return_counts=True)
    boundary = np.unique(edges, axis=0)[count == 1]
    interior_faces = np.flatnonzero(~np.isin(F, boundary.ravel()).any(axis=1))
    # Remove faces that share no vertex, so each leaves its own triangular hole (two removed faces
    # meeting at a vertex would make it a bow-tie instead).
    gone, used = [], set()
    for f in rng.permutation(interior_faces):
        if len(gone) < 12 and not used & set(F[f].tolist()):
            gone.append(f)
            used |= set(F[f].tolist())
    F2 = np.delete(F, gone, axis=0)
    (isl,) = bd_uv.islands(V, F2)
    assert len(isl.loops) == 13
    res = unwrap_checked(V, F2)
    assert res.certified


# ---------------------------------------------------------------------------------------------
# Extreme coordinates: must work, certified, scale-invariant
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("transform", ["scale 1e8", "scale 1e-8", "offset 1e8"])
@pytest.mark.parametrize("bound", [5.0, "auto"])
def test_huge_and_tiny_coordinates_are_certified(transform, bound):
    V, F = nefertiti()
    ref = unwrap_checked(V, F, bound=bound)
    centred = V - V.mean(axis=0)
    Vt = {"scale 1e8": centred * 1e8, "scale 1e-8": centred * 1e-8,
          "offset 1e8": centred + 1e8}[transform]
    res = unwrap_checked(Vt, F, bound=bound)
    (isl,) = res.islands
    assert isl.status == "certified"
    assert uv_area(res.corner_uv) == pytest.approx(area3d(Vt, F), rel=1e-6)
    assert isl.max_distortion == pytest.approx(ref.islands[0].max_distortion, rel=1e-3)


@pytest.mark.parametrize("scale", [1e150, 1e-150, 1e300, 1e-300])
def test_absurd_scales_end_in_a_certificate_or_a_typed_error(scale):
    """Far outside the 1e-8..1e8 range that must work: squared lengths overflow or underflow.
    Whatever happens must still be a certified island or a typed island error."""
    V, F = grid()
    with np.errstate(all="ignore"):
        unwrap_checked(V * scale, F)


@pytest.mark.parametrize("seams_mode", ["auto", "needed"])
@pytest.mark.parametrize("scale", [1e30, 1e80, 1e120])
def test_coordinates_too_large_to_measure_are_refused_by_name(seams_mode, scale):
    """The seam search forms fourth powers of coordinates: a disk scaled to 1e80 ended in
    numpy's LinAlgError ("Eigenvalues did not converge") out of ``unwrap(seams_mode="auto")``
    and out of the command line, a crash. Coordinates beyond ``mesh.MEASURABLE`` (1e60) are
    now refused by name as too large to measure, as NaN is; at 1e30 the disk is certified."""
    from bd_uv.mesh import MEASURABLE
    from bd_uv.options import UnwrapOptions
    V, F = grid()
    res = unwrap_checked(V * scale, F, options=UnwrapOptions(seams_mode=seams_mode))
    if scale <= MEASURABLE:
        assert [r.status for r in res.islands] == ["certified"]
        return
    assert all(r.status == "failed" for r in res.islands)
    assert any(isinstance(r.error, bd_uv.NonFiniteError) and "1e60" in r.message
               for r in res.islands)


# ---------------------------------------------------------------------------------------------
# Seams and options
# ---------------------------------------------------------------------------------------------

def test_out_of_range_seam_is_rejected_or_ignored():
    V, F = grid()
    n = len(V)
    assert np.any(np.isin(F, 1).any(axis=1) & np.isin(F, 6).any(axis=1))   # (1, 6) is an edge
    seams = np.array([[0, n + 6]])
    before = snapshot(V, F, seams)
    try:
        res = bd_uv.unwrap(V, F, seams=seams)
    except bd_uv.InvalidMeshError as exc:
        assert_message(str(exc), "seam")
        return
    finally:
        assert_unchanged(before, V, F, seams)
    (isl,) = res.islands
    assert len(isl.vertices) == n, "a mesh edge was cut by a seam that names no mesh edge"


def test_seams_that_are_not_mesh_edges_are_ignored():
    V, F = grid()
    res = unwrap_checked(V, F, seams=np.array([[0, 24], [-1, 5], [3, 3]]))
    (isl,) = res.islands
    assert isl.status == "certified" and len(isl.vertices) == len(V)


@pytest.mark.parametrize("option, value", [
    ("bound", float("nan")), ("bound", 0.5), ("bound", -3.0), ("bound", "tight"),
    ("bound_limit", float("nan")), ("bound_limit", float("inf")), ("bound_limit", 0.5),
    ("method", "abf"), ("frames", "uv"), ("cone", "sdp")])
def test_bad_options_raise_value_error_naming_the_option(option, value):
    V, F = grid()
    before = snapshot(V, F)
    with pytest.raises(ValueError) as info:
        bd_uv.unwrap(V, F, **{option: value})
    # issue 20: a typed error (a BDError, still a ValueError) that names the option
    assert isinstance(info.value, bd_uv.OptionError) and info.value.option == option
    assert_message(str(info.value), option)
    assert_unchanged(before, V, F)


@pytest.mark.parametrize("stretch", [None, 1.5])
@pytest.mark.parametrize("bound", [1.0000001, 1.0001, 1.0002])
def test_a_bound_just_above_one_is_no_crash(bound, stretch):
    """Issue 22: for 1 < C < 1 / (1 - 2e-4) the solve bound (a hair below C, never below 1) is 1,
    and the projection was started at it: ValueError("C must be > 1"). Such a C is solved like
    C = 1 (the conic solve alone): certified within C, or a typed island error."""
    V, F = grid()
    res = unwrap_checked(V, F, bound=bound, stretch=stretch)
    (isl,) = res.islands
    if isl.status == "certified":
        assert isl.bound_certified >= bound
    else:
        assert isinstance(isl.error, bd_uv.InfeasibleError), isl.error


def test_infinite_bound_is_a_value_error_or_certified():
    V, F = grid()
    try:
        res = unwrap_checked(V, F, bound=float("inf"))
    except ValueError as exc:
        assert_message(str(exc), "bound")
        return
    assert res.certified


# ---------------------------------------------------------------------------------------------
# Pins
# ---------------------------------------------------------------------------------------------

def all_corners(F):
    return np.arange(3 * len(F))


def test_every_vertex_pinned_to_a_valid_map_is_certified_and_kept():
    V, F = nefertiti()
    first = unwrap_checked(V, F)
    pins = first.corner_uv.reshape(-1, 2).copy()
    res = unwrap_checked(V, F, pin_corners=all_corners(F), pin_uv=pins)
    (isl,) = res.islands
    assert isl.status == "certified" and isl.bound_certified == 5.0
    assert np.array_equal(res.corner_uv.reshape(-1, 2), pins)


def test_every_vertex_pinned_beyond_the_bound_raises_it():
    V, F = grid()
    pins = V[F.ravel(), :2] * [3.0, 1.0]                        # stretch 3: distortion about 3
    res = unwrap_checked(V, F, pin_corners=all_corners(F), pin_uv=pins, bound=2.0)
    (isl,) = res.islands
    assert isl.status == "certified" and "bound_raised" in isl.flags
    assert isl.bound_certified >= isl.max_distortion >= 2.9
    assert np.array_equal(res.corner_uv.reshape(-1, 2), pins)


def test_every_vertex_pinned_beyond_the_bound_without_raising_is_infeasible():
    V, F = grid()
    pins = V[F.ravel(), :2] * [3.0, 1.0]
    res = unwrap_checked(V, F, pin_corners=all_corners(F), pin_uv=pins, bound=2.0,
                         raise_bound=False)
    (isl,) = res.islands
    assert type(isl.error) is bd_uv.InfeasibleError and isl.error.island == 0
    assert_message(isl.message, "island 0", "distortion 2", "allow raising the bound")


@pytest.mark.parametrize("pins_kind", ["mirrored", "stretched x300"])
@pytest.mark.parametrize("bound", [5.0, "auto"])
def test_every_vertex_pinned_to_an_impossible_map_is_infeasible(pins_kind, bound):
    V, F = grid()
    factor = [-1.0, 1.0] if pins_kind == "mirrored" else [300.0, 1.0]
    pins = V[F.ravel(), :2] * factor
    res = unwrap_checked(V, F, pin_corners=all_corners(F), pin_uv=pins, bound=bound,
                         bound_limit=100.0)
    (isl,) = res.islands
    assert type(isl.error) is bd_uv.InfeasibleError
    assert_message(isl.message, "island 0", "raise the limit")
    assert re.search(r"\b100\b", isl.message), isl.message     # the limit passed, not 1000
    if bound == 5.0:
        assert_message(isl.message, "pins")


@pytest.mark.parametrize("bound", [5.0, "auto"])
def test_pins_forcing_a_flip_name_their_island(bound):
    """Three pins put face 0 of the second component in clockwise order: it must flip."""
    V, F = combine(grid(), grid())
    f = 32                                                   # face 0 of island 1
    corners = np.array([3 * f, 3 * f + 1, 3 * f + 2])
    pins = V[F[f], :2] * [-1.0, 1.0]
    res = unwrap_checked(V, F, pin_corners=corners, pin_uv=pins, bound=bound)
    assert res.islands[0].status == "certified"
    bad = res.islands[1]
    assert type(bad.error) is bd_uv.InfeasibleError and bad.error.island == 1
    assert_message(bad.message, "island 1", "raise the limit")
    assert_message(bad.message, "move" if bound == "auto" else "move or remove pins")


def test_pins_of_one_vertex_at_two_places_are_infeasible():
    V, F = grid()
    # corner 2 of face 0 and corner 1 of face 1 are both vertex 6 (see grid())
    assert F[0, 2] == F[1, 1] == 6
    res = unwrap_checked(V, F, pin_corners=np.array([2, 4]), pin_uv=np.array([[0, 0], [1, 1.0]]))
    (isl,) = res.islands
    assert type(isl.error) is bd_uv.InfeasibleError
    assert_message(isl.message, "pinned to different UVs", "unpin one")


# ---------------------------------------------------------------------------------------------
# Cancellation: CancelledError, nothing returned, inputs untouched
# ---------------------------------------------------------------------------------------------

def test_cancel_set_before_the_call():
    V, F = nefertiti()
    ev = threading.Event()
    ev.set()
    err = raises_unchanged(bd_uv.CancelledError, V, F, cancel=ev)
    assert_message(str(err), "cancelled", "nothing was changed")


def test_cancel_set_from_the_progress_callback():
    V, F = nefertiti()
    ev = threading.Event()
    calls = []

    def progress(fraction, message):
        calls.append(fraction)
        ev.set()
    raises_unchanged(bd_uv.CancelledError, V, F, cancel=ev, progress=progress)
    assert 0 < calls[0] < 1 and 1.0 not in calls            # stopped before the end


def test_cancel_at_the_second_island_returns_nothing_of_the_first():
    V, F = combine(grid(), grid())
    ev = threading.Event()
    done_first = []

    def progress(fraction, message):
        if message.startswith("island 2/2"):
            done_first.append(fraction)
            ev.set()
    raises_unchanged(bd_uv.CancelledError, V, F, cancel=ev, progress=progress)
    assert done_first and done_first[0] >= 0.5


def progress_calls(V, F, **kw):
    calls = []
    bd_uv.unwrap(V, F, progress=lambda f, msg: calls.append(f), **kw)
    return calls


@pytest.mark.parametrize("bound", [5.0, "auto"])
def test_cancel_at_every_progress_report(bound):
    """Cancel at the k-th progress report, for every k: CancelledError each time, except at the
    final report (fraction 1.0, all work done), after which the complete result may come back."""
    V, F = combine(grid(), grid())
    fractions = progress_calls(V, F, bound=bound)
    assert fractions[-1] == 1.0 and len(fractions) >= 3
    for k in range(len(fractions)):
        ev = threading.Event()
        seen = []

        def progress(fraction, message):
            seen.append(fraction)
            if len(seen) == k + 1:
                ev.set()
        if k < len(fractions) - 1:
            raises_unchanged(bd_uv.CancelledError, V, F, bound=bound, cancel=ev, progress=progress)
        else:
            try:
                res = unwrap_checked(V, F, bound=bound, cancel=ev, progress=progress)
            except bd_uv.CancelledError:
                continue
            assert res.certified


class CancelAfter:
    """``is_set()`` turns True after ``k`` checks: with k = 1 the check at the start of the first
    solve passes and Clarabel's termination callback stops the solve at its first iteration."""

    def __init__(self, k):
        self.k, self.checks = k, 0

    def is_set(self):
        self.checks += 1
        return self.checks > self.k


def test_cancel_inside_the_clarabel_solve(monkeypatch):
    """Cancel after k checks, k = 1..6: always CancelledError; for some k the cancel lands inside a
    Clarabel solve (its termination callback), which must be reported as cancelled too."""
    V, F = nefertiti()
    outcomes = []
    real = bd_uv.solvers.conic.solve_conic

    def spy(*args, **kwargs):
        sol = real(*args, **kwargs)
        outcomes.append(sol.status)
        return sol
    monkeypatch.setattr(bd_uv.solvers.conic, "solve_conic", spy)
    inside = 0
    for k in range(1, 7):
        outcomes.clear()
        # BD-Dirichlet always solves F_C with Clarabel (no projection first)
        raises_unchanged(bd_uv.CancelledError, V, F, method="dirichlet", cancel=CancelAfter(k))
        inside += outcomes[-1:] == ["CallbackTerminated"]
    assert inside >= 1


# ---------------------------------------------------------------------------------------------
# Solver faults, simulated: never a wrong certificate
# ---------------------------------------------------------------------------------------------

REAL_SOLVER = clarabel.DefaultSolver


def faulty_solver(status, x_mode):
    """A stand-in for clarabel.DefaultSolver that reports ``status`` and returns as x: the true
    iterate ("real"), NaN, zeros (every face collapsed) or random numbers (faces flipped)."""
    class Faulty:
        def __init__(self, P, q, A, b, cones, settings):
            self.args = (P, q, A, b, cones, settings)

        def set_termination_callback(self, callback):
            pass

        def solve(self):
            n = self.args[0].shape[0]
            if x_mode == "real":
                sol = REAL_SOLVER(*self.args).solve()
                x, iters = np.asarray(sol.x), sol.iterations
            else:
                x = {"nan": np.full(n, np.nan), "zeros": np.zeros(n),
                     "random": np.random.default_rng(n).normal(size=n)}[x_mode]
                iters = 3
            return types.SimpleNamespace(status=getattr(clarabel.SolverStatus, status),
                                         x=list(x), iterations=iters, obj_val=0.0)
    return Faulty


TIGHT = 1.002   # below the max distortion of grid()'s conformal map, 1.0046
TWO_PINS = dict(pin_corners=np.array([0, 3 * 31 + 2]), pin_uv=np.array([[0.0, 0.0], [1.0, 1.0]]))


@pytest.mark.parametrize("status, x_mode", [
    ("NumericalError", "nan"), ("InsufficientProgress", "zeros"), ("MaxIterations", "random"),
    ("Solved", "zeros"), ("Solved", "random"), ("PrimalInfeasible", "nan"),
    ("MaxIterations", "real"), ("AlmostSolved", "real")])
@pytest.mark.parametrize("setting", ["tight bound", "auto", "two pins"])
def test_solver_faults_never_certify_a_bad_map(monkeypatch, status, x_mode, setting):
    monkeypatch.setattr(bd_uv.solvers.conic.clarabel, "DefaultSolver", faulty_solver(status, x_mode))
    V, F = combine(grid(), grid())
    # The grids' conformal maps have max distortion 1.0046: below it the solver has to be used.
    kw = {"tight bound": {"bound": TIGHT}, "auto": {"bound": "auto"},
          "two pins": dict(TWO_PINS, bound=TIGHT)}[setting]
    res = unwrap_checked(V, F, **kw)                # certified islands are re-verified there
    for isl in res.islands:
        if isl.status == "certified" and x_mode != "real":
            # nothing the conic solver returned was usable: only the flip-free initial map (the
            # fallback when C reaches its distortion, or Algorithm 1's) or a map of the
            # projection iterations can have been certified
            assert "initial_map" in isl.flags or "projected" in isl.flags
        if isl.status == "failed":
            assert type(isl.error) in (bd_uv.InfeasibleError, bd_uv.SolverError)
    if x_mode == "real":
        assert res.certified


def test_solver_outcome_replaced_through_solve_conic(monkeypatch):
    """Patching the wrapper itself: every solve 'inexact' with no iterate."""
    def broken(P, q, A, b, cones, cancel=None, max_iter=0):
        return ConicSolution(None, "inexact", "NumericalError", 80, 0.0, float("nan"))
    monkeypatch.setattr(bd_uv.solvers.conic, "solve_conic", broken)
    V, F = grid()
    res = unwrap_checked(V, F, bound=TIGHT, raise_bound=False, **TWO_PINS)
    assert type(res.islands[0].error) in (bd_uv.InfeasibleError, bd_uv.SolverError)
    res = unwrap_checked(V, F)
    assert res.certified and "initial_map" in res.islands[0].flags


def test_solver_failure_with_pins_is_reported_as_a_solver_error(monkeypatch):
    monkeypatch.setattr(bd_uv.solvers.conic.clarabel, "DefaultSolver",
                        faulty_solver("NumericalError", "nan"))
    V, F = grid()
    # Below the pinned conformal map's distortion and without raising C, nothing can fall back.
    res = unwrap_checked(V, F, bound=TIGHT, raise_bound=False, **TWO_PINS)
    (isl,) = res.islands
    assert type(isl.error) is bd_uv.SolverError
    assert_message(isl.message, "solver")


def test_solver_exception_fails_the_island_not_the_call(monkeypatch):
    class Raising(faulty_solver("Solved", "real")):
        def solve(self):
            raise RuntimeError("simulated solver crash")
    monkeypatch.setattr(bd_uv.solvers.conic.clarabel, "DefaultSolver", Raising)
    V, F = grid()
    res = unwrap_checked(V, F, bound=TIGHT, raise_bound=False, **TWO_PINS)
    assert type(res.islands[0].error) is bd_uv.SolverError


# ---------------------------------------------------------------------------------------------
# Time budget in bound="auto"
# ---------------------------------------------------------------------------------------------

def test_zero_time_budget_still_returns_a_certified_map():
    """No time at all: the certified initial map (or one solve's result) comes back, flagged.
    (A bumpy patch whose full run takes two Dinkelbach steps.)"""
    V, F = grid(8, 8, bump=0.3)
    res = unwrap_checked(V, F, bound="auto", time_budget=0.0)
    (isl,) = res.islands
    assert isl.status == "certified" and "time_budget_exhausted" in isl.flags
    # the certified bound keeps a little room above the map's distortion for float32 storage
    # (0.02 %), rounded up to 4 significant digits (at most 1e-3 more for a C below 10)
    assert isl.max_distortion <= isl.bound_certified <= isl.max_distortion * 1.0002 + 1e-3


def test_time_budget_running_out_returns_the_best_found_so_far(monkeypatch):
    """A clock that advances one second per target of the search (``BoundSearch.run``, ADMM onto
    F_C) and per conic solve, and stands still otherwise: a budget of n - 1.5 s lets exactly
    n - 1 of the n targets of the full run go, whatever the machine's speed, and no conic
    finishing step after them."""
    V, F = grid(8, 8, bump=0.3)
    clock, runs = [0.0], []
    real_run = bd_uv.solvers.bound_search.BoundSearch.run
    real = bd_uv.solvers.conic.solve_conic

    def ticking_run(*args, **kwargs):
        clock[0] += 1.0
        runs.append(1)
        return real_run(*args, **kwargs)

    def ticking(*args, **kwargs):
        clock[0] += 1.0
        return real(*args, **kwargs)
    monkeypatch.setattr(bd_uv.solvers.bound_search.BoundSearch, "run", ticking_run)
    monkeypatch.setattr(bd_uv.solvers.conic, "solve_conic", ticking)
    now = lambda: clock[0]
    for module in (PIPELINE, bd_uv.unwrapping.island_solve, bd_uv.unwrapping.strategies,
                   bd_uv.solvers.bound_search):
        monkeypatch.setattr(module, "time",
                            types.SimpleNamespace(perf_counter=now, monotonic=now, time=now))
    full = unwrap_checked(V, F, bound="auto", time_budget=float("inf"))
    n = len(runs)
    assert n >= 2 and full.islands[0].solves >= 1   # the search's targets, then conic steps
    runs.clear()
    res = unwrap_checked(V, F, bound="auto", time_budget=n - 1.5)
    (isl,) = res.islands
    assert isl.status == "certified" and "time_budget_exhausted" in isl.flags
    assert len(runs) == n - 1 and isl.solves == 0
    assert "time_budget_exhausted" not in full.islands[0].flags
    assert isl.bound_certified >= full.islands[0].bound_certified


def test_zero_time_budget_with_pins_names_the_budget_or_solves_once():
    V, F = grid()
    res = unwrap_checked(V, F, bound="auto", time_budget=0.0, **TWO_PINS)
    (isl,) = res.islands
    if isl.status == "failed":
        assert_message(isl.message, "time budget")
    else:  # the pinned conformal start may already meet the bisection tolerance (no solve)
        assert isl.solves <= 1 or "time_budget_exhausted" in isl.flags


# ---------------------------------------------------------------------------------------------
# Existing UV maps as input, and inputs as Blender hands them over
# ---------------------------------------------------------------------------------------------

def test_input_uv_frames_with_an_island_missing_uvs():
    """frames="input-uv": an island whose faces have no UVs (NaN) fails and says what to do; the
    island with UVs is certified; the UV map passed in is not modified."""
    V, F = combine(grid(), grid())
    first = unwrap_checked(V, F)
    initial = first.corner_uv.copy()
    initial[32:] = np.nan                                   # the second grid has no UVs
    res = unwrap_checked(V, F, frames="input-uv", initial_uv=initial)
    good, bad = res.islands
    assert good.status == "certified" and good.frames == "input-uv"
    assert type(bad.error) is bd_uv.InfeasibleError
    assert_message(bad.message, "island 1", "UVs", "unwrap it first")


def test_read_only_inputs_are_accepted_and_untouched():
    """Inputs flagged read-only: any attempt to write into them would raise."""
    V, F = nefertiti()
    first = unwrap_checked(V, F)
    corners = np.array([0, 7, 100])
    pins = first.corner_uv.reshape(-1, 2)[corners]
    seams = F[200:203, :2].copy()
    initial = first.corner_uv.copy()
    for a in (V, F, corners, pins, seams, initial):
        a.setflags(write=False)
    res = unwrap_checked(V, F, seams=seams, pin_corners=corners, pin_uv=pins,
                         frames="input-uv", initial_uv=initial)
    assert res.certified


def test_blender_dtypes_int32_faces_float32_vertices():
    """Blender's foreach_get hands over int32 indices and float32 coordinates."""
    V, F = nefertiti()
    V32, F32 = V.astype(np.float32), F.astype(np.int32)
    res = unwrap_checked(V32, F32)
    assert res.certified and res.corner_uv.dtype == np.float64
    ref = unwrap_checked(V32.astype(np.float64), F)
    assert np.array_equal(res.corner_uv, ref.corner_uv)
