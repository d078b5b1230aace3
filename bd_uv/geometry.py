"""Per-face local geometry: each triangle isometrically laid in the plane.

The canonical local frame of face j has its origin at the first corner, e1 along the first edge and
e2 = n x e1 (Lipman 2012, eq. 4.1 with the frame's rotation kept separately, see ``frames``)."""
import numpy as np

from .array_calls import einsum, quiet


def _rows(A, idx):
    """``A[idx]`` for an integer index array: by ``take`` where the ids are signed integers
    (numpy 1.26 gathers rows by a fancy index ~4x slower; the same values and the same
    IndexError out of range), by the fancy index otherwise (unsigned ids, which ``take`` would
    refuse or wrap)."""
    idx = np.asarray(idx)
    return A.take(idx, axis=0) if idx.dtype.kind == "i" else A[idx]


def face_areas(V, F):
    """Area of each triangle.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array

    Returns
    -------
    A : (m,) float64
    """
    P = _rows(np.asarray(V), F)
    with np.errstate(invalid="ignore", over="ignore"):  # non-finite input is reported, not warned
        return 0.5 * _cross_norm(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])


def _cross_norm(a, b):
    """``np.linalg.norm(np.cross(a, b), axis=1)`` for (m,3) arrays, the same arithmetic in the
    same order (the same bits) without np.cross's axis handling, which costs more than the
    arithmetic on small meshes."""
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    c0 = a1 * b2 - a2 * b1
    c1 = a2 * b0 - a0 * b2
    c2 = a0 * b1 - a1 * b0
    return np.sqrt(c0 * c0 + c1 * c1 + c2 * c2)


def local_coordinates(V, F):
    """2D coordinates of each triangle's corners in its canonical local frame.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array

    Returns
    -------
    Z : (m,3) complex128
        Corner 0 at 0, corner 1 on the positive real axis, corner 2 in the upper half plane (for a
        non-degenerate face).
    """
    P = _rows(np.asarray(V, dtype=np.float64), F)
    return local_frame(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])


def corner_angles(Z):
    """(m,3) each corner's angle of the triangles with corners Z (m,3) complex, signed
    (negative in a flipped face); its absolute value is the interior angle."""
    d = np.roll(Z, -1, axis=1) - Z
    e = np.roll(Z, -2, axis=1) - Z
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.angle(e / d)


def local_frame(e01, e02):
    """``local_coordinates`` of faces given by their two edges from the first corner, e01 and
    e02 (m,3) float64."""
    # np.linalg.norm(e01, axis=1)'s sum in its order (the same bits), without its dispatch
    l01 = np.sqrt(e01[:, 0] * e01[:, 0] + e01[:, 1] * e01[:, 1] + e01[:, 2] * e01[:, 2])
    with quiet("invalid", "divide"):
        e1 = e01 / l01[:, None]
        x2 = einsum("ij,ij->i", e02, e1)
        y2 = _cross_norm(e1, e02)
    Z = np.zeros((len(e01), 3), dtype=np.complex128)
    Z[:, 1] = l01
    Z[:, 2] = x2 + 1j * y2
    return Z


def gradient_operators(Z):
    """Per-face gradient of a linear function in the local frame.

    For values ``s`` at the three corners, ``grad = G[j] @ s`` with ``G[j]`` 2x3.

    Parameters
    ----------
    Z : (m,3) complex array of local corner coordinates

    Returns
    -------
    G : (m,2,3) float64
    """
    d1 = Z[:, 1] - Z[:, 0]
    d2 = Z[:, 2] - Z[:, 0]
    a, b, c, d = d1.real, d1.imag, d2.real, d2.imag  # rows of the edge matrix E = [[a,b],[c,d]]
    det = a * d - b * c
    # E^-1 = [[d, -b], [-c, a]] / det times [[-1, 1, 0], [-1, 0, 1]] (corner values to the two
    # edge differences), written out: products by 1 and 0 are exact, so the same numbers as the
    # matrix product, without the stacking and the batched product's fixed cost.
    G = np.empty((len(Z), 2, 3))
    with quiet("invalid", "divide"):
        G[:, 0, 1] = d / det
        G[:, 0, 2] = -b / det
        G[:, 1, 1] = -c / det
        G[:, 1, 2] = a / det
        G[:, :, 0] = -G[:, :, 1] - G[:, :, 2]   # inf - inf on a zero-area face: NaN, quietly
    return G


