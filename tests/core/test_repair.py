"""Issue 20, item 2: real meshes as they come, through the core API and the command line.

Each mesh carries one defect (a bow-tie vertex inside one island, an edge of three faces, a part
oriented against the rest, a duplicate face, a zero-area face). With the default seams
("needed") every other face is unwrapped and certified: recomputed here from the stored UVs
(SVD of each face's map, signed areas, an exact triangle overlap test), and the report names the
defect. A closed mesh without ``--seams`` unwraps too.
"""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from bd_uv.layout import stored_layout
from bd_uv.repair import repair_mesh, stored_precision
from bd_uv.seams.needed import unwrap_needed
from helpers import reference_distortion
from overlap_shapes import overlapping_triangle_pairs

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
C = 5.0


def _grid(nx=4, ny=3):
    """A gently curved triangulated grid, vertex (i, j) at index i * (ny + 1) + j."""
    xs, ys = np.meshgrid(np.arange(nx + 1.0), np.arange(ny + 1.0), indexing="ij")
    V = np.stack([xs.ravel(), ys.ravel(), 0.1 * np.sin(xs.ravel() + 0.5 * ys.ravel())], 1)
    i = (np.arange(nx)[:, None] * (ny + 1) + np.arange(ny)[None, :]).ravel()
    F = np.concatenate([np.stack([i, i + ny + 1, i + ny + 2], 1),
                        np.stack([i, i + ny + 2, i + 1], 1)])
    return V, F


def bowtie():
    """The grid's corners (0,0) and (4,0) made one vertex: two fans of it in one island."""
    V, F = _grid()
    F[F == 4 * 4] = 0
    return V, F, set(), "non-manifold vertex"


def three_faces_on_an_edge():
    """A fin triangle on the inner edge (1,1)-(2,1)."""
    V, F = _grid()
    a, b = 1 * 4 + 1, 2 * 4 + 1
    V = np.vstack([V, [[1.5, 1.0, 1.0]]])
    return V, np.vstack([F, [[a, b, len(V) - 1]]]), set(), "three or more faces"


def flipped_part():
    """The first column of faces wound the other way."""
    V, F = _grid()
    F = F.copy()
    first = np.isin(np.arange(len(F)) % 12, np.arange(3))   # faces of column i = 0
    F[first] = F[first][:, ::-1]
    return V, F, set(), "oriented against each other"


def duplicate_face():
    V, F = _grid()
    return V, np.vstack([F, F[7][[1, 2, 0]]]), set(), "duplicate face"


def zero_area_face():
    """A sliver on three collinear points hanging off the grid's border."""
    V, F = _grid()
    V = np.vstack([V, 0.5 * (V[0] + V[4])])     # the midpoint of the border edge (0,0)-(1,0)
    z = len(F)
    return V, np.vstack([F, [[0, len(V) - 1, 4]]]), {z}, "zero-area"


def non_finite_vertex():
    """A triangle hanging off the grid's border on a vertex with a NaN coordinate."""
    V, F = _grid()
    V = np.vstack([V, [[0.5, -1.0, np.nan]]])
    z = len(F)
    return V, np.vstack([F, [[0, len(V) - 1, 4]]]), {z}, "NaN or infinite"


def double_sided():
    """Every face repeated on its vertices in reverse order (a surface modelled double-sided, as
    trimesh's chair_model.obj, a Blender 2.71 export, is: 6,374 faces twice)."""
    V, F = _grid()
    return V, np.vstack([F, F[:, ::-1]]), set(), "double-sided"


def lone_double_sided_triangle():
    """A triangle on its own, written twice in opposite orders (trimesh's bunny.ply holds such
    pairs): on main the pair was one closed island of two faces, refused ("2 faces repeat the
    same three vertices ... merge or delete the duplicates")."""
    V, F = _grid()
    n = len(V)
    V = np.vstack([V, [[6.0, 0.0, 0.0], [7.0, 0.0, 0.2], [6.0, 1.0, 0.1]]])
    return V, np.vstack([F, [[n, n + 1, n + 2], [n, n + 2, n + 1]]]), set(), "double-sided"


DEFECTS = [bowtie, three_faces_on_an_edge, flipped_part, duplicate_face, zero_area_face,
           non_finite_vertex, double_sided, lone_double_sided_triangle]


