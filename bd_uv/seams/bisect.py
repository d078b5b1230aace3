"""Splitting the charts that fail, in batches: one level of Fiedler splits for every chart at
once (``bisect``, on polygons when given), or several levels while the restriction of a chart's
map to a piece still breaks S far (``split_deep``); the cost of cutting a vertex pair
(``edge_weight``). Used by ``auto.unwrap_auto``'s rounds.
"""
import numpy as np

from .charts import MARGIN, piece_stretch
from .split import fiedler_split_many
from ..trim import CHUNK

# Levels a failing chart is split at once while its restricted map still breaks S.
SPLIT_DEPTH = 4
# ... while the restricted map's stretch exceeds S by this factor (a piece's own map is better
# than the restriction of its chart's map: nearer S it is left to its own map).
DEEPER = 4.0
# ... but a piece holding at least this share of its chart's faces is split again while its
# restricted map breaks S at all (the factor MOST_DEEPER): the chart lost a sliver, so the
# piece's own map would be nearly the restriction and fail in the next round, one round (a map
# and a split of the large piece) later. A chart peeled a sliver a round took 13 rounds on
# suzanne, 10 on fandisk; 10 and 9 with this, the same charts.
MOST = 0.8
MOST_DEEPER = 1.0


class FaceCentroids:
    """Face centroids ``V[F].mean(axis=1)`` formed for the faces asked for (``cen[faces]``),
    the same bits row by row as the whole (m,3) array, which the seam
    search would otherwise hold throughout (12 MB on a 500k-face mesh) to read a few rows
    per split.

    With ``hold`` (the search's meshes that hold their face geometry, ``auto.GEOM_FACES``)
    the whole array is formed once and rows are read from it (the same bits: each row's own
    mean), and so are the distances between the centroids of each edge's two faces
    (``dual_lengths``), which every split weighs its dual graph by: a face is split ~2-8 times
    on its way to a chart, each time forming both again."""

    def __init__(self, V, F, hold=False):
        self.V, self.F = V, F
        self.held = self.dual = None
        if hold:
            self.held = self[np.arange(len(F))]

    def dual_lengths(self, E):
        """(e,) float64, the distance between the centroids of each edge's two faces (0 on a
        boundary edge), ``np.linalg.norm`` of their difference row by row, as
        ``split.fiedler_split_many`` forms it for the pairs it is given (the same bits); None
        where the centroids are not held."""
        if self.held is None:
            return None
        if self.dual is None or len(self.dual) != len(E.faces):
            f0, f1 = E.faces[:, 0], E.faces[:, 1]
            d = np.linalg.norm(self.held[f0] - self.held[np.maximum(f1, 0)], axis=1)
            d[f1 < 0] = 0.0
            self.dual = d
        return self.dual

    def __getitem__(self, faces):
        faces = np.asarray(faces)
        if faces.ndim != 1:
            return self.V[self.F[faces]].mean(axis=1)
        if self.held is not None:
            return self.held.take(faces, axis=0)
        if len(faces) <= CHUNK:
            return _mean3(self.V, self.F[faces])
        # ``CHUNK`` rows at a time (each row's own mean: the same bits): the (k,3,3) corner
        # positions of a 500k-face sphere's first split were 36 MB at once.
        out = np.empty((len(faces), 3))
        for i in range(0, len(faces), CHUNK):
            out[i:i + CHUNK] = _mean3(self.V, self.F[faces[i:i + CHUNK]])
        return out


def _mean3(V, Ff):
    """``V[Ff].mean(axis=1)`` to the bit: numpy's sum over that length-3 axis adds the corners
    in turn ((a + b) + c: no pairwise sum below 9 terms) and then divides by 3, as here, without
    the (k,3,3) gather and the strided reduction (half the time on a 4k-face batch)."""
    # (``take``: numpy's row gather by a fancy index is ~4x dearer; the same rows)
    return (V.take(Ff[:, 0], axis=0) + V.take(Ff[:, 1], axis=0) + V.take(Ff[:, 2], axis=0)) / 3


