"""Cut the mesh along seams and split it into validated islands.

An island is a set of faces connected across manifold, non-seam edges. Each island gets its own cut
vertices: corners of one input vertex share an island vertex only when they are connected around
that vertex without crossing a seam, so a seam through an island opens it up.
"""
from dataclasses import dataclass

import numpy as np

from ..errors import ClosedIslandError, InvalidMeshError, TopologyError
from ..geometry import components, face_areas, ordered_loops
from .arrays import (DEGENERATE_RATIO, as_indices, check_arrays, measurable,
                     thinner_than_precision)
from .faults import _repeated_rows, _validate


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


def _edge_keys(a, b, n):
    return np.minimum(a, b) * n + np.maximum(a, b)


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