def _check_certified(V, F, corner_uv, skip):
    """Every face but ``skip`` has stored UVs: none flipped, distortion <= C, no two faces
    overlapping (a duplicate may lie exactly on its twin: the pair is its own)."""
    mask = np.ones(len(F), dtype=bool)
    mask[list(skip)] = False
    uv = corner_uv[mask]
    assert np.isfinite(uv).all()
    D, flipped = reference_distortion(V, F[mask], uv)
    assert not flipped.any() and D.max() <= C * (1 + 1e-6)
    pairs = overlapping_triangle_pairs(uv)
    same = np.array([set(F[mask][i]) == set(F[mask][j]) for i, j in pairs], dtype=bool)
    assert same.all(), pairs[~same]


@pytest.mark.parametrize("make", DEFECTS, ids=lambda f: f.__name__)
def test_core_api_unwraps_every_other_face(make):
    V, F, skip, words = make()
    res = unwrap_needed(V, F)
    assert any(words in note for note in res.repair), res.repair
    layout = stored_layout(V, F, res, dtype=np.float32)
    _check_certified(V, F, layout.corner_uv, skip)
    # Only the faces that cannot be certified at all are named failed, their UVs not written.
    failed = [r for r in res.islands if r.status != "certified"]
    assert sorted(int(f) for r in failed for f in r.faces) == sorted(skip)
    assert np.isnan(layout.corner_uv[list(skip)]).all()


def written_corner_uv(path):
    """(m,3,2) float64: each face's corner UVs as an OBJ the command line wrote holds them (its
    ``vt`` records, read as text); NaN for a face written without them."""
    vt, ft = [], []
    for line in path.read_text().splitlines():
        p = line.split()
        if p and p[0] == "vt":
            vt.append([float(t) for t in p[1:3]])
        elif p and p[0] == "f":
            ft.append([int(t.split("/")[1]) - 1 if "/" in t else -1 for t in p[1:]])
    vt, ft = np.array(vt).reshape(-1, 2), np.array(ft)
    return np.where((ft >= 0)[:, :, None], vt[np.maximum(ft, 0)], np.nan)


def run_command_line(tmp_path, V, F, *options):
    """The mesh written as an OBJ file and unwrapped by ``python -m bd_uv unwrap`` with
    ``options``. Returns (the finished process, the output OBJ's path, the report's path)."""
    src = tmp_path / "messy.obj"
    src.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in V.tolist())
                   + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F))
    out, rep = tmp_path / "out.obj", tmp_path / "r.json"
    r = subprocess.run([sys.executable, "-m", "bd_uv", "unwrap", str(src), "-o", str(out),
                        "--report", str(rep), *options], capture_output=True, text=True,
                       cwd=REPO)
    return r, out, rep


@pytest.mark.parametrize("make", DEFECTS, ids=lambda f: f.__name__)
def test_command_line_unwraps_every_other_face(make, tmp_path):
    V, F, skip, words = make()
    r, out, rep = run_command_line(tmp_path, V, F)
    # faces of zero area alone do not fail a mesh: they take their neighbours' UVs (as a scene's)
    zero = make is zero_area_face
    assert r.returncode == (1 if skip and not zero else 0), r.stderr
    assert words in r.stdout
    report = json.loads(rep.read_text())
    assert any(words in note for note in report["repair"])
    corner_uv = written_corner_uv(out)
    _check_certified(V, F, corner_uv, skip)
    if zero:
        assert report["zero_area_faces"] == len(skip)
        assert np.isfinite(corner_uv[list(skip)]).all()
    else:
        assert np.isnan(corner_uv[list(skip)]).all()


def test_closed_mesh_without_seams_unwraps_from_the_command_line(tmp_path):
    src = tmp_path / "tet.off"
    src.write_text("OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n")
    rep = tmp_path / "r.json"
    r = subprocess.run([sys.executable, "-m", "bd_uv", "unwrap", str(src), "-o",
                        str(tmp_path / "o.obj"), "--report", str(rep)], capture_output=True,
                       text=True, cwd=REPO)
    assert r.returncode == 0, r.stderr
    report = json.loads(rep.read_text())
    assert len(report["seams_added"]) > 0