def split_deep(todo, E, cut, A, cen, S, poly=None, orders=None, big=None, curved=None):
    """Split charts, and split their pieces again while a chart's conformal map restricted to a
    piece (``piece_stretch``: no new solve) still breaks S by the factor ``DEEPER``.

    A piece whose restricted map is nearer S is left for the next round to map on its own; the
    restriction saves the rounds (and solves) a chart far beyond S would take one split at a
    time. A piece holding most of its chart (``MOST``) is split again while its restricted map
    breaks S at all: its own map would hardly differ. Pieces on flipped faces of the chart's
    map are left to their own map too. Every level splits all its pieces in one batch
    (``bisect``).

    A chart without a map (None: too large to map, a sphere, an open chart) has its pieces of
    more than ``big`` faces split again, to the same depth: the next round would split them
    unmapped anyway, one level a round (a 500k-face sphere took 8 rounds to come down to
    pieces it maps, each round finding the charts of the whole remaining mesh again).

    Parameters
    ----------
    todo : list of (faces (k,) int64 sorted global face ids, sigma (k,2) float64 or None): the
        charts, with their map's singular values per face (``ChartMaps.sigma``); None: split
        once, and its pieces again while they hold more than ``big`` faces
    big : int, optional (None: pieces of charts without a map are not split again)
    curved : ((m,) float64, float, int), optional: each face's share of the curvature, a limit
        and a size: a piece of a chart without a map of at least that many faces whose shares
        sum to more than the limit is split again too

    Returns
    -------
    (len(todo),) bool, whether each chart was split

    ``orders``: the mesh's ``orders.Orders`` for the Fiedler systems, optional (``bisect``).
    """
    split = np.zeros(len(todo), dtype=bool)
    stack = [(faces, j) for j, (faces, _) in enumerate(todo)]
    extra = {} if orders is None else {"orders": orders}
    for _ in range(SPLIT_DEPTH):
        sides = bisect([f for f, _ in stack], E, cut, A, cen, poly, **extra)
        pieces = []                         # (piece, chart) of charts with a map
        large = []                          # ... of charts without, of more than ``big`` faces
        for (f, j), two in zip(stack, sides):
            if two is None:
                continue
            split[j] = True
            if todo[j][1] is not None:
                pieces += [(piece, j) for piece in two]
            else:
                large += [(piece, j) for piece in two
                          if (big is not None and len(piece) > big)
                          or (curved is not None and len(piece) >= curved[2]
                              and curved[0][piece].sum() > curved[1])]
        if not pieces:
            stack = large
            if not stack:
                break
            continue
        # Every piece's restricted stretch at once.
        sig = np.concatenate([todo[j][1].take(todo[j][0].searchsorted(piece), axis=0)
                              for piece, j in pieces])
        fa = np.concatenate([piece for piece, _ in pieces])
        label = np.repeat(np.arange(len(pieces)), [len(piece) for piece, _ in pieces])
        st = piece_stretch(sig, A[fa], label, len(pieces))
        share = np.array([len(piece) / len(todo[j][0]) for piece, j in pieces])
        deeper = np.where(share >= MOST, MOST_DEEPER, DEEPER)
        stack = [(piece, j) for (piece, j), s_, d_ in zip(pieces, st, deeper)
                 if np.isfinite(s_) and s_ > d_ * S * MARGIN and len(piece) > 1] + large
        if not stack:
            break
    return split


def edge_weight(E, pairs, n, diag=None):
    """Cost of cutting each vertex pair (length times crease discount; inside a polygon, a
    million times that, so cut graphs run along polygon edges)."""
    k = E.keys(pairs, n)
    w = np.where(k >= 0, E.length[k] * E.cost[k], np.inf)
    if diag is not None:
        w = np.where((k >= 0) & diag[np.maximum(k, 0)], 1e6 * w, w)
    return w


def polygon_edges(polygons, E, m):
    """Checked polygon ids (m,) int64 (None without) and the edges inside a polygon (e,) bool."""
    diag = np.zeros(len(E.ends), dtype=bool)
    if polygons is None:
        return None, diag
    poly = np.asarray(polygons)
    if poly.shape != (m,) or not np.issubdtype(poly.dtype, np.integer):
        raise ValueError(f"polygons must be ({m},) integers, one polygon id per triangle, got "
                         f"shape {poly.shape} of {poly.dtype}")
    poly = poly.astype(np.int64)
    inner = E.faces[:, 1] >= 0
    diag[inner] = poly[E.faces[inner, 0]] == poly[E.faces[inner, 1]]
    return poly, diag


