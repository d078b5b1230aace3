"""One top-down round of the seam search (``auto.unwrap_auto``): each chart not yet accepted is
cut or accepted.

A chart that is not a disk has its handles cut (``cut_graph``; all of a round's together,
``cut_graphs``), and the disks that opens are mapped in the same round (in a round of fewer than
``trim.TRIM_FACES`` faces); closed spheres, open charts no cut graph changes, disks of more than
``MAP_VERTICES`` vertices (or of more than ``MAP_SHARE_VERTICES`` holding less than ``MAP_SHARE``
of the mesh's, or of ``CURVED_FACES`` faces or more curved beyond ``CURVED``: ``angle_defects``)
and disks whose conformal map fails the charts' test (``charts.chart_maps``) are split, all in one
batch (``bisect.split_deep``; the pieces of a chart without a map again while they hold more than
``2 MAP_VERTICES`` faces, or ``CURVED_FACES`` faces or more curved beyond ``PIECE_CURVED``); a disk
that passes, and a chart no split divides, is accepted (frozen).
"""
import numpy as np

from .charts import MARGIN, chart_maps, mean_cap
from .cut_graph import cut_graphs
from .merge import chart_key
from .bisect import edge_weight, split_deep
from .topology import charts
from ..array_calls import einsum, quiet
from ..trim import CHUNK, TRIM_FACES, release_memory

# A chart of more vertices than this is split without its conformal map, and its pieces again
# while they hold more than twice as many faces (``bisect.split_deep``'s ``big``, in the same
# round: 15 rounds became 11 on a 500k-face mesh): the map's LDL^T factor was the search's
# memory peak on a 500k-face mesh (~310 MB for its first round's 183k-vertex chart, against
# ~95 MB at this size), and a chart that large passes rarely (a wide, nearly developable
# region). Where it would, its pieces pass and merging (``merge_charts``, which maps unions of
# any size) joins them again. Not 25k: on that mesh the rounds' maps above 25k vertices all
# failed, but dino subdivided twice, cow twice and fandisk twice (125k, 93k, 207k faces) lost
# 3-6 % of seam length without them (their maps guide the first splits, ``split_deep``).
MAP_VERTICES = 60_000
# ... and a chart of more than MAP_SHARE_VERTICES is mapped only where it holds at least
# MAP_SHARE of the mesh's vertices: on the 500k-face mesh the rounds' maps of 25k-48k-vertex
# charts (10-19 % of it: long tubes) all failed, 14 % of its CPU, while on the meshes above the
# 25k-60k charts whose maps guide the first splits hold 24 % of theirs or more
MAP_SHARE_VERTICES = 25_000
MAP_SHARE = 0.2
# A disk of at least CURVED_FACES faces whose interior vertices' angle defects sum to more than
# CURVED (its total Gaussian curvature, more than a hemisphere's 2 pi) is split without its
# conformal map: no chart of the search so curved passed on 8 meshes (their maps' stretch
# 2-74x), while they held 21-36 % of the faces the search mapped (fandisk's first two maps of
# ~6.5k faces each). A chart split wrongly this way is whole again where merging's union of its
# pieces passes (merging maps every union, whatever its curvature).
CURVED = 2 * np.pi
# ... and the pieces of a chart split without a map (a closed part, an open chart no cut graph
# changes, a chart skipped above) are split again in the same round while they hold at least
# CURVED_FACES faces curved more than PIECE_CURVED (the faces' shares of their corners' defects,
# ``angle_defects``): a closed part's first split went one level a round, each piece mapped and
# failing before the next (fandisk: 43k faces mapped by the search -> 28k, 9 rounds -> 8).
PIECE_CURVED = 2.0
# Only charts and pieces this large: below it a map is cheap, and the depth its failure guides
# (``split_deep``) saves rounds; at 1,000 faces elephant, cow and dino ran 2-5 % more maps or
# rounds and a small box's band, found whole and cut by the atlas pass, was split into five
# (tests/core/test_seams_pack_shape.py); at 4,000 suzanne, elephant, cesiumman, cow, dino and
# the shader ball keep their seams, and meshes under 4,000 faces are searched as before.
CURVED_FACES = 4000