def cycle_labels(nxt):
    """The cycles of a permutation (the boundary loops of a mesh or of a UV layout, each entry's
    successor along its loop), each labelled by its least member.

    Pointer doubling: after k steps each entry holds the least of the 2^k entries from it on, so
    about log2 of the longest cycle steps, each a few vectorised operations (no graph is built);
    up to ``WALK_BOUNDARY`` entries walked in Python instead (cheaper than the steps' calls).

    Parameters
    ----------
    nxt : (b,) int64, a permutation of 0..b-1

    Returns
    -------
    least : (c,) int64, the least member of each cycle, increasing
    label : (b,) int64, the cycle of each entry (0..c-1, numbered by least member, as
        ``scipy.sparse.csgraph.connected_components`` numbers them)
    """
    if len(nxt) <= WALK_BOUNDARY:
        walked = _walk_labels(nxt)
        if walked is not None:
            return walked
    least, ptr = np.arange(len(nxt)), np.asarray(nxt, dtype=np.int64)
    while True:
        lower = np.minimum(least, least[ptr])
        if np.array_equal(lower, least):
            break
        least, ptr = lower, ptr[ptr]
    least, label = np.unique(least, return_inverse=True)
    return least, label.ravel()


# Up to this many boundary half-edges the loops are walked one step at a time in Python (a few
# tenths of a microsecond a step); above, ranked by pointer jumping in whole-array steps (each a
# few numpy calls, ~0.3 ms on a 200-face island's 51 boundary edges).
WALK_BOUNDARY = 1024


def _walk_labels(nxt):
    """``cycle_labels`` one step at a time (short boundaries); None when ``nxt`` is not a
    permutation."""
    nl = np.asarray(nxt).tolist()
    if len(set(nl)) != len(nl) or (nl and (min(nl) < 0 or max(nl) >= len(nl))):
        return None
    label = [-1] * len(nl)
    least = []
    for i in range(len(nl)):
        if label[i] >= 0:
            continue
        c, j = len(least), i
        least.append(i)
        while label[j] < 0:
            label[j] = c
            j = nl[j]
    return np.array(least, dtype=np.int64), np.array(label, dtype=np.int64)


def ordered_loops(nxt, owner, verts, n_owners):
    """The cycles of the successor ``nxt`` (a permutation: the boundary half-edges of a mesh,
    each followed by the next along its loop), each from its least member, numbered by it (as
    ``cycle_labels``), handed out per owner (``owner`` (b,), 0..n_owners-1: the island of each
    half-edge) as arrays of ``verts`` (b,) along the loop, longest first (ties in that order).

    Returns
    -------
    start : (c,) int64, the least member of each loop, increasing
    loops_of : list (n_owners) of tuples of (len,) int64 arrays
    """
    if len(nxt) <= WALK_BOUNDARY:
        return _walk_loops(nxt, owner, verts, n_owners)
    return _ranked_loops(nxt, owner, verts, n_owners)


def _walk_loops(nxt, lisl, verts, n_isl):
    """``ordered_loops`` one step at a time."""
    nl = nxt.tolist()
    if len(set(nl)) != len(nl) or (nl and (min(nl) < 0 or max(nl) >= len(nl))):   # not a
        # permutation: the general path
        return _ranked_loops(nxt, lisl, verts, n_isl)
    seen = [False] * len(nl)
    starts, by_isl = [], [[] for _ in range(n_isl)]
    owner = lisl.tolist()
    for i in range(len(nl)):
        if seen[i]:
            continue
        seq, j = [], i
        while not seen[j]:
            seen[j] = True
            seq.append(j)
            j = nl[j]
        starts.append(i)
        by_isl[owner[i]].append(verts[seq].astype(np.int64))
    for loops in by_isl:
        loops.sort(key=len, reverse=True)
    return np.array(starts, dtype=np.int64), [tuple(loops) for loops in by_isl]


