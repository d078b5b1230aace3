"""Rebuild the benchmark meshes earlier sessions kept in /tmp, at the same paths, in one command.

    PYTHONPATH=$PWD python3.11 benchmarks/unseen_meshes.py --root /work/.mirror [--group 21 18 rest]

``--root`` is where the project's ``fetch`` tool puts repositories (``<owner>+<name>/repo``, a
bare git directory or one with ``.git`` inside); ``--git owner/name=GITDIR`` names one directly.
Every file is read at the commit recorded below (``git show COMMIT:path``), so a newer mirror
gives the same meshes as long as it still holds that commit. ``--shared`` is the shared mesh
directory (CC0 meshes of its MANIFEST.tsv: camel, cow, ChineseDragon-10kv, mannequin-devil).
A file already present is kept (``--force`` rewrites it). The face count of each file is
printed against the count the results files give, and the run fails if one differs.

Groups (in the order other helpers wait on them):

- ``21``: issue 21's disks and closed meshes: /tmp/unseen/spot.obj, /tmp/u11/m/{knight,elephant,
  shaderball,cesiumman}.obj, /tmp/auto15/m/*-patch*.obj (``assets.patch``),
  /tmp/unseen16/m/*-ball*/-strip*.obj (``assets.ball`` / ``assets.strip``).
- ``18``: issue 18's: /tmp/unseen/{rocker-arm,homer}.obj, /tmp/unseen14/m/igl-{arm,elephant}.obj,
  assimp's Spider_binary.stl and Wuson.off under /tmp/unseen22/a/test/models/, /tmp/s24/max3ds.stl
  and /tmp/s24/wuson.stl.
- ``rest``: the other unseen14 and u11 meshes, /tmp/unseen's cheburashka, alligator and woody.

How each was made (from benchmarks/results/):

- common-3d-test-models (unseen11, lead-2026-11-28.md): ``data/<name>.obj`` copied byte for byte.
- libigl-tutorial-data (unseen14-2026-11-28.md): ``trimesh.load(process=True)`` (merges duplicate
  vertices; face counts unchanged), exported as OBJ to /tmp/unseen14/m/igl-<name>.obj.
- usd-wg/assets (unseen11-2026-11-28.md): the named UsdGeom.Mesh prim's points and faces (local
  coordinates, default time), polygons fan-triangulated (0, i, i+1), points welded by exact
  position (first occurrence kept, in file order), written with ``assets.write_obj``.
- assimp (unseen22-2026-11-28.md, issue18-many24-2026-11-28.md): test/models files copied byte for
  byte; /tmp/s24/max3ds.stl is ``test/models/STL/3DSMaxExport.STL``, /tmp/s24/wuson.stl is
  ``test/models/STL/Wuson.stl``.
- auto15 patches (issue21-auto15-2026-11-28.md): ``assets.patch(path, N, out_dir=...)``.
- unseen16 balls and strips (issue21-unseen16-2026-11-28.md section 1): ``assets.ball`` and
  ``assets.strip``.

Licences: none of these meshes may be committed or shared beyond this machine's /tmp (the results
files say so). libigl-tutorial-data has no licence file (its README names each model's origin);
common-3d-test-models gives a source per model and no licence for spot/homer/rocker-arm; usd-wg
assets is Apache-2.0 with per-asset READMEs; assimp is BSD-3-Clause. The shared meshes are CC0.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, HERE)
sys.path.insert(0, REPO)

import assets  # noqa: E402


@dataclass(frozen=True)
class Source:
    repo: str
    commit: str
    licence: str


SOURCES = {
    "igl": Source("libigl/libigl-tutorial-data", "c1f9ede366d02e3531ecbaec5e3769312f31cccd",
                  "no licence file; README names each model's source"),
    "c3d": Source("alecjacobson/common-3d-test-models", "8a4f8642acaf43f9cd7b67858a1502e1055ef202",
                  "per model in README.md (spot: Keenan Crane; homer, rocker-arm: unclear)"),
    "usd": Source("usd-wg/assets", "274fa4584dd6afe7e7d84ea30e1ec9c652858d9a",
                  "Apache-2.0 (LICENSE), per-asset READMEs"),
    "assimp": Source("assimp/assimp", "21bea12f1278090c09a94c39ca090d9fb458ccd9",
                     "BSD-3-Clause (LICENSE)"),
}


@dataclass(frozen=True)
class Spec:
    """One mesh to write: ``out`` from ``how`` (a tuple: kind and its arguments)."""
    group: str
    out: str
    how: tuple
    faces: int


def _specs():
    S = []
    u, u11, u14 = "/tmp/unseen", "/tmp/u11/m", "/tmp/unseen14/m"
    a15, u16 = "/tmp/auto15/m", "/tmp/unseen16/m"
    usd_knight = ("full_assets/OpenChessSet/assets/Knight", "Knight.usd", "/Knight/Geom/Render")
    # group 21 --------------------------------------------------------------------------------
    S += [Spec("21", f"{u}/spot.obj", ("copy", "c3d", "data/spot.obj"), 5856),
          Spec("21", f"{u11}/knight.obj", ("usd", *usd_knight), 11184),
          Spec("21", f"{u11}/elephant.obj",
               ("usd", "full_assets/ElephantWithMonochord", "SoC-ElephantWithMonochord.usdc",
                "/SoC_ElephantWithMonochord/Object/Elefant/Elefant1"), 2064),
          Spec("21", f"{u11}/shaderball.obj",
               ("usd", "full_assets/StandardShaderBall", "standard_shader_ball_scene.usda",
                "/standard_shader_ball_scene/shader_ball/material_surface"), 11676),
          Spec("21", f"{u11}/cesiumman.obj",
               ("usd", "test_assets/USDZ/CesiumMan", "CesiumMan.usdz",
                "/CesiumMan/Geom/Z_UP/Armature/Skeleton_torso_joint_1_3/Cesium_Man_2"), 4672),
          # the inputs of the patches below that the groups above do not hold
          Spec("21", f"{u}/homer.obj", ("copy", "c3d", "data/homer.obj"), 12000),
          Spec("21", f"{u14}/igl-elephant.obj", ("igl", "elephant.obj"), 12064),
          Spec("21", f"{u14}/igl-bunny.obj", ("igl", "bunny.off"), 6966),
          Spec("21", f"{u14}/igl-decimated-knight.obj", ("igl", "decimated-knight.off"), 1000)]
    S += [Spec("21", f"{a15}/camel-patch1200.obj", ("patch", "shared:camel.off", 1200), 1324),
          Spec("21", f"{a15}/homer-patch3000.obj", ("patch", f"{u}/homer.obj", 3000), 3521),
          Spec("21", f"{a15}/igl-elephant-patch2000.obj",
               ("patch", f"{u14}/igl-elephant.obj", 2000), 2004),
          Spec("21", f"{a15}/igl-bunny-patch1500.obj", ("patch", f"{u14}/igl-bunny.obj", 1500),
               1595),
          Spec("21", f"{a15}/ChineseDragon-10kv-patch1500.obj",
               ("patch", "shared:ChineseDragon-10kv.off", 1500), 1577)]
    S += [Spec("21", f"{u16}/cow-strip1200x.obj", ("strip", "shared:cow.off", 1200, "x"), 1251),
          Spec("21", f"{u16}/knight-ball3000top.obj", ("ball", f"{u11}/knight.obj", 3000, "top"),
               3028),
          Spec("21", f"{u16}/mannequin-devil-strip1000y.obj",
               ("strip", "shared:mannequin-devil.off", 1000, "y"), 1112),
          Spec("21", f"{u16}/homer-strip1800y.obj", ("strip", f"{u}/homer.obj", 1800, "y"), 1982),
          Spec("21", f"{u16}/igl-decimated-knight-strip800y.obj",
               ("strip", f"{u14}/igl-decimated-knight.obj", 800, "y"), 976)]
    # group 18 --------------------------------------------------------------------------------
    models = "/tmp/unseen22/a/test/models"
    S += [Spec("18", f"{u}/rocker-arm.obj", ("copy", "c3d", "data/rocker-arm.obj"), 20088),
          Spec("18", f"{u14}/igl-arm.obj", ("igl", "arm.obj"), 16618),
          Spec("18", f"{models}/STL/Spider_binary.stl",
               ("copy", "assimp", "test/models/STL/Spider_binary.stl"), 1368),
          Spec("18", f"{models}/OFF/Wuson.off", ("copy", "assimp", "test/models/OFF/Wuson.off"),
               3732),
          Spec("18", "/tmp/s24/max3ds.stl",
               ("copy", "assimp", "test/models/STL/3DSMaxExport.STL"), 2000),
          Spec("18", "/tmp/s24/wuson.stl", ("copy", "assimp", "test/models/STL/Wuson.stl"), 3732)]
    # rest ------------------------------------------------------------------------------------
    for name, faces in [("cheburashka", 13334), ("alligator", 5981), ("woody", 1267)]:
        S.append(Spec("rest", f"{u}/{name}.obj", ("copy", "c3d", f"data/{name}.obj"), faces))
    for name, faces in [("bumpy.off", 2496), ("screwdriver.off", 6786), ("3holes.off", 7200),
                        ("fertility.off", 9000), ("decimated-max.obj", 10540)]:
        S.append(Spec("rest", f"{u14}/igl-{os.path.splitext(name)[0]}.obj", ("igl", name), faces))
    S += [Spec("rest", f"{u11}/fancyteapot.obj",
               ("usd", "full_assets/Teapot", "DrawModes.usd", "/World/FancyTeapot_0/Geometry"),
               12144),
          Spec("rest", f"{u11}/pawntop.obj",
               ("usd", "full_assets/OpenChessSet/assets/Pawn", "Pawn.usd",
                "/Pawn/Geom_Top/Render"), 2208),
          Spec("rest", f"{u11}/ballbase.obj",
               ("usd", "full_assets/StandardShaderBall", "standard_shader_ball_scene.usda",
                "/standard_shader_ball_scene/shader_ball/neutral_objects/base"), 1584)]
    return S


SPECS = _specs()


class Builder:
    def __init__(self, root, gits, shared, scratch):
        self.root, self.gits, self.shared, self.scratch = root, gits, shared, scratch
        self._trees = set()

    def git_dir(self, key):
        repo = SOURCES[key].repo
        if repo in self.gits:
            return self.gits[repo]
        base = os.path.join(self.root or "", repo.replace("/", "+"))
        for cand in (os.path.join(base, "repo", ".git"), os.path.join(base, "repo"), base):
            if os.path.isdir(os.path.join(cand, "objects")):
                return cand
        raise SystemExit(f"{repo}: no git directory under {base} (fetch github:{repo}, or pass "
                         f"--git {repo}=GITDIR)")

    def _git(self, key, *args):
        return subprocess.run(["git", f"--git-dir={self.git_dir(key)}", *args],
                              capture_output=True, check=True).stdout

    def blob(self, key, path):
        return self._git(key, "show", f"{SOURCES[key].commit}:{path}")

    def tree(self, key, prefix):
        """Write every blob under ``prefix`` at the recorded commit to the scratch directory
        (USD layers refer to their neighbours); blobs absent from the mirror are skipped."""
        dest = os.path.join(self.scratch, key)
        if (key, prefix) not in self._trees:
            listing = self._git(key, "ls-tree", "-r", "-z", SOURCES[key].commit, prefix)
            for ent in filter(None, listing.split(b"\0")):
                meta, path = ent.split(b"\t", 1)
                sha = meta.split()[2].decode()
                r = subprocess.run(["git", f"--git-dir={self.git_dir(key)}", "cat-file", "blob",
                                    sha], capture_output=True)
                if r.returncode:
                    continue
                p = os.path.join(dest, path.decode())
                os.makedirs(os.path.dirname(p), exist_ok=True)
                with open(p, "wb") as fh:
                    fh.write(r.stdout)
            self._trees.add((key, prefix))
        return os.path.join(dest, prefix)

    def input_path(self, p):
        return os.path.join(self.shared, p[len("shared:"):]) if p.startswith("shared:") else p

    def build(self, spec):
        kind, *args = spec.how
        out = spec.out
        os.makedirs(os.path.dirname(out), exist_ok=True)
        if kind == "copy":
            data = self.blob(*args)
            with open(out + ".part", "wb") as fh:
                fh.write(data)
            os.replace(out + ".part", out)
        elif kind == "igl":
            import trimesh
            name = args[0]
            ext = os.path.splitext(name)[1][1:]
            tm = trimesh.load(trimesh.util.wrap_as_stream(self.blob("igl", name)), file_type=ext,
                              process=True, force="mesh")
            tm.export(out + ".part", file_type="obj")
            os.replace(out + ".part", out)
        elif kind == "usd":
            prefix, layer, prim = args
            V, F = usd_mesh(os.path.join(self.tree("usd", prefix), layer), prim)
            assets.write_obj(out, V, F)
        elif kind == "patch":
            src, n = args
            made = assets.patch(self.input_path(src), n, out_dir=os.path.dirname(out))
            assert os.path.abspath(made) == os.path.abspath(out), (made, out)
        elif kind == "ball":
            src, n, at = args
            made = assets.ball(self.input_path(src), n, at, out_dir=os.path.dirname(out))
            assert os.path.abspath(made) == os.path.abspath(out), (made, out)
        elif kind == "strip":
            src, n, axis = args
            made = assets.strip(self.input_path(src), n, axis, out_dir=os.path.dirname(out))
            assert os.path.abspath(made) == os.path.abspath(out), (made, out)
        else:
            raise ValueError(kind)


def usd_mesh(layer, prim):
    """The prim's points and fan-triangulated faces, points welded by exact position."""
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(layer)
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath(prim))
    if not mesh:
        raise SystemExit(f"{layer}: no UsdGeom.Mesh at {prim}")
    P = np.asarray(mesh.GetPointsAttr().Get(), dtype=np.float64)
    counts = np.asarray(mesh.GetFaceVertexCountsAttr().Get(), dtype=np.int64)
    idx = np.asarray(mesh.GetFaceVertexIndicesAttr().Get(), dtype=np.int64)
    starts = np.r_[0, np.cumsum(counts)[:-1]]
    tris = [np.c_[np.full(c - 2, s), s + np.arange(1, c - 1), s + np.arange(2, c)]
            for s, c in zip(starts, counts) if c >= 3]
    F = idx[np.concatenate(tris)]
    _, first, inv = np.unique(P, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)                 # welded points in order of first occurrence
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    used, F = np.unique(rank[inv.ravel()][F], return_inverse=True)
    return P[first[order]][used], F.reshape(-1, 3)