def refine(V, F, E, cut, frozen, A, cen, C, S, n, poly=None, diag=None, cap=None, known=None,
            geom=None, failed=None, orders=None, defect=None):
    """One top-down round over the charts not yet accepted; True when a seam was added.

    Handles are cut first; the charts to split (closed spheres, open charts no cut graph
    changes, disks of more than ``MAP_VERTICES`` vertices or of more than ``MAP_SHARE_VERTICES``
    holding less than ``MAP_SHARE`` of the mesh's, disks whose map fails) are all split
    in one batch (``bisect.split_deep``). A disk
    passes with a mean distortion up to ``cap`` (default ``mean_cap(C)``); its conformal map goes
    into ``known`` (``ChartMaps.remember``). A disk that fails (at ``cap`` >= ``mean_cap(C)``, so
    at merging's test too) goes into ``failed`` (``merge.chart_key`` -> its map's max stretch).
    ``orders``: the mesh's ``orders.Orders`` for the maps' solves, optional.
    ``defect``: each vertex's angle defect and each face's share (``angle_defects``), optional:
    a disk of ``CURVED_FACES`` faces or more whose interior vertices' defects sum to more than
    ``CURVED`` is split without its map, and the pieces of charts split without a map again
    while they hold ``CURVED_FACES`` faces or more whose shares sum to more than
    ``PIECE_CURVED`` (``split_deep``'s ``curved``).
    """
    sub = (~frozen).ravel().nonzero()[0]
    if len(sub) == 0:
        return False
    # Each step of a round (charts, cut graphs, maps, splits) starts on the heap the last one
    # freed handed back (``trim``): on a 500k-face mesh the Fiedler sweep's and the factors'
    # freed heap otherwise stayed resident (50-100 MB) under the next step's own peak.
    release_memory(len(sub))
    chs = charts(F, E, cut, sub)
    changed = False
    todo = []                               # (faces, the map's sigma per face or None)
    opened = []                             # the faces of charts whose handles were cut
    # The cut graphs of the round's open charts (handles, or several boundary loops) together.
    ochs = [c for c in chs if c.kind == "open"]
    if ochs:
        allv = np.concatenate([c.vertices for c in ochs])
        graphs = iter(cut_graphs([(c.tris, len(c.vertices)) for c in ochs],
                                 lambda pairs: edge_weight(E, allv[pairs], n, diag)))
    for c in chs:
        if c.kind == "open":
            g = next(graphs)
            k = E.keys(c.vertices[g], n) if len(g) else np.zeros(0, np.int64)
            k = k[k >= 0]
            if diag is not None:            # never inside a polygon (the split below instead)
                k = k[~diag[k]]
            if len(k) and not cut[k].all():
                cut[k] = True
                changed = True
                opened.append(c.faces)
                continue
        if c.kind in ("open", "sphere"):    # a sphere: split along its neck
            todo.append((c.faces, None))
    strict = set()                          # the first faces of the charts opened here
    # (not in a round of ``trim.TRIM_FACES`` faces or more: mapping them with the round's disks
    # raised the 500k-face peak from ~331 to ~345 MB, over xatlas's 332, for no time measured)
    if opened and len(sub) < TRIM_FACES:
        # A chart its cut graph opened is mapped in this round (the round after would find it
        # as it is now, and map it then, at ``mean_cap(C)``): its disks join this round's
        # maps; a chart still not a disk waits for the next round, as before.
        new = charts(F, E, cut, np.concatenate(opened))
        strict = {int(c.faces[0]) for c in new}
        chs = sorted([c for c in chs if c.kind == "disk"] + new, key=lambda c: int(c.faces[0]))
    disks = []
    share = MAP_SHARE * len(V)
    for c in chs:
        if c.kind != "disk":
            continue
        nv = len(c.vertices)
        if ((nv > MAP_VERTICES or MAP_SHARE_VERTICES < nv < share
             or (defect is not None and len(c.faces) >= CURVED_FACES
                 and curvature(c, defect[0]) > CURVED)) and len(c.faces) >= 2):
            todo.append((c.faces, None))    # split unmapped; merging may join it again
        else:
            disks.append(c)
    # The charts that are not disks hold their vertices and triangles only here (a round's
    # open and closed charts: up to the whole mesh, ~36 bytes a face): not held through the
    # maps' factors.
    chs = None
    if disks:
        release_memory(len(sub))
        cap = mean_cap(C) if cap is None else cap
        cm = chart_maps(V, disks, geom, limits=(S * MARGIN, cap), orders=orders)
        # (a chart opened in this round passes at ``mean_cap(C)``, as in the next round: a
        # looser ``cap`` is for the charts of the given seams only)
        caps = np.array([mean_cap(C) if int(c.faces[0]) in strict else cap for c in disks])
        ok = (np.isfinite(cm.max_distortion) & (cm.max_stretch <= S * MARGIN)
              & (cm.crossings == 0) & (cm.mean_distortion <= caps))
        if known is not None:
            cm.remember(disks, ok, known)
        for j, c in enumerate(disks):
            if ok[j] or len(c.faces) < 2:
                frozen[c.faces] = True
            else:
                if failed is not None:
                    failed[chart_key(c)] = float(cm.max_stretch[j])
                todo.append((c.faces, cm.sigma[cm.foff[j]:cm.foff[j + 1]].copy()))
    # The round's charts and maps are not held through the splits (the Fiedler sweep is the
    # top-down rounds' peak): ~36 bytes per face of charts and ~48 per face and vertex mapped
    # (17 MB and more on a 500k-face mesh); only the failed disks' singular values are kept.
    chs = disks = cm = None
    if todo:
        release_memory(len(sub))
        curved = None if defect is None else (defect[1], PIECE_CURVED, CURVED_FACES)
        split = split_deep(todo, E, cut, A, cen, S, poly, orders, big=2 * MAP_VERTICES,
                           curved=curved)
        for (faces, _), done in zip(todo, split):
            if not done:
                frozen[faces] = True
        changed |= bool(split.any())
    return changed


