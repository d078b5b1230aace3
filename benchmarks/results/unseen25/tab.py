import json, sys, os
def load(t): return {json.loads(l)['file']: json.loads(l) for l in open(f'res-{t}.jsonl')}
O, N = load('old'), load('new')
CO = json.load(open('chk-old.json')) if os.path.exists('chk-old.json') else {}
CN = json.load(open('chk-new.json')) if os.path.exists('chk-new.json') else {}
src = {'mikedh+trimesh': 'trimesh a513c0e2', 'tinyobjloader+tinyobjloader': 'tinyobjloader b5346fa',
       'alecjacobson+common-3d-test-models': 'alecjacobson 8a4f864', 'usd-wg+assets': 'usd-wg 274fa45',
       'PixarAnimationStudios+OpenUSD': 'OpenUSD 59992d21', 'assimp+assimp': 'assimp 21bea12f'}
def ci(d):
    if d.get('cert') is None: return '-'
    return f"{d['cert']}/{d['isl']}" + (f" ({d['mc']})" if d.get('mc') else '')
def rep(t, f):
    key = f.replace('/tmp/unseen25/in/', '').replace('/', '__')
    try: return json.load(open(f'out/{t}/{key}.json'))
    except Exception: return None
def fix(d, t):
    R = rep(t, d['file'])
    if R and 'meshes' in R:
        ms = R['meshes']
        d['cert'] = sum(e.get('status') == 'certified' for m in ms for e in (m.get('islands') or []))
        d['isl'] = sum(len(m.get('islands') or []) for m in ms)
        d['mc'] = f"{sum(m.get('status') == 'certified' for m in ms)}/{len(ms)} meshes"
        d['zero'] = sum(m.get('zero_area_faces') or 0 for m in ms) or ''
        d['tri'] = sum(m.get('polygons_as_triangles') or 0 for m in ms)
rows = []
for f in [l.strip() for l in open(sys.argv[1])]:
    if f not in O or f not in N: continue
    if os.path.getsize(f) == 0: continue
    o, n = O[f], N[f]
    fix(o, 'old'); fix(n, 'new')
    rel = f.replace('/tmp/unseen25/in/', '')
    s, path = rel.split('/', 1)
    co, cn = CO.get(f, {}), CN.get(f, {})
    notes = []
    if o['tb'] or n['tb']: notes.append(f"TB old={o['tb']} new={n['tb']}")
    if cn.get('other_diff'): notes.append(f"{cn['other_diff']} non-vt/f lines differ")
    if cn.get('f_changed'): notes.append(f"{cn['f_changed']} f v/vn changed")
    if cn.get('fan_bad') or co.get('fan_bad'): notes.append(f"fan UV flips old {co.get('fan_bad',0)} new {cn.get('fan_bad',0)}")
    if cn.get('check_error'): notes.append('chk: ' + cn['check_error'][:60])
    flag = ''
    fo = (o.get('isl') or 0) - (o.get('cert') or 0); fn = (n.get('isl') or 0) - (n.get('cert') or 0)
    mo = int(o['mc'].split('/')[0]) if o.get('mc') else 0; mn = int(n['mc'].split('/')[0]) if n.get('mc') else 0
    if n['rc'] > o['rc'] or fn > fo or mn < mo or (o.get('cert') and not n.get('cert')): flag = 'WORSE'
    elif n['rc'] < o['rc'] or fn < fo or mn > mo: flag = 'better'
    if n['cpu'] > 2 * o['cpu'] + 3: flag += ' slower'
    if n['rc'] != 0 and not n.get('cert'):
        notes.append(n['stderr'].strip().splitlines()[-1][:90] if n['stderr'].strip() else '')
    rows.append((src[s], path, o['rc'], n['rc'], ci(o), ci(n), n.get('tri') or 0, n.get('zero') or '',
                 o['cpu'], n['cpu'], cn.get('polys', ''), flag, '; '.join(x for x in notes if x)))
print('| source | file | rc old | rc new | certified/islands old | new | polygons as triangles (new) | zero_area_faces (new) | CPU s old | new | polygons (>3) written (new) | change | notes |')
print('|' + '---|' * 13)
for r in rows: print('| ' + ' | '.join(str(x).replace('|', '/') for x in r) + ' |')
