"""Random polygon meshes and the files that hold them, for the polygon fuzz contract
(``test_fuzz_polygons.py``): shares no line with ``bd_uv``'s readers or writers.

A sheet is a grid of cells merged at random into polyomino polygons (concave, with corners in a
line along their straight sides, each one simple loop with no hole), laid flat, tilted or bent
in space; parts beside it add a random star-shaped n-gon, corners on a line or repeated, a
polygon of no area, a face of no area hanging on the sheet, a self-crossing quad and a spiral.
The files: OBJ (mixed records, CRLF, negative indices, continued lines, tabs, a byte order mark,
old ``vt``, ``vn``), a USD stage, a binary PLY of polygons, an ASCII PLY, a binary PLY of
triangle strips (degenerate joins, -1 restarts, short strips), an ASCII or binary STL.
"""
import struct

import numpy as np


# ---------------------------------------------------------------------------------------------
# the polygons

def polyomino_sheet(rng, nx, ny, merges):
    """(V (n,3) in the plane z = 0, polygons: lists of vertex ids, counter-clockwise): an nx x ny
    grid of unit cells, ``merges`` random merges of neighbouring regions each kept only when the
    merged region's boundary is one loop through distinct vertices (simply connected, no
    pinch). Every grid vertex on a region's boundary is a corner (corners in a line)."""
    ids = np.arange((nx + 1) * (ny + 1)).reshape(ny + 1, nx + 1)
    V = np.array([[i, j, 0.0] for j in range(ny + 1) for i in range(nx + 1)], dtype=np.float64)
    region = np.arange(nx * ny).reshape(ny, nx)
    for _ in range(merges):
        y, x = int(rng.integers(ny)), int(rng.integers(nx))
        dy, dx = [(0, 1), (1, 0), (0, -1), (-1, 0)][int(rng.integers(4))]
        if not (0 <= y + dy < ny and 0 <= x + dx < nx):
            continue
        a, b = region[y, x], region[y + dy, x + dx]
        if a == b:
            continue
        trial = np.where(region == b, a, region)
        if _loop(trial, ids, a) is not None:
            region = trial
    polys = [_loop(region, ids, r) for r in np.unique(region)]
    return V, polys


def _loop(region, ids, r):
    """The boundary of region ``r`` as one counter-clockwise loop of vertex ids, or None when it
    is not one loop through distinct vertices."""
    ny, nx = region.shape
    out = {}
    for y, x in zip(*np.nonzero(region == r)):
        cell = [ids[y, x], ids[y, x + 1], ids[y + 1, x + 1], ids[y + 1, x]]   # ccw
        for k in range(4):
            a, b = cell[k], cell[(k + 1) % 4]
            if (b, a) in out:
                del out[(b, a)]
            else:
                out[(a, b)] = True
    nxt = {}
    for a, b in out:
        if a in nxt:
            return None           # a vertex on the boundary twice: a pinch
        nxt[a] = b
    start = next(iter(nxt))
    loop, v = [start], nxt[start]
    while v != start:
        loop.append(v)
        v = nxt[v]
    return loop if len(loop) == len(nxt) else None          # else a hole: two loops


def star_polygon(rng, n):
    """(n,2) a random star-shaped simple polygon about the origin, counter-clockwise (concave
    where a radius dips): each corner's angle within its own n-th of the turn, so no gap
    between two reaches half a turn (angles drawn anywhere left the origin outside, and the
    closing side could cross the others: found by this contract's first deep run)."""
    t = 2 * np.pi * (np.arange(n) + rng.uniform(0.1, 0.9, n)) / n
    r = rng.uniform(0.2, 1.0, n)
    return np.column_stack([r * np.cos(t), r * np.sin(t)])


def on_sides(q, rng, k):
    """The polygon ``q`` (c,2) with ``k`` corners added in the middle of random sides (three
    corners in a line)."""
    q = [tuple(p) for p in q]
    for _ in range(k):
        i = int(rng.integers(len(q)))
        a, b = np.array(q[i]), np.array(q[(i + 1) % len(q)])
        s = float(rng.choice([0.5, 0.25, 0.75]))
        q.insert(i + 1, tuple(a + s * (b - a)))
    return np.array(q)


def place(q, origin, tilt):
    """Points (c,2) of a plane put in space: x along (1, 0, tilt[0]), y along (tilt[1], 1,
    tilt[2]), from ``origin``."""
    q = np.asarray(q, np.float64)
    return np.asarray(origin, np.float64) + q[:, :1] * [1.0, 0.0, tilt[0]] \
        + q[:, 1:2] * [tilt[1], 1.0, tilt[2]]