def curvature(chart, defect):
    """A disk chart's total Gaussian curvature: the angle defects of its interior vertices (all
    but its boundary loop's)."""
    v = chart.vertices
    return float(defect[v].sum() - defect[v[chart.loops[0]]].sum())


def angle_defects(V, F, E, A):
    """Each vertex's angle defect, ``2 pi`` minus its corners' angles (0 on the mesh's boundary
    and at vertices of no face), and each face's share of its corners' defects (a vertex's
    defect shared among its corners by their angles: a face set's total is its curvature,
    counting its boundary vertices in part), ``CHUNK`` faces at a time; ``A`` the face areas.
    None on a mesh of fewer than ``CURVED_FACES`` faces, where no chart is large enough to use
    them.

    Returns
    -------
    (n,) float64, (m,) float64, or None
    """
    if len(F) < CURVED_FACES:
        return None
    chunks = list(_corner_angles(V, F, A))    # (views of F, (k,3) angles: 24 bytes a face)
    total = np.zeros(len(V))
    for f, ang in chunks:
        total += np.bincount(f.ravel(), ang.ravel(), minlength=len(V))
    defect = 2 * np.pi - total
    defect[total == 0] = 0.0
    defect[E.ends[E.faces[:, 1] < 0].ravel()] = 0.0
    defect[~np.isfinite(defect)] = 0.0
    with quiet("invalid", "divide"):
        per_angle = np.where(total > 0, defect / total, 0.0)
    share = np.concatenate([einsum("ij,ij->i", ang, per_angle[f])
                            for f, ang in chunks])
    share[~np.isfinite(share)] = 0.0
    return defect, share


def _corner_angles(V, F, A):
    """(faces, their (k,3) corner angles), ``CHUNK`` faces at a time: ``arctan2`` of twice the
    face's area over the corner's dot product, from the squared side lengths (law of
    cosines)."""
    for i in range(0, len(F), CHUNK):
        f = F[i:i + CHUNK]
        p0, p1, p2 = (V.take(f[:, j], axis=0) for j in range(3))    # (rows: ``take``, ~4x)
        d0, d1, d2 = p2 - p1, p0 - p2, p1 - p0          # the sides opposite corners 0, 1, 2
        s0, s1, s2 = (einsum("ij,ij->i", d, d) for d in (d0, d1, d2))
        twice = 2 * A[i:i + CHUNK]
        with quiet("invalid"):
            ang = np.stack([np.arctan2(twice, 0.5 * (s1 + s2 - s0)),
                            np.arctan2(twice, 0.5 * (s2 + s0 - s1)),
                            np.arctan2(twice, 0.5 * (s0 + s1 - s2))], axis=1)
        yield f, ang
