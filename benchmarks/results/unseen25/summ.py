import json, os, sys, collections
exec(open('tab.py').read().split("rows = []")[0].replace("print(", "pass  # ("))
def S(tagO, tagN, lst):
    O = {json.loads(l)['file']: json.loads(l) for l in open(f'res-{tagO}.jsonl')}
    N = {json.loads(l)['file']: json.loads(l) for l in open(f'res-{tagN}.jsonl')}
    files = [f for f in dict.fromkeys(l.strip() for l in open(lst) if l.strip()) if f in O and f in N and os.path.getsize(f)]
    out = {}
    for t, D in (('old', O), ('new', N)):
        rc = collections.Counter(D[f]['rc'] for f in files)
        for f in files: fix(D[f], tagO if t == 'old' else tagN)
        cert = sum(D[f].get('cert') or 0 for f in files); isl = sum(D[f].get('isl') or 0 for f in files)
        tb = sum(D[f]['tb'] for f in files); cpu = sum(D[f]['cpu'] for f in files)
        tri = sum(D[f].get('tri') or 0 for f in files); zero = sum(1 for f in files if D[f].get('zero'))
        out[t] = dict(files=len(files), rc=dict(sorted(rc.items())), certified=cert, islands=isl, tracebacks=tb, cpu=round(cpu, 1), poly_as_tri=tri, files_with_zero_area=zero)
    return out
print(json.dumps(S(sys.argv[1], sys.argv[2], sys.argv[3])))