def bend(V, kind, rng):
    """The sheet's points in space: ``flat`` (z = 0), ``tilted`` (a plane), ``curved`` (a
    cylinder of large radius: its polygons bent a little) or ``folded`` (bent a lot)."""
    V = V.copy()
    x, y = V[:, 0], V[:, 1]
    if kind == "tilted":
        return place(V[:, :2], [0, 0, 0], (0.3, -0.2, 0.4))
    if kind == "curved":
        V[:, 2] = 0.03 * (x - x.mean()) ** 2 + 0.02 * y
    elif kind == "folded":
        V[:, 2] = 0.4 * np.sin(1.3 * x) + 0.2 * y * x / (1 + x.max())
    return V


class Part:
    """A polygon mesh being assembled: points, polygons (vertex id lists) and each polygon's
    kind ("sheet", "star", ...), whether it is flat and simple (its triangles must tile it)."""

    def __init__(self):
        self.V = np.zeros((0, 3))
        self.polys, self.kinds, self.flat = [], [], []

    def add(self, V, polys, kind, flat):
        n = len(self.V)
        self.V = np.concatenate([self.V, np.asarray(V, np.float64).reshape(-1, 3)])
        for p in polys:
            self.polys.append([int(v) + n for v in p])
            self.kinds.append(kind)
            self.flat.append(flat)
        return n


#: the extras that are triangles (for strips and STL files)
TRIANGLE_EXTRAS = ("zero-area hanging", "zero-area point", "triangle pair")
EXTRAS = ("star", "star on sides", "repeated corner", "same position", "collinear polygon",
          "zero-area hanging", "zero-area point", "bowtie", "spiral", "triangle pair")


def build(rng, sheet, shape, extras, jitter, triangles=False):
    """A ``Part`` of the polyomino sheet (``sheet``: (nx, ny, merges); ``shape``: ``bend``'s
    kind), its grid points moved in its plane by up to ``jitter`` of a cell (corners off their
    lines), and the ``extras`` (names from ``EXTRAS``) beside it, each its own island. With
    ``triangles`` the sheet is the grid's triangles (``grid_triangles``), not polygons."""
    nx, ny, merges = sheet
    V, polys = polyomino_sheet(rng, nx, ny, 0 if triangles else merges)
    if triangles:
        polys = grid_triangles(nx, ny).tolist()
    if jitter:
        V[:, :2] += rng.uniform(-jitter, jitter, (len(V), 2))
    m = Part()
    flat = shape in ("flat", "tilted")
    m.add(bend(V, shape, rng), polys, "sheet", flat)
    width = float(nx) + 2.0
    for k, name in enumerate(extras):
        origin = [width + 3.0 * k, 0.0, 0.0]
        tilt = tuple(rng.uniform(-0.5, 0.5, 3))
        if name in ("star", "star on sides", "repeated corner", "same position"):
            q = star_polygon(rng, int(rng.integers(4, 25)))
            if name == "star on sides":
                q = on_sides(q, rng, int(rng.integers(1, 4)))
            P = place(q, origin, tilt)
            poly = list(range(len(P)))
            if name == "repeated corner":              # f ... 7 7 ...: the same vertex twice
                i = int(rng.integers(len(poly)))
                poly.insert(i, poly[i])
            elif name == "same position":              # two vertices at one place, in a row
                i = int(rng.integers(len(P)))
                P = np.insert(P, i + 1, P[i], axis=0)
                poly = list(range(len(P)))
            m.add(P, [poly], name, name != "repeated corner" and name != "same position")
        elif name == "collinear polygon":               # four corners on a line: no area
            P = place([[0, 0], [1, 0], [2.5, 0], [1.5, 0]], origin, tilt)
            m.add(P, [[0, 1, 2, 3]], name, False)
        elif name in ("zero-area hanging", "zero-area point"):
            # a triangle of no area on one of the sheet's boundary edges (its third corner on
            # the edge's line, a vertex of its own) or at one point (three vertices there)
            a, b = 0, 1                                   # grid vertices (0,0), (1,0): a side
            Pa, Pb = m.V[a], m.V[b]
            if name == "zero-area hanging":
                c = m.add([Pa + float(rng.choice([0.5, 2.0, -1.0])) * (Pb - Pa)], [], name, False)
                m.polys.append([b, a, c])
            else:
                c = m.add([Pa, Pa], [], name, False)
                m.polys.append([a, c, c + 1])
            m.kinds.append(name)
            m.flat.append(False)
        elif name == "bowtie":                          # a quad crossing itself
            P = place([[0, 0], [1, 1], [1, 0], [0, 1]], origin, tilt)
            m.add(P, [[0, 1, 2, 3]], name, False)
        elif name == "spiral":   # one polygon whose fan turns 900 degrees round its first corner
            t = np.radians(np.arange(16) * 60.0)
            P = np.column_stack([np.cos(t), np.sin(t), 0.1 * np.arange(16)])
            m.add(np.concatenate([[[0.0, 0.0, 0.0]], P]) + origin, [list(range(17))], name,
                  False)
        elif name == "triangle pair":                   # two plain triangles, a quad's halves
            P = place([[0, 0], [1, 0], [1, 1], [0, 1]], origin, tilt)
            m.add(P, [[0, 1, 2], [0, 2, 3]], name, True)
    return m


