"""``unions.union_charts`` (the unions merging tests, found from their two charts) equals
``topology.charts`` on the trial cut: faces, vertices, triangles, boundary loop (its first vertex
and direction), kind and dtypes, for random cuts of closed, open and genus-1 meshes, with some
seams between the two charts kept (slits, annuli, charts that touch at a vertex)."""
import numpy as np

from bd_uv.seams.edges import edge_table
from bd_uv.seams.topology import charts
from bd_uv.seams.unions import union_charts
from seams_helpers import torus, uv_sphere


def _as_lists(c):
    return (c.faces.dtype, c.vertices.dtype, c.tris.dtype, c.faces.tolist(), c.vertices.tolist(),
            c.tris.tolist(), c.kind, [(lp.dtype, lp.tolist()) for lp in c.loops])


def test_unions_equal_the_charts_of_the_trial_cut():
    rng = np.random.default_rng(11)
    Vt, Ft, _, _ = torus(nu=24, nv=10)
    Vs, Fs, _ = uv_sphere(14, 7)
    Vo, Fo = Vs, Fs[Vs[Fs].mean(axis=1)[:, 2] < 0.5]      # an open cap (boundary fans)
    checked = kinds = 0
    seen = set()
    for V, F in ((Vt, Ft), (Vs, Fs), (Vo, Fo)):
        E = edge_table(V, F)
        assert E.fans is not None
        inner = E.faces[:, 1] >= 0
        for trial_no in range(16):
            cut = (rng.random(len(E.ends)) < (0.15, 0.3, 0.5, 0.8)[trial_no % 4]) & inner
            chs = charts(F, E, cut)
            label = np.empty(len(F), dtype=np.int64)
            for j, c in enumerate(chs):
                label[c.faces] = j
            # Neighbouring pairs across cut edges, a random matching of them.
            e = np.flatnonzero(cut & inner)
            la, lb = label[E.faces[e, 0]], label[E.faces[e, 1]]
            e, la, lb = e[la != lb], la[la != lb], lb[la != lb]
            pairs = np.unique(np.stack([np.minimum(la, lb), np.maximum(la, lb)], 1), axis=0)
            busy, xs, ys = set(), [], []
            for x, y in pairs[rng.permutation(len(pairs))].tolist():
                if x not in busy and y not in busy and rng.random() < 0.7:
                    busy.update((x, y))
                    xs.append(x)
                    ys.append(y)
            if not xs:
                continue
            xs, ys = np.array(xs, dtype=np.int64), np.array(ys, dtype=np.int64)
            pid = {(min(x, y), max(x, y)): i for i, (x, y) in enumerate(zip(xs, ys))}
            owner = np.array([pid.get((min(a, b), max(a, b)), -1)
                              for a, b in zip(la.tolist(), lb.tolist())], dtype=np.int64)
            # Remove most seams between each pair; a few stay cut (slits or annuli).
            gone = (owner >= 0) & (rng.random(len(e)) < 0.85)
            have = np.zeros(len(xs), dtype=bool)
            have[owner[gone]] = True
            gone &= have[np.maximum(owner, 0)]
            keep = have                     # pairs with at least one seam removed
            if not keep.any():
                continue
            sel = keep[np.maximum(owner, 0)] & gone
            remap = np.cumsum(keep) - 1
            xs, ys = xs[keep], ys[keep]
            trial = cut.copy()
            trial[e[sel]] = False
            got = union_charts(F, E, chs, label, xs, ys, e[sel], remap[owner[sel]], trial)
            faces = np.concatenate([np.concatenate([chs[x].faces, chs[y].faces])
                                    for x, y in zip(xs, ys)])
            ref = charts(F, E, trial, faces)
            assert [_as_lists(c) for _, c in got] == [_as_lists(c) for c in ref]
            for i, c in got:                # each union holds exactly its two charts
                assert set(label[c.faces].tolist()) == {int(xs[i]), int(ys[i])}
                seen.add(c.kind)
            checked += len(got)
            kinds += 1
    assert checked > 100 and kinds > 30
    assert {"disk", "open"} <= seen
