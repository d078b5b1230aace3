"""Mesh preparation: validate, cut along seams, split into islands.

An island is a set of faces connected across manifold, non-seam edges. Each island gets its own cut
vertices: corners of one input vertex share an island vertex only when they are connected around
that vertex without crossing a seam, so a seam through an island opens it up.
"""
from dataclasses import dataclass

import numpy as np

from .errors import (ClosedIslandError, DegenerateFacesError, DuplicateFacesError,
                     InvalidMeshError, NonFiniteError, NonManifoldError, OrientationError,
                     TopologyError)
from .geometry import components, face_areas, ordered_loops

# A face is degenerate when twice its area is below this fraction of its longest edge squared.
DEGENERATE_RATIO = 1e-12


@dataclass(frozen=True)
class Island:
    """One connected piece of the cut mesh.

    Attributes
    ----------
    index : int
    faces : (k,) int64, indices into the input F
    vertices : (nk,) int64, input vertex id of each island vertex
    tris : (k,3) int64, the island's triangles in island vertex ids
    loops : tuple of (b,) int64 arrays, boundary loops in island vertex ids, longest first
    error : IslandError or None, why the island cannot be parameterized
    """
    index: int
    faces: np.ndarray
    vertices: np.ndarray
    tris: np.ndarray
    loops: tuple
    error: Exception = None


def check_arrays(V, F, *, share=False):
    """Validate shapes and indices; return float64 V and int64 F.

    With ``share``, arrays already of those types come back as read-only views of the caller's
    (no copy: the seam search holds V and F through its whole run, 17 MB on a 500k-face mesh);
    anything writing into them raises rather than changing the caller's mesh.

    Raises
    ------
    InvalidMeshError
    """
    V = np.asarray(V)
    F = np.asarray(F)
    if V.ndim != 2 or V.shape[1] != 3:
        raise InvalidMeshError(f"vertices must be an (n,3) array, got shape {V.shape}")
    if F.size == 0:
        raise InvalidMeshError("the mesh has no faces: nothing to unwrap")
    if F.ndim != 2 or F.shape[1] != 3:
        raise InvalidMeshError(f"faces must be an (m,3) array of triangles, got shape {F.shape}; "
                               "triangulate n-gons first")
    F = _shared(F) if share and F.dtype == np.int64 else as_indices(F, "face indices")
    bad = np.flatnonzero(np.any((F < 0) | (F >= len(V)), axis=1))
    if len(bad):
        raise InvalidMeshError(f"{len(bad)} face(s) use vertex indices outside 0..{len(V) - 1} "
                               f"(faces {_some(bad)}); fix the face list")
    return (_shared(V) if share and V.dtype == np.float64 else as_reals(V, "vertex coordinates"),
            F)


def _shared(x):
    """A read-only view of ``x``."""
    x = x.view()
    x.flags.writeable = False
    return x


