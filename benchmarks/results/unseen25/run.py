"""run.py LIST TAG CODE [extra args...]: one JSON line per file to res-TAG.jsonl."""
import json, os, resource, subprocess, sys, time
lst, tag, code, *extra = sys.argv[1:]
files = [l.strip() for l in open(lst) if l.strip()]
od = f"/tmp/unseen25/out/{tag}"; os.makedirs(od, exist_ok=True)
done = set()
resf = f"/tmp/unseen25/res-{tag}.jsonl"
if os.path.exists(resf):
    done = {json.loads(l)["file"] for l in open(resf)}
env = dict(os.environ, PYTHONPATH=code, BD_UV_THREADS="1")
for i, f in enumerate(files):
    if f in done: continue
    low = f.lower()
    ext = os.path.splitext(f)[1] if low.endswith((".usd", ".usda", ".usdc")) else ".obj"
    key = f.replace("/tmp/unseen25/in/", "").replace("/", "__")
    out = f"{od}/{key}{ext}"; rep = f"{od}/{key}.json"
    for p in (out, rep):
        if os.path.exists(p): os.remove(p)
    timeout = int(os.environ.get("TMO", 0)) or (120 if os.path.getsize(f) > 3_000_000 else 90)
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN); t0 = time.time()
    p = subprocess.run(["timeout", str(timeout), "python3.11", "-m", "bd_uv", "unwrap", f, "-o", out,
                        "--report", rep, "--quiet", *extra], env=env, capture_output=True, text=True,
                       cwd=code)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    d = {"file": f, "rc": p.returncode, "cpu": round(cpu, 2), "wall": round(time.time() - t0, 1),
         "tb": "Traceback" in p.stderr, "stderr": p.stderr[-600:], "out": out if os.path.exists(out) else None}
    try:
        R = json.load(open(rep))
        s = R.get("summary", {})
        d.update(cert=s.get("certified"), isl=s.get("islands"), tri=R.get("polygons_as_triangles", 0),
                 zero=R.get("zero_area_faces"))
        if "meshes" in R:
            d["meshes"] = [(m.get("status"), m.get("name")) for m in R["meshes"]][:50]
    except Exception as e:
        d["noreport"] = str(e)[:100]
    with open(resf, "a") as fh: fh.write(json.dumps(d) + "\n")
