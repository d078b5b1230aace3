"""Bottom-up: neighbouring charts merged pairwise while the union's conformal map still passes
(``charts.chart_maps``: flip-free, stretch within S, mean within ``charts.mean_cap(C)``, boundary
not crossing itself)."""
import hashlib

import numpy as np

from .charts import MARGIN, chart_maps, mean_cap
from .topology import charts
from .unions import union_charts
from ..solvers import radix
from ..trim import release_memory

# Rounds of pairwise merging (each merges a matching of neighbouring charts).
MERGE_ROUNDS = 15
# A union whose conformal map stretches beyond this many S: the charts around its two are not
# tried together again (a larger union around them rarely stretches less). 1.1 rather than 1.5:
# 10 % less time on dino and fandisk for one chart more or less (dino 34 -> 36, camel 28 -> 29,
# armadillo 42 -> 41; seams within 2 %).
HOPELESS = 1.1
# Matchings of neighbouring chart pairs tested together in one merging round.
MERGE_LAYERS = 1



def chart_key(chart):
    """A disk chart as it stands: a digest of its sorted faces, its vertex and boundary loop
    counts (a seam kept inside the faces, a material boundary, shows in both). 16 bytes of
    digest, not the faces: the search's failed charts cover a large mesh several times over."""
    return (hashlib.blake2b(chart.faces, digest_size=16).digest(), len(chart.faces),
            len(chart.vertices), len(chart.loops[0]))


