"""Elimination orders of the seam search's conformal-map systems, reused from chart to chart.

Every LSCM system of the search (``charts.chart_maps``) is a piece or a union of charts already
mapped, and qdldl orders each afresh (SuiteSparse AMD on its 2n unknowns): most of the
factorisation's time (dino's 27 systems: 143 ms CPU in ``qdldl.Solver``, 24 of them the numeric
factor; fandisk's 24: 309 and 126). Here a mesh vertex keeps a key, its place in the last
order it was given, and a system's unknowns are eliminated in the order of their vertices' keys
(u and v of a vertex side by side, ``solvers.ordered_ldl``):

- a chart with a vertex never ordered gets a fresh order: AMD of its vertex graph (half the
  unknowns of the system's own), its vertices keyed by it and its faces made one block;
- a piece of an ordered chart (the search splits it) keeps its chart's order restricted to it:
  the fill of an order restricted to a subgraph is within the fill of the whole;
- a union of charts of different blocks (merging tests it) keeps each chart's order and puts
  the vertices where blocks meet (the seam the union removes) last, as nested dissection does;
  they are keyed after everything so far and the union's faces made one block.

An order is refused when its factor would hold more than ``SLACK`` times the entries per
unknown of the fresh orders so far (the elimination tree gives the count before the numeric
factor); that system is ordered afresh (AMD of its vertex graph) and its vertices keyed by it.
The order decides only rounding (~1e-15 relative): the maps, and so the charts, are those of
qdldl's order (the same added seams bit for bit on suzanne, cow, dino, fandisk and camel).
Where ``ordered_ldl`` cannot run, ``Orders.of`` is None and qdldl orders every system.
"""
import numpy as np

from ..solvers import ordered_ldl, radix
from ..solvers.lscm import spd_solver
from .compressed import compressed

# Factor entries per unknown a reused order may reach, relative to the fresh orders' most
# (1.5 let fandisk's merged unions reach 1.5-2x the fill of AMD's order and cost more than it).
SLACK = 1.2
# Orders are reused in a batch of at most this many vertices (``charts.chart_maps``; a larger
# batch is factored in qdldl's order), and kept for a mesh of at most MESH_VERTICES vertices
# (``Orders.of``): a reused or vertex-graph order fills up to SLACK times more than AMD's, and
# the large batches' factors are the search's memory peaks. Measured: dino subdivided to 500k
# faces peaked at 470 MB with every batch reusing orders, 432 MB with batches up to 50k
# vertices, against main's 423; cow subdivided twice (46k vertices) 229 MB with batches up to
# 12.5k, against 223. Memory is where meshes that large miss xatlas (344 MB on dino-sub3); the
# small ones miss its time.
BATCH_VERTICES = 12_500
MESH_VERTICES = 20_000
# Keys of the vertices put last in a union (above any key given).
LAST = 1 << 50


def _starts(parts):
    """The offset of each of ``parts`` (arrays, none empty) in their concatenation."""
    at = np.zeros(len(parts), np.int64)
    if len(parts) > 1:
        at[1:] = np.cumsum([len(p) for p in parts[:-1]])
    return at