def _uv_islands(F, corner_uv):
    """Islands of stored UVs: faces joined across an edge whose two ends carry the same UVs in
    both faces (recomputed from the corner UVs alone)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    seen, I, J = {}, [], []
    for f, (tri, uv) in enumerate(zip(F.tolist(), corner_uv.tolist())):
        for c in range(3):
            (a, ua), (b, ub) = sorted([(tri[c], uv[c]), (tri[(c + 1) % 3], uv[(c + 1) % 3])])
            key = (a, b, *ua, *ub)
            if key in seen:
                I.append(seen[key])
                J.append(f)
            seen.setdefault(key, f)
    A = coo_matrix((np.ones(len(I)), (I, J)), shape=(len(F), len(F)))
    return connected_components(A, directed=False)


def test_double_sided_surface_unwraps_front_and_back_as_two_islands():
    """Each face twice, the second reversed: every inner edge has four faces. The backs are one
    surface of their own, so the grid's front and back come out as one island each (before, every
    edge of four faces was cut: 36 islands for this grid's 48 faces, 38 as stored)."""
    V, F, _, _ = double_sided()
    front = len(F) // 2
    rep = repair_mesh(V, F)
    assert sorted(rep.back_faces.tolist()) == list(range(front, len(F)))
    assert not len(rep.split_vertices) and not len(rep.nonmanifold_edges)
    assert not len(rep.orientation_edges)
    res = unwrap_needed(V, F)
    layout = stored_layout(V, F, res, dtype=np.float32)
    _check_certified(V, F, layout.corner_uv, set())
    n, lab = _uv_islands(F, layout.corner_uv)
    assert n == 2
    assert len(set(lab[:front])) == 1 and len(set(lab[front:])) == 1


def test_marked_seams_that_make_disks_get_no_new_seam():
    # A closed tetrahedron cut open along a spanning tree of three edges: one certifiable disk.
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    seams = np.array([[0, 1], [0, 2], [0, 3]])
    res = unwrap_needed(V, F, seams=seams)
    assert len(res.seams_added) == 0 and res.certified and len(res.islands) == 1


def test_public_unwrap_takes_seams_needed():
    # bd_uv.unwrap keeps "marked" by default (a closed mesh fails); seams="needed" cuts it.
    import bd_uv
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    assert not bd_uv.unwrap(V, F).certified
    res = bd_uv.unwrap(V, F, seams="needed")
    assert res.certified and len(res.seams_added) > 0
    D, flipped = reference_distortion(V, F, res.corner_uv)
    assert not flipped.any() and D.max() <= 2.0 * (1 + 1e-6)   # charts cut at min(C, 2)


def test_clean_mesh_is_left_as_it_is():
    V, F = _grid()
    rep = repair_mesh(V, F)
    assert not rep.changed and rep.notes() == []
    np.testing.assert_array_equal(rep.F, F)
    np.testing.assert_array_equal(rep.V, V)


def test_zero_area_at_float32_precision():
    """With ``precision=np.float32`` a triangle whose height is below one float32 step of its
    largest coordinate is zero-area (its positions cannot tell it from a line); in float64 it is
    not (twice its area over its longest edge squared, 4e-9, is far above DEGENERATE_RATIO)."""
    from bd_uv.repair import zero_area_faces
    V = np.array([[0.0, 0.0, 1.0], [0.25, 0.0, 1.0], [0.125, 1e-9, 1.0], [0.125, 1e-6, 1.0]])
    F = np.array([[0, 1, 2], [0, 1, 3]])
    h = np.array([1e-9, 1e-6])
    step = np.spacing(np.float32(1.0))            # 1.19e-7 at the largest coordinate, 1.0
    assert (h < step).tolist() == [True, False]
    assert zero_area_faces(V, F).tolist() == [False, False]
    assert zero_area_faces(V, F, np.float32).tolist() == [True, False]
    assert zero_area_faces(V, F, np.float64).tolist() == [False, False]


def test_stored_precision_only_for_flat_faces_side_by_side():
    """Faces float32 cannot tell from a line are left out from the start (``stored_precision``
    gives float32) only when two of them share an edge; one standing alone, none, float64
    positions, or arrays the unwrap refuses give None (tried as they are)."""
    from bd_uv.repair import flat_at_precision, side_by_side, stored_precision
    V = np.array([[0.0, 0.0, 1.0], [0.25, 0.0, 1.0], [0.125, 1e-9, 1.0], [0.125, -1e-9, 1.0],
                  [0.125, 0.5, 1.0], [0.6, 0.0, 1.0], [0.6, 1e-9, 1.0]])
    apart = np.array([[0, 1, 2], [0, 4, 1], [1, 5, 6]])        # two flat faces, no edge shared
    beside = np.array([[0, 1, 2], [1, 0, 3], [0, 4, 1]])       # two flat faces on edge 0-1
    for F, flat in ((apart, [True, False, True]), (beside, [True, True, False])):
        assert flat_at_precision(V, F, np.float32).tolist() == flat
        assert flat_at_precision(V, F, np.float64) is None
    assert not side_by_side(apart, np.array([True, False, True]))
    assert side_by_side(beside, np.array([True, True, False]))
    assert stored_precision(V, apart, np.float32) is None
    assert stored_precision(V, beside, np.float32) is np.float32
    assert stored_precision(V, beside, np.float64) is None
    assert stored_precision(V, np.array([[0, 4, 1]]), np.float32) is None
    assert stored_precision(V, np.array([[0, 1, 99]]), np.float32) is None   # a bad index