def _ranked_loops(nxt, lisl, verts, n_isl):
    """``_walk_loops``'s answer in whole-array steps: every half-edge ranked along its loop by
    pointer jumping, starting each loop at its least half-edge (the source of its first boundary
    half-edge in face order), as a depth-first walk from there would."""
    start, lab = cycle_labels(nxt)                         # the loops: the cycles of nxt
    n_loops = len(start)
    prev = np.empty(len(nxt), dtype=np.int64)
    prev[nxt] = np.arange(len(nxt))
    ptr = nxt.copy()
    ptr[prev[start]] = prev[start]                         # the loop's last vertex ends it
    rank = (ptr != np.arange(len(nxt))).astype(np.int64)
    while True:
        nptr = ptr[ptr]
        if np.array_equal(nptr, ptr):
            break
        rank = rank + rank[ptr]
        ptr = nptr
    ordr = np.lexsort((-rank, lab))
    lens = np.bincount(lab, minlength=n_loops)
    cuts = np.concatenate([[0], lens.cumsum()])
    loop_isl = lisl[start]
    by_isl = loop_isl.argsort(kind="stable")
    ibounds = loop_isl[by_isl].searchsorted(np.arange(n_isl + 1))
    verts = verts[ordr]
    loops_of = []
    for idx in range(n_isl):
        mine = by_isl[ibounds[idx]:ibounds[idx + 1]]
        loops = [verts[cuts[j]:cuts[j + 1]].astype(np.int64) for j in mine]
        loops.sort(key=len, reverse=True)
        loops_of.append(tuple(loops))
    return start, loops_of


# ``components`` hooks graphs of up to HOOK_VERTICES vertices itself (measured: 2x cheaper than
# scipy at 1.7k vertices, 3x dearer at 8k), handing a graph to scipy
# after HOOK_ROUNDS rounds (a mesh's graphs take ~10-20); larger graphs go to scipy directly,
# whose fixed cost is then small against the work.
HOOK_VERTICES = 4000
HOOK_ROUNDS = 40


def components(n, a, b):
    """Connected components of the undirected graph on 0..n-1 with edges (a[i], b[i]).

    Min-label hooking with pointer jumping, a few vectorised operations per round: on the graphs
    of a small mesh it is ~5x cheaper than building a sparse matrix for
    ``scipy.sparse.csgraph.connected_components`` (whose set-up is a fixed cost of ~0.5 ms), which
    takes graphs over ``HOOK_VERTICES`` vertices and those not done in ``HOOK_ROUNDS`` rounds.

    Returns
    -------
    (count, labels (n,) int64), numbered by each component's least vertex, as scipy numbers them
    """
    a = np.asarray(a, dtype=np.int64)
    b = np.asarray(b, dtype=np.int64)
    lab = np.arange(n if n <= HOOK_VERTICES else 0, dtype=np.int64)
    for _ in range(HOOK_ROUNDS if n <= HOOK_VERTICES else 0):
        la, lb = lab[a], lab[b]
        if not (la != lb).any():        # np.array_equal(la, lb), without its wrapper
            # Every edge joins equal labels: each component carries its least vertex's label,
            # so its least vertex is the one labelled itself; components are numbered in the
            # order of those (no sort).
            cs = (lab == np.arange(n)).cumsum()
            return (int(cs[-1]) if n else 0), (cs - 1)[lab]
        lo = np.minimum(la, lb)
        # Hook each label onto the least one it meets (both ends in one call).
        np.minimum.at(lab, np.concatenate([la, lb]), np.concatenate([lo, lo]))
        lab = lab[lab[lab]]             # lab[x] <= x throughout: jumping only lowers it
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components
    # The rows in int32 where they fit: the graph of a 500k-face chart's split (``split``'s
    # pieces) held ~49 MB at once from int64 COO, ~23 MB from this CSR. The same components.
    it = np.int32 if n < 2**31 - 1 else np.int64
    G = sp.csr_matrix((np.ones(len(a)), (a.astype(it), b.astype(it))), shape=(n, n))
    count, labels = connected_components(G, directed=False)
    return count, labels.astype(np.int64)