def merge_charts(V, F, E, cut, keep, invalid, S, C, rounds=None, group=None, known=None,
                 geom=None, failed=None, orders=None):
    """Merge neighbouring charts pairwise while the union's conformal map still passes.

    Each round tests a matching of neighbouring pairs (dearest shared seam first: length times
    cost, so seams along creases are the last to go) in one
    batched solve; a pair that fails is not tried again while both charts stay as they are.

    Parameters
    ----------
    keep : (e,) bool, seams never removed (marked seams, material boundaries)
    S, C : float, a union passes with stretch within ``MARGIN`` S, mean distortion within
        ``mean_cap(C)``, no flipped face and no boundary crossing
    group : (m,) int64, optional: only pairs with a chart in a group (>= 0) are tried, and
        never two charts of one group (the pieces of a chart split because its certified map
        failed: their union is that chart again)
    known : dict, optional: the conformal maps of the unions that pass go in
        (``ChartMaps.remember``), those of the charts merged go out
    geom : charts.FaceGeometry of (V, F), optional
    failed : dict, optional, ``chart_key`` -> max stretch of disks whose conformal map
        failed this test before (the search's, which then split them): a union that is one
        fails without a new solve (the same pairs are tried and the same charts come out)
    orders : orders.Orders of the mesh, optional: the unions' solves reuse their charts'
        elimination orders (``charts.chart_maps``)

    Returns
    -------
    list of topology.Chart: the charts of ``cut`` after merging, as ``topology.charts(F, E,
    cut)`` finds them (the caller need not find them again)
    """
    failed = {} if failed is None else failed
    # The counts of the failed charts: a union of other counts is not hashed (``chart_key``).
    sizes = {key[1:] for key in failed}
    tried = set()
    # A face of each of two charts whose union was far beyond S: charts holding them are not
    # tried together again (a union of larger charts around them fares no better).
    far_a, far_b = [], []
    chs = charts(F, E, cut)
    original = keep
    for _ in range(MERGE_ROUNDS if rounds is None else rounds):
        release_memory(len(F))              # the last round's freed heap (its factors' arrays)
        # Each face's chart, each chart's first face and size, at once (not a few numpy calls
        # a chart a round: a small mesh's merging has 30-100 charts and ~15 rounds).
        nfc = [len(c.faces) for c in chs]
        label = np.empty(len(F), dtype=np.int64)
        if chs:
            label[np.concatenate([c.faces for c in chs])] = np.repeat(np.arange(len(chs)), nfc)
        firsts = [int(c.faces[0]) for c in chs]
        ident = list(zip(firsts, nfc))
        good = np.array([c.kind == "disk" for c in chs], dtype=bool) & ~invalid[firsts]
        inner = (E.faces[:, 1] >= 0) & cut & ~original
        fi = E.faces[inner]         # (rows, then ``take``: numpy's mixed index is ~4x dearer)
        la, lb = label.take(fi[:, 0]), label.take(fi[:, 1])
        diff = (la != lb) & good[la] & good[lb]
        if group is not None:
            ga, gb = group.take(fi[:, 0]), group.take(fi[:, 1])
            diff &= ((ga >= 0) | (gb >= 0)) & (ga != gb)
        if not diff.any():
            return chs
        ei = inner.ravel().nonzero()[0][diff]
        la, lb = np.minimum(la[diff], lb[diff]), np.maximum(la[diff], lb[diff])
        uk, inv, _ = radix.unique(la * len(chs) + lb, len(chs) ** 2)   # np.unique's
        shared = np.bincount(inv, E.length[ei] * E.cost[ei])
        fa, fb = label[np.array(far_a, np.int64)], label[np.array(far_b, np.int64)]
        hopeless = _member(uk, np.minimum(fa, fb) * len(chs) + np.maximum(fa, fb))
        # Matchings ("layers"): dearest shared seam first, each chart in at most one pair of a
        # layer; every layer's unions are tested in one batched solve.
        used = np.zeros((MERGE_LAYERS, len(chs)), dtype=bool)
        busy = [set() for _ in range(MERGE_LAYERS)]       # the charts of each layer's pairs
        layers = [[] for _ in range(MERGE_LAYERS)]
        ukl, hl = uk.tolist(), hopeless.tolist()
        for p in np.lexsort((uk, -_quantize(shared))).tolist():
            x, y = divmod(ukl[p], len(chs))
            if hl[p] or (ident[x], ident[y]) in tried:
                continue
            lay = next((i for i in range(MERGE_LAYERS)
                        if x not in busy[i] and y not in busy[i]), None)
            if lay is None:
                continue
            busy[lay].update((x, y))
            layers[lay].append(p)
            tried.add((ident[x], ident[y]))
        disks = []                          # (union chart, trial cut, its pair's index in uk)
        for lay, chosen in enumerate(layers):
            if not chosen:
                continue
            used[lay, list(busy[lay])] = True
            trial = cut.copy()
            gone = np.zeros(len(uk), dtype=bool)
            gone[chosen] = True
            gone = gone[inv]                # np.isin(inv, chosen)
            trial[ei[gone]] = False
            if E.fans is not None:          # the unions from their two charts (``unions``)
                chosen = np.array(chosen, dtype=np.int64)
                at = chosen.argsort()
                owner = at[chosen[at].searchsorted(inv[gone])]
                for i, c in union_charts(F, E, chs, label, uk[chosen] // len(chs),
                                         uk[chosen] % len(chs), ei[gone], owner, trial):
                    if c.kind == "disk":
                        disks.append((c, trial, int(chosen[i])))
                continue
            faces = used[lay][label].ravel().nonzero()[0]
            for c in charts(F, E, trial, faces):
                lab = label[c.faces]
                other = lab[lab != lab[0]]
                if c.kind == "disk" and len(other):
                    a, b = min(lab[0], other[0]), max(lab[0], other[0])
                    disks.append((c, trial, int(uk.searchsorted(a * len(chs) + b))))
        if not disks:
            if not any(layers):
                return chs
            continue
        # Unions the search already mapped and split fail as they did; the rest in one solve.
        stretch = np.array([failed.get(chart_key(c), np.nan)
                            if (len(c.faces), len(c.vertices), len(c.loops[0])) in sizes
                            else np.nan for c, _, _ in disks])
        ok = np.zeros(len(disks), dtype=bool)
        new = np.isnan(stretch).ravel().nonzero()[0]
        if len(new):
            union = [disks[j][0] for j in new]
            cm = chart_maps(V, union, geom, limits=(S * MARGIN, mean_cap(C)), orders=orders)
            ok[new] = (np.isfinite(cm.max_distortion) & (cm.max_stretch <= S * MARGIN)
                       & (cm.crossings == 0) & (cm.mean_distortion <= mean_cap(C)))
            stretch[new] = cm.max_stretch
            if known is not None:
                cm.remember(union, ok[new], known)
        pair = np.array([p for _, _, p in disks], dtype=np.int64)
        px, py = uk[pair] // len(chs), uk[pair] % len(chs)
        for j in (~(stretch <= HOPELESS * S)).ravel().nonzero()[0]:
            far_a.append(int(chs[px[j]].faces[0]))
            far_b.append(int(chs[py[j]].faces[0]))
        merged = np.zeros(len(chs), dtype=bool)
        # Accept passing unions, dearest removed seam first (the pair's shared seam), each chart
        # merged once per round.
        gain = shared[pair]
        unions = []
        accepted = np.zeros(len(uk), dtype=bool)     # the pairs merged: their seams go at once
        okl, pxl, pyl = ok.tolist(), px.tolist(), py.tolist()
        for j in np.lexsort((np.arange(len(gain)), -_quantize(gain))).tolist():
            x, y = pxl[j], pyl[j]
            if not okl[j] or merged[x] or merged[y]:
                continue
            merged[x] = merged[y] = True
            accepted[pair[j]] = True
            unions.append(disks[j][0])
            # The two charts' maps are no final chart's now (merging never splits): dropped,
            # not held to the final unwrap (on a 500k-face mesh 14 MB of 22).
            for c in (chs[x], chs[y]) if known is not None else ():
                known.pop(c.faces.tobytes(), None)
        cut[ei[accepted[inv]]] = False
        # The charts after this round: the unions (as found on the trial cut, which agrees with
        # the new cut on their faces) and every chart not merged, as they were.
        chs = sorted([c for j, c in enumerate(chs) if not merged[j]] + unions,
                     key=lambda ch: int(ch.faces[0]))
    return chs


def _member(a, b):
    """``np.isin(a, b)`` of integer arrays (``b`` a few pairs far beyond S): one sort and one
    search, not ``isin``'s set-up (~50 us a call, twice a merging round)."""
    if len(b) == 0 or len(a) == 0:
        return np.zeros(len(a), dtype=bool)
    b = np.sort(b)
    return b[np.minimum(b.searchsorted(a), len(b) - 1)] == a


def _quantize(x, digits=9):
    """``x`` rounded to ``10**-digits`` of its largest finite magnitude (ties then broken by
    index, the same in every run)."""
    x = np.asarray(x, dtype=np.float64)
    fin = np.isfinite(x)
    scale = np.abs(x[fin]).max(initial=0.0)
    if scale == 0:
        return x
    q = scale * 10.0 ** -digits
    return np.where(fin, np.round(x / q) * q, x)