def _split_grid():
    """A curved quad grid at scale 100 split by a strip of 4 quads one float32 step high (as in
    OpenChessSet's bishops), positions rounded to float32; the strip's 8 triangles last."""
    nx, ny = 5, 4
    xs, ys = np.meshgrid(np.linspace(0.0, 1.0, nx), np.linspace(0.0, 1.0, ny))
    x, y = xs.ravel(), ys.ravel()
    V = 100.0 * np.stack([x, y, 0.25 * (x - 0.4) ** 2 + 0.1 * y], axis=1)
    i = np.arange(nx * ny).reshape(ny, nx)
    quads = np.stack([i[:-1, :-1].ravel(), i[:-1, 1:].ravel(), i[1:, 1:].ravel(),
                      i[1:, :-1].ravel()], axis=1)
    row = i[1]
    copy = np.arange(nx * ny)
    copy[row] = nx * ny + np.arange(nx)
    eps = float(np.spacing(np.float32(V[row[0], 1])))
    V = np.vstack([V, V[row] + [0.0, eps, 0.0]]).astype(np.float32).astype(np.float64)
    quads[nx - 1:] = copy[quads[nx - 1:]]       # the rows above the split take the copies
    strip = np.stack([row[:-1], row[1:], copy[row[1:]], copy[row[:-1]]], axis=1)
    q = np.vstack([quads, strip])
    F = np.vstack([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
    order = np.argsort(np.r_[np.arange(len(q)), np.arange(len(q))], kind="stable")
    F = F[order]                                 # the two triangles of a quad side by side
    seams = np.concatenate([np.stack([row[:-1], row[1:]], 1),
                            np.stack([copy[row[:-1]], copy[row[1:]]], 1)])
    return V, F, seams, np.arange(len(F)) >= 2 * len(quads)


def test_marked_seams_refuse_float32_flat_faces_at_once():
    """``precision=np.float32`` with the marked seams: faces float32 cannot tell from a line
    are zero-area there too. Marked seams around the flat strip leave the grid's
    two halves certified (recomputed here) and the strip's island refused as zero-area, named;
    without ``precision`` float64 tells the strip from a line and does not refuse it."""
    import bd_uv
    from bd_uv.errors import DegenerateFacesError
    V, F, seams, flat = _split_grid()
    assert stored_precision(V, F, np.float32) is np.float32
    res = bd_uv.unwrap(V, F, seams=seams, precision=np.float32)
    refused = [r for r in res.islands if r.status != "certified"]
    assert len(refused) == 1 and isinstance(refused[0].error, DegenerateFacesError)
    assert sorted(refused[0].faces) == np.flatnonzero(flat).tolist()
    assert "zero-area" in str(refused[0].error)
    ok = ~flat
    D, flipped = reference_distortion(V, F[ok], res.corner_uv[ok])
    assert not flipped.any() and D.max() <= 5.0 * (1 + 1e-6)
    plain = bd_uv.unwrap(V, F, seams=seams)
    assert not any(isinstance(r.error, DegenerateFacesError) for r in plain.islands)


def test_a_zero_area_face_prints_no_numpy_warning(recwarn):
    """A zero-area face's gradients are NaN (0/0 and inf - inf): measured quietly, not printed
    as RuntimeWarnings to a pipeline's log, with every seams mode; the face is refused, named."""
    import bd_uv
    from bd_uv.errors import DegenerateFacesError
    V, F = _grid()
    V = np.vstack([V, (V[F[0, 0]] + V[F[0, 1]]) / 2])
    F = np.vstack([F, [F[0, 1], F[0, 0], len(V) - 1]])     # hangs from face 0's first edge
    for seams in (None, "auto", "needed"):
        res = bd_uv.unwrap(V, F, seams=seams)
        named = np.concatenate([r.error.faces for r in res.islands
                                if isinstance(r.error, DegenerateFacesError)])
        assert named.tolist() == [len(F) - 1], seams
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)], \
        [str(w.message) for w in recwarn]
