"""Parts of a mesh that copy another part (``seams.copies``): the search runs on the original,
the copies get its seams, and every chart is still certified on its own positions.

The parts are built here with a known rotation, scale, translation and vertex numbering, so the
correspondence the search should find is known independently.
"""
import numpy as np
import pytest

from bd_uv.seams import copies as copies_mod
from bd_uv.seams import unwrap_auto
from bd_uv.seams.copies import SEARCHED, TOL, find_copies
from bd_uv.seams.edges import edge_table
from seams_helpers import torus, uv_sphere
from test_seams import check_charts


def _rotation(seed):
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def _parts():
    """A torus, and beside it: the torus rotated, scaled 2.5 and moved (a copy); moved with its
    vertices numbered in another order (a copy); mirrored (not a copy); moved with noise of
    100 TOL of its size (not a copy); a UV sphere (another part). Returns V, F, and per part
    (faces, vertex of the part for each torus vertex)."""
    Vt, Ft = torus(R=4.0, r=1.0, nu=24, nv=8)[:2]
    nt = len(Vt)
    R = _rotation(3)
    perm = np.random.default_rng(1).permutation(nt)
    where = np.empty(nt, dtype=np.int64)
    where[perm] = np.arange(nt)             # vertex i of the torus is vertex where[i] here
    noise = np.random.default_rng(2).normal(size=Vt.shape) * 100 * TOL * np.sqrt(
        np.mean(np.sum((Vt - Vt.mean(0)) ** 2, axis=1)))
    mirror = Vt * [-1.0, 1.0, 1.0]
    pieces = [(Vt, Ft, np.arange(nt)),
              (2.5 * Vt @ R.T + [20.0, 0, 0], Ft, np.arange(nt)),
              ((Vt + [0, 20.0, 0])[perm], where[Ft], where),
              (mirror + [0, 0, 20.0], Ft, np.arange(nt)),
              (Vt + noise + [0, -20.0, 0], Ft, np.arange(nt))]
    Vs, Fs = uv_sphere()[:2]
    pieces.append((Vs + [-20.0, 0, 0], Fs, None))
    V, F, parts, nv, nf = [], [], [], 0, 0
    for P, Q, corr in pieces:
        V.append(P)
        F.append(Q + nv)
        parts.append((np.arange(nf, nf + len(Q)), None if corr is None else corr + nv))
        nv += len(P)
        nf += len(Q)
    return np.concatenate(V), np.concatenate(F).astype(np.int64), parts


def test_copies_found_by_similarity_and_numbering():
    V, F, parts = _parts()
    E = edge_table(V, F)
    found = find_copies(V, F, E, np.zeros(len(E.ends), dtype=bool))
    assert found is not None
    assert len(found.classes) == 1
    members = found.classes[0]
    assert [int(found.part[verts[0]]) for _, verts, _ in members] == [
        int(found.part[parts[k][1][0]]) for k in range(3)]
    # Vertex for vertex: the torus's vertex i onto each copy's vertex i; face for face.
    orig = members[0][1]
    assert np.array_equal(np.sort(orig), parts[0][1])
    for k, (_, verts, faces) in enumerate(members):
        assert np.array_equal(verts, parts[k][1][orig - parts[0][1][0]])
        assert np.array_equal(faces, parts[k][0])
    # The first SEARCHED members are searched, the others left to the copy.
    want = np.zeros(len(F), dtype=bool)
    for k in range(SEARCHED, 3):
        want[parts[k][0]] = True
    assert np.array_equal(found.mask, want)


def test_given_seams_and_materials_must_match():
    V, F, parts = _parts()
    E = edge_table(V, F)
    cut = np.zeros(len(E.ends), dtype=bool)
    # A seam on the first copy only: it is no copy any more (the second one still is).
    e = E.keys([[parts[1][1][0], parts[1][1][1]]], len(V))[0]
    assert e >= 0
    cut[e] = True

    def members(found):
        return [[int(f[0]) for _, _, f in c] for c in found.classes]
    assert members(find_copies(V, F, E, cut)) == [[int(parts[0][0][0]), int(parts[2][0][0])]]
    groups = np.zeros(len(F), dtype=np.int64)
    groups[parts[2][0][:5]] = 1
    found = find_copies(V, F, E, np.zeros(len(E.ends), dtype=bool), face_groups=groups)
    assert members(found) == [[int(parts[0][0][0]), int(parts[1][0][0])]]