class Orders:
    """Keys of a mesh's vertices and blocks of its faces (``-1``: never ordered).

    Attributes
    ----------
    key : (n,) int64, block : (m,) int32
    face_key, face_block : (m,) int32, the same for the faces' Fiedler systems
    given : int, keys handed out so far; blocks : int, blocks made so far
    fill : float, the most factor entries per unknown of a fresh order (0 before the first)
    """

    def __init__(self, n, m):
        self.key = np.full(n, -1, np.int64)
        # Per face int32 (ranks within one system, block counts: far below 2^31): 6 MB on a
        # 500k-face mesh rather than 12.
        self.block = np.full(m, -1, np.int32)
        self.given = self.blocks = 0
        self.fill = 0.0
        self.face_key = np.full(m, -1, np.int32)
        self.face_block = np.full(m, -1, np.int32)

    def face_keys(self, pieces, fa):
        """Keys of the faces ``fa`` (the ``pieces`` concatenated) for their Fiedler systems: a
        piece whose faces all come from one order keeps it, the others get -1 (their system is
        ordered afresh, ``fiedler_solver``). Hand the keys back with ``faces_ordered``."""
        keys = self.face_key[fa]
        # Every piece's least and largest block at once (``reduceat`` over the pieces, none
        # empty), not two reductions a piece (a small search's splits: ~100 pieces a call).
        at = _starts(pieces)
        b = self.face_block[fa]
        lo, hi = np.minimum.reduceat(b, at), np.maximum.reduceat(b, at)
        for j in ((lo < 0) | (lo != hi)).ravel().nonzero()[0].tolist():
            keys[at[j]:at[j] + len(pieces[j])] = -1
        return keys

    def faces_ordered(self, pieces, fa, before, keys):
        """After the Fiedler solves: the faces' keys as ordered (``keys``, written by
        ``fiedler_solver``); a piece whose keys changed (ordered afresh) is one block now."""
        self.face_key[fa] = keys
        at = _starts(pieces)
        changed = np.logical_or.reduceat(before != keys, at)
        for j in changed.ravel().nonzero()[0].tolist():
            self.face_block[pieces[j]] = self.blocks
            self.blocks += 1

    @classmethod
    def of(cls, n, m):
        """Orders for a mesh of n vertices and m faces, or None where the ordered
        factorisation cannot run (``ordered_ldl.available``) or the mesh has more than
        ``MESH_VERTICES`` vertices."""
        return cls(n, m) if n <= MESH_VERTICES and ordered_ldl.available() else None

    def keys(self, charts, voff, gv=None):
        """Keys of the batch's vertices (chart after chart, ``voff`` their offsets; ``gv`` their
        mesh vertices, optional), giving fresh orders and ordering unions as the module says.
        Returns (nv,) int64 and a (k,) bool array: the charts ordered afresh."""
        # Which charts have a vertex never ordered, and which hold faces of several blocks (a
        # union), for all charts at once (``reduceat``; no chart is empty). A union's new keys
        # are never -1, so neither test changes as the unions are keyed below.
        if gv is None:
            gv = np.concatenate([c.vertices for c in charts])
        gk = self.key[gv]
        fresh = np.logical_or.reduceat(gk < 0, voff[:-1])
        fb = self.block[np.concatenate([c.faces for c in charts])]
        foff = _starts([c.faces for c in charts])
        union = (np.minimum.reduceat(fb, foff) != np.maximum.reduceat(fb, foff)) & ~fresh
        if not union.any():
            vk = gk                         # no key changes before the fresh charts'
        else:
            vk = np.empty(int(voff[-1]), np.int64)
            for j, c in enumerate(charts):
                if fresh[j]:
                    continue
                k = self.key[c.vertices]    # as keyed by the unions before this one
                if union[j]:                # a union: where blocks meet goes last
                    fb = self.block[c.faces]
                    # A vertex's corners all of one block iff count * sum(b^2) == sum(b)^2
                    # (exact: integers far below 2^53).
                    b = np.repeat((fb - fb.min()).astype(np.float64), 3)
                    t, nv = c.tris.ravel(), len(k)
                    s1 = np.bincount(t, b, nv)
                    sep = np.flatnonzero(np.bincount(t, minlength=nv) * np.bincount(t, b * b, nv)
                                         != s1 * s1)
                    k[sep] += LAST
                    rank = np.empty(len(sep), np.int64)
                    rank[k[sep].argsort(kind="stable")] = np.arange(len(sep))
                    self.key[c.vertices[sep]] = self.given + rank
                    self.given += len(sep)
                    self._block(c.faces)
                vk[voff[j]:voff[j + 1]] = k
        if fresh.any():
            self._fresh([charts[j] for j in fresh.ravel().nonzero()[0]])
            for j in fresh.ravel().nonzero()[0]:
                vk[voff[j]:voff[j + 1]] = self.key[charts[j].vertices]
        return vk, fresh

    def solved(self, charts, runs, out, fresh):
        """After a batch's solves: each run of charts ``runs[i]`` gave ``out[i]`` = (fill,
        ranks, free vertices (global ids)) of ``ordered_solver``. Charts ordered afresh (here or
        by a refused order) raise ``fill``; a run ordered afresh keys its vertices by it."""
        for (a, b), (fill, rank, gv) in zip(runs, out):
            if rank is not None:
                self.key[gv] = self.given + rank
                self.given += len(rank)
                for c in charts[a:b]:
                    self._block(c.faces)
            if rank is not None or fresh[a:b].all():
                self.fill = max(self.fill, fill if fill is not None else 0.0)

    def _block(self, faces):
        self.block[faces] = self.blocks
        self.blocks += 1

    def _fresh(self, charts):
        """AMD of the charts' vertex graphs (one block-diagonal pattern); their vertices keyed
        in its order (the batch after every key so far), each chart's faces one block."""
        nvs = np.array([len(c.vertices) for c in charts])
        off = np.concatenate([[0], nvs.cumsum()])
        t = np.concatenate([c.tris + off[j] for j, c in enumerate(charts)])
        a, b = t.ravel(), t.take([1, 2, 0], axis=1).ravel()
        n = int(off[-1])
        # The vertex graph's canonical compressed pattern (what ``sp.csc_matrix`` of these
        # pairs holds: sorted, duplicates summed), without scipy's COO conversion (~0.3 ms).
        _, indices, indptr = compressed(np.concatenate([b, a]), np.concatenate([a, b]),
                                        np.ones(2 * len(a)), n)
        p = ordered_ldl.amd(indptr, indices, n)
        rank = np.empty(n, np.int64)
        rank[p if p is not None else np.arange(n)] = np.arange(n)
        for j, c in enumerate(charts):
            self.key[c.vertices] = self.given + rank[off[j]:off[j + 1]]
            self._block(c.faces)
        self.given += n