def face_count(path):
    ext = os.path.splitext(path)[1].lower()
    if ext == ".obj":
        from measure import load_mesh_by_index
        return len(load_mesh_by_index(path)[1])
    import trimesh
    return len(trimesh.load(path, process=False, force="mesh").faces)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--root", default="/work/.mirror", help="where fetch put the repositories")
    ap.add_argument("--git", action="append", default=[], metavar="OWNER/NAME=GITDIR")
    ap.add_argument("--shared", default=next(
        (p for p in (os.path.normpath(os.path.join(REPO, "..", "shared", "meshes")),
                     "/work/shared/meshes") if os.path.isdir(p)), "/work/shared/meshes"))
    ap.add_argument("--group", nargs="*", default=["21", "18", "rest"],
                    choices=["21", "18", "rest"])
    ap.add_argument("--force", action="store_true", help="rewrite files already present")
    ap.add_argument("--list", action="store_true", help="list the paths and sources only")
    a = ap.parse_args(argv)
    if a.list:
        for s in SPECS:
            print(f"{s.group:5} {s.out}  {s.faces:,}  {s.how}")
        return 0
    gits = dict(g.split("=", 1) for g in a.git)
    bad = 0
    with tempfile.TemporaryDirectory(prefix="unseen_meshes_") as scratch:
        b = Builder(a.root, gits, a.shared, scratch)
        for group in a.group:
            for s in (s for s in SPECS if s.group == group):
                if a.force and os.path.exists(s.out):
                    os.remove(s.out)
                if not os.path.exists(s.out):
                    b.build(s)
                got = face_count(s.out)
                ok = got == s.faces
                bad += not ok
                print(f"{group:5} {s.out:58} faces {got:>6,} expected {s.faces:>6,} "
                      f"{'ok' if ok else 'DIFFERS'}", flush=True)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
