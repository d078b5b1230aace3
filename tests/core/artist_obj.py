"""An OBJ as an artist's tool writes it, and an independent reader of OBJ text, for the tests of
the OBJ written back with new UVs (``bd_uv.obj.patch``): quads and a pentagon, two materials,
objects and groups, smoothing groups, normals (``f v/vt/vn`` and ``f v//vn``), comments (one
with a byte that is not UTF-8), negative indices, a face continued on the next line, a vertex
the exporter split (welded for the unwrap), old ``vt`` records, CRLF line ends.

The reader here shares no line with ``bd_uv.obj``: records split on ``\\n`` after joining
continued lines, indices resolved by counting the records before each face.
"""
import numpy as np


def polygons_of(F):
    """Polygons (lists of vertex ids, the triangles' orientation) from the triangles ``F``: the
    first triangle merged with two neighbours into a pentagon, then neighbours paired into
    quads greedily (triangle (a, b, c) and (c, b, d) across b-c: quad a, b, d, c); the rest stay
    triangles."""
    F = [list(map(int, f)) for f in F]
    edge = {}
    for i, f in enumerate(F):
        for k in range(3):
            edge[(f[k], f[(k + 1) % 3])] = i
    used = set()

    def merge(poly, i):
        """``poly`` with triangle i (not used) across one of its edges, or None."""
        for k in range(len(poly)):
            a, b = poly[k], poly[(k + 1) % len(poly)]
            if edge.get((b, a)) == i:
                d = next(v for v in F[i] if v not in (a, b))
                return poly[:k + 1] + [d] + poly[k + 1:]
        return None

    def neighbours(poly):
        return [edge.get((poly[(k + 1) % len(poly)], poly[k])) for k in range(len(poly))]

    out = []
    for i, f in enumerate(F):
        if i in used:
            continue
        used.add(i)
        poly, want = f, 3 if not out else 2     # the first polygon a pentagon, then quads
        for _ in range(want - 1):
            for j in neighbours(poly):
                if j is not None and j not in used:
                    grown = merge(poly, j)
                    if grown is not None and len(set(grown)) == len(grown):
                        poly = grown
                        used.add(j)
                        break
        out.append(poly)
    return out