def ordered_solver(A, keys, budget):
    """Solve of the LSCM system A (``lscm.Upper``: its upper triangle as triplets, unknowns
    ``[u; v]`` of the free vertices) eliminated in the order of ``keys`` (the free vertices'
    keys, u and v of a vertex side by side). With ``budget`` > 0, an order whose factor would
    hold more than ``budget`` entries per unknown is refused and the system ordered afresh (AMD
    of its vertex graph, the u block's pattern); ``spd_solver`` where even that fails. The
    triplets are compressed (``Upper.csc``) only for those two: ``ordered_ldl.Factor`` sorts
    them in its own order, and the same matrix in any triplet order is factored to the same bits.

    Returns
    -------
    (callable b -> x, factor entries per unknown of the order used (None: ``spd_solver``),
     the fresh order's ranks of the free vertices or None)
    """
    n = A.n
    f = _factor(A, keys)
    if f is not None and (budget <= 0 or f.lnz <= budget * n) and f.factor():
        return f.solve, f.lnz / max(n, 1), None
    nf = n // 2
    # AMD reads the pattern of ``A.csc()`` (its indptr and row indices), formed here as that
    # does, without the scipy matrix (its constructor: ~50 us), built only for ``spd_solver``.
    order = radix.order(A.cols * n + A.rows, n * n)
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.bincount(A.cols, minlength=n).cumsum(out=indptr[1:])
    p = ordered_ldl.amd(indptr[:nf + 1], A.rows[order[:indptr[nf]]], nf)
    del order
    if p is not None:
        rank = np.empty(nf, np.int64)
        rank[p] = np.arange(nf)
        f = _factor(A, rank)
        if f is not None and f.factor():
            return f.solve, f.lnz / max(n, 1), rank
    return spd_solver(A.csc(), upper=True), None, None


def _factor(A, keys):
    # The unknowns u, v of each vertex in the stable order of the vertices' keys, the u of
    # vertices with equal keys (one vertex of two charts in a batch) before their v: the
    # stable order of (2 rank, 2 rank + 1) over the keys' dense ranks, as it was formed from
    # ``np.unique``; where no two keys are equal it is each vertex's u then its v.
    o, r, nr = _ranks(keys)
    if r is None:
        perm = np.empty(2 * len(o), np.int64)
        perm[0::2], perm[1::2] = o, o + len(o)
    else:
        perm = radix.order(np.concatenate([2 * r, 2 * r + 1]), 2 * nr)
    f = ordered_ldl.Factor(A.rows, A.cols, A.vals, A.n, perm)
    return f if f.lnz >= 0 else None


def _ranks(keys):
    """The stable order of ``keys``, their dense ranks (``np.unique``'s inverse; None where no
    two keys are equal) and the number of distinct keys: one sort, not ``np.unique``'s."""
    o = keys.argsort(kind="stable")
    s = keys[o]
    new = s[1:] != s[:-1]
    if new.all():
        return o, None, len(o)
    rs = np.zeros(len(o), np.int64)
    new.cumsum(out=rs[1:])
    r = np.empty(len(o), np.int64)
    r[o] = rs
    return o, r, int(rs[-1]) + 1 if len(o) else 0


def _stable_order(keys):
    """``keys.argsort(kind="stable")`` of non-negative integer keys by ``radix.order`` (numpy
    sorts 32-bit keys by timsort; the stable order is unique, so it is the same order)."""
    return radix.order(keys, int(keys.max()) + 1 if len(keys) else 1)


def fiedler_solver(rows, cols, vals, keys, upper):
    """Solve of a Fiedler system (its upper triangle as triplets ``rows``, ``cols``, ``vals``,
    one node a face; ``upper()`` the canonical csc matrix, duplicates summed, as ``compressed``
    forms it from them) in the order of its nodes' ``keys``; where a key is -1 the system is
    ordered afresh (AMD) and ``keys`` (a view the caller reads back) rewritten with it. A
    piece of a chart keeps the chart's order: the dual graph of a piece is a subgraph of the
    chart's, so its fill is within the chart's.
    ``spd_solver`` where the factorisation fails.

    Where every key is given, the triplets go to ``ordered_ldl.Factor`` as they are (it sorts
    them in its own order: the same compressed matrix, the same bits as from ``upper()``),
    unless two share a place (two faces with two edges in common), which ``upper()`` sums."""
    k = len(keys)
    if (keys >= 0).all():
        # The keys' stable order (the radix order of their dense ranks, as it was formed)
        f = ordered_ldl.Factor(rows, cols, vals, k, _stable_order(keys))
        if not f.repeated():
            return f.solve if f.lnz >= 0 and f.factor() else spd_solver(upper(), upper=True)
    # ``upper()``'s arrays (``compressed``, as it forms them), without its scipy matrix
    # (~50 us), which only ``spd_solver`` needs.
    data, indices, indptr = compressed(cols, rows, vals, k)
    if (keys < 0).any():
        p = ordered_ldl.amd(indptr, indices, k)
        if p is not None:
            keys[p] = np.arange(k)
    if (keys >= 0).all():
        cols = np.repeat(np.arange(k, dtype=np.int64), np.diff(indptr))
        f = ordered_ldl.Factor(indices.astype(np.int64), cols, data, k, _stable_order(keys))
        if f.lnz >= 0 and f.factor():
            return f.solve
    return spd_solver(upper(), upper=True)