def grid_triangles(nx, ny):
    """The triangles of an nx x ny grid of cells (vertex ids as ``polyomino_sheet``'s), row by
    row, two a cell, counter-clockwise: what the strips and STL files hold."""
    ids = np.arange((nx + 1) * (ny + 1)).reshape(ny + 1, nx + 1)
    out = []
    for y in range(ny):
        for x in range(nx):
            a, b, c, d = ids[y, x], ids[y, x + 1], ids[y + 1, x + 1], ids[y + 1, x]
            out += [[a, b, c], [a, c, d]]
    return np.array(out, dtype=np.int64)


# ---------------------------------------------------------------------------------------------
# the files

def _num(x):
    return repr(float(x))


def obj_bytes(m, rng, style):
    """OBJ bytes of ``m``, written in ``style`` (a dict of booleans: crlf, negative, continued,
    tabs, bom, old_vt, vt_corner (the old vt one a polygon corner, each polygon its own UV
    island: seams in the file's UVs), normals, records, comments)."""
    eol = "\r\n" if style["crlf"] else "\n"
    sep = "\t" if style["tabs"] else " "
    n = len(m.V)
    lines = []
    if style["records"]:
        lines += ["# made by the polygon fuzz \u00e9", "mtllib fuzz.mtl", ""]
    lines += [sep.join(["v"] + [_num(c) for c in p]) for p in m.V.tolist()]
    per_corner = style["old_vt"] and style.get("vt_corner")
    base = np.concatenate([[0], np.cumsum([len(p) for p in m.polys])])
    if per_corner:        # each polygon's corners projected, the polygons side by side
        lines += [f"vt {_num(m.V[v, 0] + 3.0 * k)} {_num(m.V[v, 1])}"
                  for k, p in enumerate(m.polys) for v in p]
    elif style["old_vt"]:
        lines += [f"vt {_num(x)} {_num(y)}" for x, y, _ in m.V.tolist()]
    nt = int(base[-1]) if per_corner else n
    if style["normals"]:
        lines += [f"vn 0 0 {1 if i % 2 else -1}" for i in range(n)]
    if style["records"]:
        lines += ["o sheet", "g part1", "usemtl red", "s 1"]
    half = len(m.polys) // 2
    for k, p in enumerate(m.polys):
        if style["records"] and k == half:
            lines += ["", "# the second half", "g part2", "usemtl blue", "s off",
                      "l 1 2", "p 1"]
        neg = style["negative"] and k % 2 == 1
        corners = []
        for c, v in enumerate(p):
            i = str(v - n if neg else v + 1)          # counted back from the last v (all read)
            t = i if style["old_vt"] else ""
            if per_corner:
                j = int(base[k]) + c
                t = str(j - nt if neg else j + 1)
            corners.append(f"{i}/{t}/{i}" if style["normals"] else f"{i}/{t}" if t else i)
        if style["continued"] and len(corners) > 3 and k % 3 == 0:
            rec = f"f{sep}" + sep.join(corners[:2]) + " \\" + eol + "  " + sep.join(corners[2:])
        else:
            rec = f"f{sep}" + sep.join(corners)
        if style["comments"] and k % 4 == 0:
            rec += "  # face %d" % k
        lines.append(rec)
    lines.append("# end")
    text = eol.join(lines) + eol
    data = text.encode("utf-8")
    return (b"\xef\xbb\xbf" if style["bom"] else b"") + data


def usda_write(path, m):
    """A USD stage of ``m`` as one mesh (float32 points)."""
    from pxr import Usd, UsdGeom, Vt
    stage = Usd.Stage.CreateNew(str(path))
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    mesh = UsdGeom.Mesh.Define(stage, "/World/Sheet")
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(m.V.astype(np.float32)))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray([len(p) for p in m.polys]))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray([v for p in m.polys for v in p]))
    stage.GetRootLayer().Save()