def _cut_pairs(res, F, faces):
    """The mesh edges of ``faces`` whose two faces are in different charts or do not share both
    chart vertices, as sorted vertex pairs (recomputed from the islands)."""
    corner = np.full((len(F), 3), -1, dtype=np.int64)
    off = 0
    for r in res.islands:
        corner[r.faces] = r.tris + off
        off += len(r.vertices)
    half = {}
    for f in faces.tolist():
        for k in range(3):
            a, b = int(F[f, k]), int(F[f, (k + 1) % 3])
            half[(a, b)] = (corner[f, k], corner[f, (k + 1) % 3])
    out = set()
    for (a, b), (ca, cb) in half.items():
        other = half.get((b, a))
        if other is not None and (other[0] != cb or other[1] != ca):
            out.add((min(a, b), max(a, b)))
    return out


@pytest.mark.parametrize("searched", [1, SEARCHED])
def test_copies_get_the_originals_seams_and_are_certified(monkeypatch, searched):
    """With 1 searched the copies are left out of the search; with ``SEARCHED`` (more than the
    two copies) all three are searched and the best one's seams replace the others'."""
    monkeypatch.setattr(copies_mod, "SEARCHED", searched)
    V, F, parts = _parts()
    res, added, info = unwrap_auto(V, F, bound=2.0, stretch=2.0)
    check_charts(V, F, res)
    seams = [_cut_pairs(res, F, faces) for faces, _ in parts]
    assert seams[0]                         # a torus needs seams
    for k in (1, 2):
        corr = parts[k][1]
        image = {tuple(sorted((int(corr[a - parts[0][1][0]]), int(corr[b - parts[0][1][0]]))))
                 for a, b in seams[0]}
        assert image == seams[k]
        charts = {int(i) for i in res.face_island[parts[k][0]]}
        assert len(charts) == len({int(i) for i in res.face_island[parts[0][0]]})
    # ``added`` holds the copies' seams too.
    got = {tuple(p) for p in added.tolist()}
    assert set().union(*seams[:3]) <= got


def test_copies_with_polygons_stay_whole_polygons():
    """Three UV spheres of quads, two of them rotated and scaled copies, with their polygons:
    copies are found polygon for polygon (another numbering of the polygons is the same
    polygons), every chart is whole polygons and certified, and the copies are cut alike."""
    from test_seams_polygons import _check_whole_polygons
    Vs, Fs, ps = uv_sphere(24, 12)
    R = _rotation(5)
    V = np.concatenate([Vs, 0.5 * Vs @ R.T + [5.0, 0, 0], Vs @ R + [0, 5.0, 0]])
    F = np.concatenate([Fs, Fs + len(Vs), Fs + 2 * len(Vs)]).astype(np.int64)
    poly = np.concatenate([ps, ps + 1000, 5000 - ps])
    E = edge_table(V, F)
    found = find_copies(V, F, E, np.zeros(len(E.ends), dtype=bool), polygons=poly)
    assert len(found.classes) == 1 and len(found.classes[0]) == 3
    res, added, info = unwrap_auto(V, F, bound=2.0, stretch=2.0, polygons=poly)
    check_charts(V, F, res)
    _check_whole_polygons(F, poly, res, added)
    m = len(Fs)
    seams = [_cut_pairs(res, F, np.arange(k * m, (k + 1) * m)) for k in range(3)]
    assert seams[0]
    for k in (1, 2):
        assert {(a + k * len(Vs), b + k * len(Vs)) for a, b in seams[0]} == seams[k]


@pytest.mark.parametrize("searched", [1, SEARCHED])
def test_copies_take_the_atlas_cuts(monkeypatch, searched):
    """Two copies of a thin torus: each one's band alone caps the atlas, so the atlas's split
    of the searched one is copied, and counted, on the other (as when both are searched)."""
    monkeypatch.setattr(copies_mod, "SEARCHED", searched)
    Vt, Ft = torus(R=8.0, r=0.5, nu=64, nv=8)[:2]
    V = np.concatenate([Vt, Vt + [40.0, 0, 0]])
    F = np.concatenate([Ft, Ft + len(Vt)]).astype(np.int64)
    res, added, info = unwrap_auto(V, F, bound=2.0, stretch=2.0)
    check_charts(V, F, res)
    atlas = {tuple(p) for p in info["atlas_seams"].tolist()}
    one = {(a, b) for a, b in atlas if b < len(Vt)}
    assert one and info["atlas_cuts"] == 2
    assert {(a + len(Vt), b + len(Vt)) for a, b in one} == atlas - one
