import sys, os, json
from pxr import Usd, UsdGeom, Tf
Tf.Debug  # quiet
out = []
for root in sys.argv[1:]:
    for dp, dn, fn in os.walk(root):
        for f in fn:
            if not f.endswith(('.usda', '.usd', '.usdc')): continue
            p = os.path.join(dp, f)
            try:
                st = Usd.Stage.Open(p)
            except Exception:
                continue
            if st is None: continue
            nm = nf = npoly = mx = 0
            for prim in st.Traverse():
                if prim.IsA(UsdGeom.Mesh):
                    c = UsdGeom.Mesh(prim).GetFaceVertexCountsAttr().Get()
                    if c is None:
                        ts = UsdGeom.Mesh(prim).GetFaceVertexCountsAttr().GetTimeSamples()
                        if ts: c = UsdGeom.Mesh(prim).GetFaceVertexCountsAttr().Get(ts[0])
                    if c is None: continue
                    nm += 1; nf += len(c); npoly += sum(1 for k in c if k > 3); mx = max([mx] + list(c))
            if nm: out.append((p, nm, nf, npoly, mx))
json.dump(out, open('usdscan.json', 'w'))
print(len(out), sum(1 for o in out if o[3] > 0))