def ply_binary_faces(V, polys, big=False):
    """A binary PLY (float32 points), its face list of any lengths."""
    o = ">" if big else "<"
    head = ("ply\nformat binary_%s_endian 1.0\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nelement face %d\n"
            "property list uchar int vertex_indices\nend_header\n"
            % ("big" if big else "little", len(V), len(polys)))
    return head.encode() + b"".join(struct.pack(o + "3f", *v) for v in V.tolist()) + b"".join(
        struct.pack(o + "B%di" % len(p), len(p), *p) for p in polys)


def ply_ascii_faces(V, polys):
    head = ("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
            "property float z\nelement face %d\nproperty list uchar int vertex_indices\n"
            "end_header\n" % (len(V), len(polys)))
    V32 = np.asarray(V, np.float32).astype(np.float64)
    return (head + "".join(" ".join(_num(c) for c in v) + "\n" for v in V32.tolist())
            + "".join(f"{len(p)} " + " ".join(map(str, p)) + "\n" for p in polys)).encode()


def strips_of(nx, ny, rng, joins):
    """Triangle strips drawing an nx x ny grid of cells (vertex ids as ``polyomino_sheet``'s),
    two triangles a cell, one strip a row (top, bottom, top, bottom: d a c b c' b' ...). Rows
    joined by repeated vertices (``joins`` "degenerate": the joins' triangles have a repeated
    vertex, and are no triangles; a third repeat where needed keeps the next row's triangles
    wound as its own) or ended by -1 ("restart"), with short strips (two ids) and empty ones
    thrown in. Returns (the strips' id lists, the triangles drawn as ``read_strips`` reads
    them)."""
    ids = np.arange((nx + 1) * (ny + 1)).reshape(ny + 1, nx + 1)
    rows = [[int(v) for x in range(nx + 1) for v in (ids[y + 1, x], ids[y, x])]
            for y in range(ny)]
    out = []
    for k, strip in enumerate(rows):
        if k and joins == "degenerate":
            out += [out[-1], strip[0]]
            if len(out) % 2 == 1:
                out.append(strip[0])
        elif k:
            out.append(-1)
            if rng.random() < 0.3:
                out += [strip[0], strip[1], -1]          # a short strip: no triangle
            if rng.random() < 0.3:
                out.append(-1)                           # an empty one
        out += strip
    return [out], read_strips([out])


def read_strips(strips):
    """The triangles the strips draw, this test's reading: strip i's triangle k is
    (s[k], s[k+1], s[k+2]), every odd one turned back (s[k+1], s[k], s[k+2]); -1 ends a strip;
    a triangle with a repeated vertex is none."""
    tris = []
    for ids in strips:
        cur = []
        for v in list(ids) + [-1]:
            if v >= 0:
                cur.append(int(v))
                continue
            for k in range(len(cur) - 2):
                t = [cur[k], cur[k + 1], cur[k + 2]] if k % 2 == 0 else \
                    [cur[k + 1], cur[k], cur[k + 2]]
                if len(set(t)) == 3:
                    tris.append(t)
            cur = []
    return np.array(tris, dtype=np.int64).reshape(-1, 3)


def ply_strips(V, strips):
    """A binary little-endian PLY of ``tristrips`` (float32 points)."""
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nelement tristrips %d\n"
            "property list int int vertex_indices\nend_header\n" % (len(V), len(strips)))
    return head.encode() + b"".join(struct.pack("<3f", *v) for v in V.tolist()) + b"".join(
        struct.pack("<i%di" % len(s), len(s), *s) for s in strips)


def stl_bytes(V, F, binary):
    """An STL of the triangles (every corner written out, float32 in a binary one)."""
    P = np.asarray(V, np.float64)[np.asarray(F)]
    if binary:
        out = [b"fuzz".ljust(80, b"\0"), struct.pack("<I", len(P))]
        for t in P.tolist():
            out.append(struct.pack("<12fH", 0, 0, 1, *t[0], *t[1], *t[2], 0))
        return b"".join(out)
    rows = ["solid fuzz"]
    for t in np.asarray(P, np.float32).astype(np.float64).tolist():
        rows += ["facet normal 0 0 1", "outer loop"]
        rows += ["vertex " + " ".join(_num(c) for c in p) for p in t]
        rows += ["endloop", "endfacet"]
    return ("\n".join(rows + ["endsolid fuzz"]) + "\n").encode()