def as_reals(x, what):
    """``x`` as float64, or InvalidMeshError naming ``what`` when it is not real numbers (text,
    complex numbers: nothing is parsed or dropped silently). NaN and inf pass."""
    x = np.asarray(x)
    if x.dtype.kind not in "biufO":
        raise InvalidMeshError(f"{what} must be real numbers, got {x.dtype}")
    try:
        return x.astype(np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidMeshError(f"{what} must be real numbers ({exc})") from None


def as_indices(x, what):
    """``x`` as int64 indices, or InvalidMeshError naming ``what`` when a value is not an integer
    (fractions, NaN, text: never truncated or cast silently)."""
    x = np.asarray(x)
    if x.dtype.kind in "iu":
        return x.astype(np.int64)
    f = as_reals(x, what)
    if not np.all(np.isfinite(f)) or np.any(f != np.round(f)):
        raise InvalidMeshError(f"{what} must be integers")
    return f.astype(np.int64)


def _some(idx, k=8):
    idx = np.asarray(idx)
    s = ", ".join(str(int(i)) for i in idx[:k])
    return s + (f", ... ({len(idx)} in all)" if len(idx) > k else "")


def _edge_keys(a, b, n):
    return np.minimum(a, b) * n + np.maximum(a, b)


#: the largest coordinate magnitude a face may have: the seam search forms fourth powers of
#: coordinates (area-weighted second moments), which overflow float64 near 1e77 (a disk scaled to
#: 1e80 ended in LinAlgError out of the Fiedler split's principal axes); beyond it a face is refused
#: by name as too large to measure, as a non-finite one is
MEASURABLE = 1e60
TOO_LARGE = "coordinates beyond 1e60 (too large to measure)"   # how messages say it


def measurable(P):
    """(m,) bool: faces (corners ``P`` (m,3,3)) whose coordinates are finite and at most
    ``MEASURABLE`` in magnitude."""
    with np.errstate(invalid="ignore"):
        return np.all(np.abs(P) <= MEASURABLE, axis=(1, 2))


def thinner_than_precision(P, A, lmax2, precision):
    """(m,) bool: faces (corners ``P`` (m,3,3), areas ``A``, longest edges squared ``lmax2``)
    too thin for ``precision``, the float type the positions were stored in and the UVs are
    written in (``np.float32`` for glTF, USD, Blender); None or float64: none. Their height,
    twice the area over the longest edge, is below

    - one step of ``precision`` at their largest coordinate: three points that precision cannot
      tell from a line; or
    - one step of ``precision`` in the unit square's upper half (2^-24 for float32) times the
      square root of the mesh's area (the faces ``A`` given): at the largest scale a map of the
      mesh into the unit square has on average (its faces keeping their 3D areas, all of the
      square covered), the face is less than one UV step high, so no float32 UVs keep it from
      flipping or collapsing wherever it is packed. usd-wg's tractor body has one such face
      (3.7e-7 high at coordinates up to 2.85, 1.6 position steps, in 195 square units: 0.45 UV
      step); it failed its island as stored in about one run of four, by where it was packed.
    """
    if precision is None or np.dtype(precision) == np.float64:
        return np.zeros(len(A), dtype=bool)
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        step = np.spacing(np.abs(P).max(axis=(1, 2)).astype(precision)).astype(np.float64)
        total = float(np.sum(A[np.isfinite(A)]))
        uv_step = float(np.spacing(np.asarray(0.5, dtype=precision))) * np.sqrt(total)
        return ~(2 * A > np.maximum(step, uv_step) * np.sqrt(lmax2))


def islands(V, F, seams=None, precision=None):
    """Cut the mesh along seams and split it into validated islands.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array
    seams : (s,2) int array, optional
        Vertex pairs of the edges to cut along. Pairs that are not mesh edges (including indices
        outside 0..n-1) are ignored.
    precision : float type the positions were stored in, optional: faces it cannot tell from a
        line are zero-area too (``thinner_than_precision``)

    Returns
    -------
    list of Island, ordered by their smallest face index.
    """
    V, F = check_arrays(V, F)
    return checked_islands(V, F, seams, precision)


def checked_islands(V, F, seams=None, precision=None):
    """``islands`` of arrays ``check_arrays`` already returned (float64 V, int64 F in range).
    With ``precision``, the float type the positions were stored in, faces it cannot tell from a
    line count as zero-area too (``thinner_than_precision``)."""
    n, m = len(V), len(F)
    # Half-edges: corner (f, k) starts the directed edge F[f,k] -> F[f,k+1].
    src = F.ravel()
    dst = F[:, [1, 2, 0]].ravel()
    key = _edge_keys(src, dst, n)
    # Half-edges grouped by undirected edge (in increasing order within a group): one sort for
    # np.unique's answer and the grouping both.
    order = np.argsort(key, kind="stable")
    ks = key[order]
    new_edge = np.empty(len(ks), dtype=bool)
    new_edge[0] = True
    np.not_equal(ks[1:], ks[:-1], out=new_edge[1:])
    first = np.flatnonzero(new_edge)                       # each edge's first half-edge
    count = np.diff(np.append(first, len(ks)))
    inv = np.empty(len(ks), dtype=np.int64)
    inv[order] = np.cumsum(new_edge) - 1
    he_count = count[inv]
    if seams is not None and len(seams):
        S = as_indices(seams, "seam vertex indices")
        if S.size % 2 or (S.ndim > 1 and S.shape[-1] != 2):
            raise InvalidMeshError(f"seams must be an (s,2) array of vertex pairs, got shape "
                                   f"{S.shape}")
        S = S.reshape(-1, 2)
        S = S[np.all((S >= 0) & (S < n), axis=1)]  # pairs naming no mesh vertex name no edge
        is_seam = np.isin(key, _edge_keys(S[:, 0], S[:, 1], n))
    else:
        is_seam = np.zeros(len(key), dtype=bool)

    # Pair the two half-edges of each edge used by exactly two faces.
    two = np.flatnonzero(count == 2)
    h1, h2 = order[first[two]], order[first[two] + 1]
    g1, g2 = h1, h2                                        # every pair, seams included
    join = ~is_seam[h1]
    h1, h2 = h1[join], h2[join]
    f1, f2 = h1 // 3, h2 // 3
    consistent = src[h1] == dst[h2]

    # Islands: faces connected across the joined edges.
    n_isl, face_isl = components(m, f1, f2)

    # Cut vertices: corners glued across joined edges. Corner of src[h] is h; of dst[h] is next(h).
    nxt = lambda h: (h // 3) * 3 + (h % 3 + 1) % 3
    ca = np.where(consistent, nxt(h2), h2)
    cb = np.where(consistent, h2, nxt(h2))
    rows = np.concatenate([h1, nxt(h1)])
    cols = np.concatenate([ca, cb])
    _, corner_vertex = components(3 * m, rows, cols)

    # Non-manifold vertices: several corner fans of one vertex, ignoring seams, in one island.
    if join.all():      # no seam between two faces: the fans are the cut vertices
        fan = corner_vertex
    else:
        gcons = src[g1] == dst[g2]
        rows = np.concatenate([g1, nxt(g1)])
        cols = np.concatenate([np.where(gcons, nxt(g2), g2), np.where(gcons, g2, nxt(g2))])
        _, fan = components(3 * m, rows, cols)
    # A fan holds corners of one vertex; (vertex, island) pairs reached by several fans are
    # bow-ties. Integer keys, not np.unique(axis=0) (a structured sort, slow on small meshes too).
    corner_isl = np.repeat(face_isl, 3)
    fan_vertex = np.empty(3 * m, dtype=np.int64)
    fan_vertex[fan] = src
    fan_isl = np.unique(fan.astype(np.int64) * n_isl + corner_isl)  # distinct (fan, island)
    vi, vi_count = np.unique(fan_vertex[fan_isl // n_isl] * n_isl + fan_isl % n_isl,
                             return_counts=True)
    vi = vi[vi_count > 1]
    bowtie = np.stack([vi // n_isl, vi % n_isl], axis=1)

    A = face_areas(V, F)
    P = V[F]
    with np.errstate(invalid="ignore", over="ignore"):
        lmax2 = np.max(np.sum((P - np.roll(P, -1, axis=1)) ** 2, axis=2), axis=1)
        degenerate = ~(2 * A > DEGENERATE_RATIO * lmax2)
    degenerate |= thinner_than_precision(P, A, lmax2, precision)
    # The one place non-finite vertex coordinates are caught: NaN or inf, and coordinates so large
    # that the face's squared edges or area overflow (nothing downstream could measure it).
    nonfinite_face = ~(measurable(P) & np.isfinite(lmax2) & np.isfinite(A))
    many = np.flatnonzero(he_count >= 3)
    # Every edge in at most two faces and no face repeating a vertex (whose two sides of one edge
    # would pair with each other): each half-edge's only possible twin is its pair's other half.
    simple = not len(many) and not bool(np.any(src == dst))
    if not simple:
        duplicate = _repeated_rows(np.sort(F, axis=1))
    else:
        # Two faces on the same three vertices share each edge as a pair, so they are the pairs
        # whose third (opposite) corners are the same vertex.
        opp = F[:, [2, 0, 1]].ravel()
        dup = opp[g1] == opp[g2]
        duplicate = np.zeros(m, dtype=bool)
        duplicate[g1[dup] // 3] = True
        duplicate[g2[dup] // 3] = True
    nonmanifold_face = np.zeros(m, dtype=bool)
    nonmanifold_face[many // 3] = True
    inconsistent_face = np.zeros(m, dtype=bool)
    inconsistent_face[f1[~consistent]] = True
    inconsistent_face[f2[~consistent]] = True

    # Islands numbered by their smallest face index; faces of each island in increasing order.
    first_face = np.full(n_isl, m, dtype=np.int64)
    np.minimum.at(first_face, face_isl, np.arange(m))
    label_of = np.empty(n_isl, dtype=np.int64)
    label_of[np.argsort(first_face, kind="stable")] = np.arange(n_isl)
    fisl = label_of[face_isl]                              # island index per face
    order = np.argsort(fisl, kind="stable")                # faces grouped by island
    fbounds = np.searchsorted(fisl[order], np.arange(n_isl + 1))
    first_corner = np.empty(corner_vertex.max() + 1, dtype=np.int64)
    first_corner[corner_vertex[::-1]] = np.arange(3 * m)[::-1]
    vertex_of_cut = src[first_corner]
    # Island-local vertex ids: a cut vertex's rank among its island's cut vertices, by id.
    ncut = len(first_corner)
    cut_isl = fisl[first_corner // 3]
    cut_order = np.lexsort((np.arange(ncut), cut_isl))
    vbounds = np.searchsorted(cut_isl[cut_order], np.arange(n_isl + 1))
    local = np.empty(ncut, dtype=np.int64)
    local[cut_order] = np.arange(ncut) - vbounds[cut_isl[cut_order]]
    cv = corner_vertex.reshape(m, 3)[order]                # (m,3) cut ids, island by island
    tris_all = local[cv]

    # Boundary half-edges of the cut mesh: those with no reverse in cut vertex ids. A reverse
    # lies on the same mesh edge, so in a simple mesh only the pairs need comparing (np.isin
    # over all half-edges otherwise).
    if not simple:
        interior = None
    else:
        cdst = corner_vertex[(np.arange(3 * m) // 3) * 3 + (np.arange(3 * m) % 3 + 1) % 3]
        rev = (corner_vertex[g1] == cdst[g2]) & (cdst[g1] == corner_vertex[g2])
        interior = np.zeros(3 * m, dtype=bool)
        interior[g1[rev]] = True
        interior[g2[rev]] = True
        interior = interior.reshape(m, 3)[order].ravel()
    problem = (degenerate | nonfinite_face | duplicate | nonmanifold_face | inconsistent_face)
    if len(bowtie):
        problem |= np.isin(src, bowtie[:, 0]).reshape(m, 3).any(axis=1)
    bad_isl = np.bincount(fisl, problem, minlength=n_isl) > 0
    loops_of, topo_err = _all_boundary_loops(cv, fisl[order], n_isl, ncut, fbounds, ~bad_isl,
                                             local, interior)
    out = []
    for idx in range(n_isl):
        f0, f1 = fbounds[idx], fbounds[idx + 1]
        faces = order[f0:f1].astype(np.int64)
        tris = tris_all[f0:f1]
        vertices = vertex_of_cut[cut_order[vbounds[idx]:vbounds[idx + 1]]]
        err = None
        if bad_isl[idx]:
            err = _validate(idx, faces, tris, vertices, V, degenerate, nonfinite_face, duplicate,
                            nonmanifold_face, inconsistent_face, bowtie, face_isl[faces[0]])
        loops = ()
        if err is None:
            loops, err = loops_of[idx], topo_err(idx, faces)
        out.append(Island(idx, faces, vertices, tris, loops if err is None else (), err))
    return out


def _repeated_rows(T):
    """(m,) bool: rows of the (m,3) int array ``T`` that occur more than once."""
    order = np.lexsort((T[:, 2], T[:, 1], T[:, 0]))
    S = T[order]
    same = np.all(S[1:] == S[:-1], axis=1)
    rep = np.zeros(len(T), dtype=bool)
    rep[1:] |= same
    rep[:-1] |= same
    out = np.empty(len(T), dtype=bool)
    out[order] = rep
    return out


def _validate(idx, faces, tris, vertices, V, degenerate, nonfinite, duplicate, nonmanifold,
              inconsistent, bowtie, label):
    name = f"island {idx}"
    bad = faces[nonfinite[faces]]
    if len(bad):
        return NonFiniteError(f"{name}: {len(bad)} face(s) have NaN or infinite vertex coordinates, "
                              f"or {TOO_LARGE} (faces {_some(bad)}); fix or delete those "
                              "vertices", idx, bad)
    bad = faces[duplicate[faces]]
    if len(bad):
        return DuplicateFacesError(f"{name}: {len(bad)} faces repeat the same three vertices "
                                   f"(faces {_some(bad)}); merge or delete the duplicates",
                                   idx, bad)
    bad = faces[nonmanifold[faces]]
    if len(bad):
        return NonManifoldError(f"{name}: non-manifold edges (shared by 3 or more faces) at faces "
                                f"{_some(bad)}; split those edges or mark them as seams", idx, bad)
    bv = bowtie[bowtie[:, 1] == label, 0] if len(bowtie) else np.zeros(0, np.int64)
    if len(bv):
        bad = faces[np.isin(vertices[tris], bv).any(axis=1)]
        return NonManifoldError(f"{name}: non-manifold vertex (faces meet only at a point) at "
                                f"vertices {_some(bv)}; split the vertex (Mesh > Split) or "
                                "separate the parts", idx, bad)
    bad = faces[inconsistent[faces]]
    if len(bad):
        return OrientationError(f"{name}: {len(bad)} faces are oriented against their neighbours "
                                f"(faces {_some(bad)}); recalculate normals (Mesh > Normals > "
                                "Recalculate Outside)", idx, bad)
    bad = faces[degenerate[faces]]
    if len(bad):
        return DegenerateFacesError(f"{name}: {len(bad)} zero-area face(s) (faces {_some(bad)}); "
                                    "dissolve degenerate geometry (Mesh > Clean Up > Degenerate "
                                    "Dissolve)", idx, bad)
    return None


def _all_boundary_loops(cv, hisl, n_isl, ncut, fbounds, valid, local, interior=None):
    """Boundary loops of every valid island at once, and the topology check.

    Parameters
    ----------
    cv : (m,3) int, cut vertex ids of each face, faces grouped by island
    hisl : (m,) int, island of each face (grouped)
    valid : (n_isl,) bool, islands whose loops are wanted
    local : (ncut,) int, island-local id of each cut vertex
    interior : (3m,) bool or None, the half-edges (of ``cv``) with a reverse, when known

    Returns
    -------
    loops_of : list of tuples of (b,) int64 arrays (island-local ids), longest first
    topo_err : callable(idx, faces) -> ClosedIslandError, TopologyError or None
    """
    k = np.diff(fbounds)
    a = cv.ravel()
    b = cv[:, [1, 2, 0]].ravel()
    eisl = np.repeat(hisl, 3)
    boundary = ~np.isin(a * ncut + b, b * ncut + a) if interior is None else ~interior
    nb = np.bincount(eisl, boundary, minlength=n_isl).astype(np.int64)
    nv = np.bincount(_island_of_vertices(a, eisl, ncut), minlength=n_isl)
    n_edges = (3 * k + nb) // 2
    euler = nv - n_edges + k
    keep = boundary & valid[eisl]
    ba, bb = a[keep], b[keep]
    # Each boundary vertex has one outgoing boundary half-edge (pinched vertices were rejected).
    pos = np.full(ncut, -1, dtype=np.int64)
    pos[ba] = np.arange(len(ba))
    nxt = pos[bb]
    lisl = eisl[keep]
    start, loops_of = ordered_loops(nxt, lisl, local[ba], n_isl)
    loops_per_isl = np.bincount(lisl[start], minlength=n_isl) if len(start) else np.zeros(n_isl, int)
    genus2 = 2 - loops_per_isl - euler

    def topo_err(idx, faces):
        name = f"island {idx}"
        if nb[idx] == 0:
            return ClosedIslandError(f"{name} ({k[idx]} faces) is closed: it has no boundary and "
                                     "cannot be flattened; mark seams that cut it open", idx, faces)
        if genus2[idx] != 0:
            return TopologyError(f"{name} ({k[idx]} faces) has genus {genus2[idx] / 2:g} (handles "
                                 "or tunnels); mark seams across each handle so it becomes a disk "
                                 "(possibly with holes)", idx, faces)
        return None
    return loops_of, topo_err


def _island_of_vertices(a, eisl, ncut):
    """Island of each cut vertex used by the half-edges, one entry per distinct vertex."""
    isl = np.full(ncut, -1, dtype=np.int64)
    isl[a] = eisl
    return isl[isl >= 0]