def artist_obj(V, F, split_vertex=True, crlf=True):
    """(bytes of the OBJ, its polygons as written: a list of dicts with ``v`` (0-based vertex
    ids as read), ``vn`` (0-based normal ids or None) and ``tokens`` (the corners' v and vn text
    as written)).

    The first half of the polygons is object ``partA`` (group ``g1``, material ``red``,
    smoothing on; ``f v/vt/vn``, one face's record continued on a second line), the second
    ``partB`` (group ``g2``, material ``blue``, smoothing off; ``f v//vn`` with negative
    indices, one ``f v`` face). With ``split_vertex`` a vertex of partA is written twice (its
    second copy used by some of its faces), as exporters split vertices at UV seams."""
    V = np.asarray(V, dtype=np.float64)
    polys = polygons_of(F)
    n = len(V)
    copies = {}
    if split_vertex:    # the vertex of the first quad's third corner: copy used by that quad
        quad = next(p for p in polys[:len(polys) // 2] if len(p) == 4)
        copies = {quad[2]: n}
        polys = [[copies.get(v, v) if p is quad else v for v in p] for p in polys]
    Vall = np.concatenate([V, V[list(copies)]]) if copies else V
    nv = len(Vall)
    N = np.tile([0.0, 0.0, 1.0], (nv, 1)) + 0.01 * Vall     # one normal a vertex, any values
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    lines = ["# Blender-style export \xe9\x01", "mtllib scene.mtl", "",
             "# vertices"]
    lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in Vall.tolist()]
    lines += [f"vt {x!r} {y!r}" for x, y, _ in Vall.tolist()]   # old UVs: a projection
    lines += [f"vn {x!r} {y!r} {z!r}" for x, y, z in N.tolist()]
    half = len(polys) // 2
    written = []
    lines += ["o partA", "g g1", "usemtl red", "s 1"]
    for k, p in enumerate(polys[:half]):
        toks = [f"{v + 1}/{v + 1}/{v + 1}" for v in p]
        if k == 1:      # continued on the next line
            lines.append("f " + " ".join(toks[:2]) + " \\")
            lines.append("  " + " ".join(toks[2:]))
        else:
            lines.append("f " + " ".join(toks) + ("  # first face" if k == 0 else ""))
        written.append(dict(v=list(p), vn=list(p), tokens=[(f"{v + 1}", f"{v + 1}") for v in p]))
    lines += ["", "# the other part", "o partB", "g g2", "usemtl blue", "s off"]
    for k, p in enumerate(polys[half:]):
        if k == 0:      # v only
            lines.append("f " + " ".join(str(v + 1) for v in p))
            written.append(dict(v=list(p), vn=None, tokens=[(f"{v + 1}", None) for v in p]))
            continue
        toks = [(f"{v - nv}", f"{v - nv}") for v in p]     # counted back from the last v, vn
        lines.append("f " + " ".join(f"{a}//{b}" for a, b in toks))
        written.append(dict(v=list(p), vn=list(p), tokens=toks))
    lines.append("# end")
    eol = "\r\n" if crlf else "\n"
    text = eol.join(lines) + eol
    return text.encode("utf-8").replace("\xe9".encode("utf-8"), b"\xe9"), written


def records(data):
    """(key, record bytes with its line ends) of OBJ bytes, continued lines joined in one."""
    out, pending = [], b""
    for line in data.splitlines(keepends=True):
        pending += line
        if line.rstrip().endswith(b"\\"):
            continue
        words = pending.split()
        out.append((words[0].decode("utf-8", "replace") if words else "", pending))
        pending = b""
    if pending:
        out.append((pending.split()[0].decode("utf-8", "replace"), pending))
    return out


def read_faces(data):
    """V (n,3), VT (k,2), and per ``f`` record its corners: a list of (v, vt, vn) 0-based ids
    (None where absent) and its corners' (v, vn) text as written."""
    V, VT, faces = [], [], []
    counts = {"v": 0, "vt": 0, "vn": 0}
    for key, rec in records(data):
        body = rec.decode("utf-8", "replace").replace("\\", " ").split(" #")[0].split()
        if key in ("v", "vt"):
            (V if key == "v" else VT).append([float(t) for t in body[1:4 if key == "v" else 3]])
        if key in counts:
            counts[key] += 1
        if key != "f":
            continue
        corners, text = [], []
        for t in body[1:]:
            parts = t.split("/") + ["", ""]
            ids = []
            for part, kind in zip(parts[:3], ("v", "vt", "vn")):
                # a normal index is kept as written, not read (a file cut short: "3/2/-")
                i = int(part) if part and (kind != "vn" or part.lstrip("-").isdigit()) else None
                ids.append(None if i is None else i + counts[kind] if i < 0 else i - 1)
            corners.append(tuple(ids))
            text.append((parts[0], parts[2] or None))
        faces.append((corners, text))
    return np.array(V).reshape(-1, 3), np.array(VT).reshape(-1, 2), faces


def fan_uvs(V, VT, faces):
    """Triangles (t,3) of the faces' fans from their first corner and their UVs (t,3,2) (NaN
    where a corner has no vt), with each triangle's face."""
    tris, uvs, owner = [], [], []
    for k, (corners, _) in enumerate(faces):
        for j in range(1, len(corners) - 1):
            c = [corners[0], corners[j], corners[j + 1]]
            tris.append([x[0] for x in c])
            uvs.append([VT[x[1]] if x[1] is not None else [np.nan, np.nan] for x in c])
            owner.append(k)
    return (np.array(tris, dtype=np.int64), np.array(uvs, dtype=np.float64),
            np.array(owner, dtype=np.int64))
