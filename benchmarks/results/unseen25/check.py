"""check.py: OBJ record comparison (input vs written) and first-corner-fan UV flips."""
import json, sys, numpy as np

def obj_lines(path):
    raw = open(path, 'rb').read()
    if raw[:2] in (b'\xff\xfe', b'\xfe\xff'):
        raw = raw.decode('utf-16').encode()
    txt = raw.decode('utf-8', 'replace').replace('\r\n', '\n').replace('\r', '\n')
    out, buf = [], ''
    for ln in txt.split('\n'):
        if ln.endswith('\\'):
            buf += ln[:-1] + ' '; continue
        out.append(buf + ln); buf = ''
    if buf: out.append(buf)
    return out

def kind(ln):
    t = ln.split(None, 1)
    return t[0] if t else ''

def compare_obj(inp, outp):
    a, b = obj_lines(inp), obj_lines(outp)
    ka = [l for l in a if kind(l) not in ('vt', 'f')]
    kb = [l for l in b if kind(l) not in ('vt', 'f')]
    # trailing empty line differences ignored
    while ka and not ka[-1].strip(): ka.pop()
    while kb and not kb[-1].strip(): kb.pop()
    import difflib
    diff = [d for d in difflib.unified_diff(ka, kb, lineterm='', n=0) if d[:1] in '+-' and d[:3] not in ('+++', '---')]
    fa = [l for l in a if kind(l) == 'f']; fb = [l for l in b if kind(l) == 'f']
    def vidx(l): return [tok.split('/')[0] for tok in l.split()[1:]]
    def nidx(l): return [tok.split('/')[2] if tok.count('/') == 2 else '' for tok in l.split()[1:]]
    fchg = None
    if len(fa) == len(fb):
        fchg = sum(vidx(x) != vidx(y) or nidx(x) != nidx(y) for x, y in zip(fa, fb))
    return {"other_diff": len(diff), "diff_head": diff[:6], "f_in": len(fa), "f_out": len(fb), "f_changed": fchg}

def parse_obj(path):
    V, T, P = [], [], []
    for l in obj_lines(path):
        t = l.split()
        if not t: continue
        if t[0] == 'v': V.append([float(x) for x in t[1:4]])
        elif t[0] == 'vt': T.append([float(x) for x in t[1:3]])
        elif t[0] == 'f':
            vs, ts = [], []
            for tok in t[1:]:
                s = tok.split('/')
                vi = int(s[0]); vi = vi - 1 if vi > 0 else len(V) + vi
                ti = None
                if len(s) > 1 and s[1]:
                    ti = int(s[1]); ti = ti - 1 if ti > 0 else len(T) + ti
                vs.append(vi); ts.append(ti)
            if None in ts: continue
            P.append((vs, ts))
    V = np.array(V) if V else np.zeros((0, 3)); T = np.array(T) if T else np.zeros((0, 2))
    return [(V[vs], T[ts]) for vs, ts in P]

def parse_usd(path):
    from pxr import Usd, UsdGeom
    st = Usd.Stage.Open(path); polys = []
    for prim in st.Traverse():
        if not prim.IsA(UsdGeom.Mesh): continue
        m = UsdGeom.Mesh(prim)
        tc = Usd.TimeCode.Default()
        pts = m.GetPointsAttr().Get(tc); cnt = m.GetFaceVertexCountsAttr().Get(tc); idx = m.GetFaceVertexIndicesAttr().Get(tc)
        if pts is None or cnt is None:
            for a in (m.GetPointsAttr(), m.GetFaceVertexCountsAttr()):
                ts = a.GetTimeSamples()
                if ts: tc = Usd.TimeCode(ts[0])
            pts = m.GetPointsAttr().Get(tc); cnt = m.GetFaceVertexCountsAttr().Get(tc); idx = m.GetFaceVertexIndicesAttr().Get(tc)
        if pts is None or cnt is None: continue
        pv = None
        for p in UsdGeom.PrimvarsAPI(prim).GetPrimvars():
            if p.GetTypeName().role == 'TextureCoordinate' or p.GetPrimvarName() in ('st', 'UVMap'):
                if p.GetPrimvarName() in ('st',) or pv is None: pv = p
        if pv is None: continue
        uv = pv.ComputeFlattened(tc)
        if uv is None: continue
        uv = np.array(uv, float); P = np.array(pts, float); idx = np.array(idx); cnt = np.array(cnt)
        interp = pv.GetInterpolation(); off = 0
        for c in cnt:
            vs = idx[off:off + c]
            if interp == 'faceVarying': u = uv[off:off + c]
            elif interp in ('vertex', 'varying'): u = uv[vs]
            else: off += c; continue
            polys.append((P[vs], u, prim.GetPath().pathString)); off += c
    return polys

def fan_flips(polys):
    """(n polygons >3, fan tris, flipped-in-UV where 3D fan triangle is positive, both negative)."""
    res = dict(polys=0, fan_bad=0, fan_concave=0, examples=[])
    signs = []
    items = []
    for p in polys:
        X, U = p[0], p[1]
        if len(X) < 4: continue
        res['polys'] += 1
        n = np.zeros(3)
        for i in range(len(X)):
            a, b = X[i], X[(i + 1) % len(X)]
            n += np.cross(a, b)
        area = np.linalg.norm(n) / 2
        if area == 0: continue
        n /= np.linalg.norm(n)
        ua = 0.0
        for i in range(len(U)):
            a, b = U[i], U[(i + 1) % len(U)]; ua += a[0] * b[1] - a[1] * b[0]
        for k in range(1, len(X) - 1):
            s3 = np.dot(np.cross(X[k] - X[0], X[k + 1] - X[0]), n) / 2
            e1, e2 = U[k] - U[0], U[k + 1] - U[0]
            su = (e1[0] * e2[1] - e1[1] * e2[0]) / 2
            items.append((s3 / area, su, ua, p[2] if len(p) > 2 else '', k, len(X)))
    if not items: return res
    # orientation of UV relative to 3D: majority sign of su over clearly positive 3D fan triangles
    SG = {}
    for s3, su, ua, name, k, nc in items:
        if s3 > 1e-3 and su != 0:
            SG.setdefault(name, [0, 0])[su > 0] += 1
    for s3, su, ua, name, k, nc in items:
        sgn = 1 if SG.get(name, [0, 0])[1] >= SG.get(name, [0, 0])[0] else -1
        if s3 > 1e-3 and sgn * su < 0:
            res['fan_bad'] += 1
            if len(res['examples']) < 3: res['examples'].append((name, k, nc, round(s3, 4), su))
        elif s3 < -1e-3 and sgn * su < 0:
            res['fan_concave'] += 1
    return res

if __name__ == '__main__':
    out = {}
    for line in open(sys.argv[1]):
        d = json.loads(line)
        f, o = d['file'], d.get('out')
        r = {}
        if o:
            try:
                if o.endswith('.obj'):
                    if f.lower().endswith('.obj'):
                        r.update(compare_obj(f, o))
                    r.update(fan_flips(parse_obj(o)))
                else:
                    r.update(fan_flips(parse_usd(o)))
            except Exception as e:
                r['check_error'] = repr(e)[:200]
        out[f] = r
    json.dump(out, open(sys.argv[2], 'w'), indent=1)