def _edges_of(fe, e):
    """``np.unique(fe)`` of edge ids in ``[0, e)``: marked in an (e,) array and read back in
    order where they are at least an eighth of the edges (a split of most of a small mesh: no
    sort), numpy's sort otherwise, its duplicates dropped by ``compress`` (numpy 1.26's boolean
    index, which ``np.unique`` uses, is ~3x dearer)."""
    if 8 * len(fe) >= e:
        mark = np.zeros(e, dtype=bool)
        mark[fe] = True
        return mark.ravel().nonzero()[0].astype(fe.dtype, copy=False)
    s = np.sort(fe)
    keep = np.empty(len(s), dtype=bool)
    keep[:1] = True
    np.not_equal(s[1:], s[:-1], out=keep[1:])
    return s.compress(keep)


def bisect(pieces, E, cut, A, cen, poly=None, orders=None):
    """Split charts by ``fiedler_split_many`` (all at once) and mark the new seams.

    With ``poly`` (polygon of each face) the split runs on the polygons (each one node of the
    dual graph, its area and area-weighted centroid), so no polygon is cut.

    Parameters
    ----------
    pieces : list of (k_i,) int64, sorted global face ids of disjoint charts
    orders : orders.Orders, optional: the Fiedler systems (on faces, not polygons) factor in
        the order a piece's chart was given, or afresh (``orders.fiedler_solver``)

    Returns
    -------
    list of (faces_a, faces_b) sorted global face ids of the two sides, or None where a chart
    is not split
    """
    out = [None] * len(pieces)
    if not pieces:
        return out
    m = len(E.face_edges)
    sizes = np.array([len(f) for f in pieces], dtype=np.int64)
    fa = np.concatenate(pieces)
    owner = np.repeat(np.arange(len(pieces)), sizes)
    # Local face ids and the node pairs in int32 (E's index type): the first round's split of
    # a 500k-face sphere held ~25 MB more of them in int64.
    local = np.full(m, -1, dtype=E.face_edges.dtype)
    local[fa] = np.arange(len(fa))
    fe = _edges_of(E.face_edges.take(fa, axis=0).ravel(), len(E.ends))
    fe = fe[(E.faces[:, 1].take(fe) >= 0) & ~cut.take(fe)]
    f01 = E.faces.take(fe, axis=0)          # (int32 ids: ``take``, not numpy's slower gather)
    la, lb = local.take(f01[:, 0]), local.take(f01[:, 1])
    del f01
    inside = (la >= 0) & (lb >= 0)
    # (``compress``: numpy 1.26's boolean index is ~3x dearer, the same elements)
    inside[inside] = owner[la.compress(inside)] == owner[lb.compress(inside)]
    fe, la, lb = fe.compress(inside), la.compress(inside), lb.compress(inside)
    # Nodes: the faces, or the polygons (grouped by chart either way).
    if poly is None:
        node = None
        mass, pcen = A[fa], cen[fa]
    else:
        key = owner * (int(poly.max()) + 1) + poly[fa]
        _, node = np.unique(key, return_inverse=True)
        node = node.ravel()
        mass = np.bincount(node, A[fa])
        c = cen[fa]
        pcen = np.stack([np.bincount(node, A[fa] * c[:, d]) for d in range(3)], 1)
        pcen /= np.maximum(mass, 1e-300)[:, None]
    if node is None:
        nowner = owner
    else:
        nowner = np.zeros(len(mass), dtype=np.int64)
        nowner[node] = owner
    offsets = nowner.searchsorted(np.arange(len(pieces) + 1))
    na, nb = (la, lb) if node is None else (node[la], node[lb])     # each face its own node
    across = na != nb
    if across.all():
        pairs, w = np.stack([na, nb], 1), fe
    else:
        pairs, w = np.stack([na[across], nb[across]], 1), fe[across]
    del na, nb, across
    keys = None if orders is None or poly is not None else orders.face_keys(pieces, fa)
    before = None if keys is None else keys.copy()
    # The dual edges' lengths where held (faces are the nodes: each pair one mesh edge's)
    dual = cen.dual_lengths(E) if node is None and isinstance(cen, FaceCentroids) else None
    side, split = fiedler_split_many(mass, pcen, offsets, pairs, E.length.take(w),
                                     E.cost.take(w), keys, None if dual is None else dual.take(w))
    if keys is not None:
        orders.faces_ordered(pieces, fa, before, keys)
    del pairs, w
    fside = side if node is None else side[node]
    new = fe[fside[la] != fside[lb]]
    cut[new[split[owner[local[E.faces[new, 0]]]]]] = True
    for j in split.ravel().nonzero()[0]:
        f = pieces[j]
        sj = fside[local[f]]
        out[j] = (f[sj], f[~sj])
    return out


