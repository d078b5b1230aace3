"""USD files that usd-core itself dies on (SIGABRT, SIGSEGV) or cannot copy are refused with an
error naming the file, before any unwrap, and nothing is written (``bd_uv.scenes.usd_probe``).

The files are tests/data/usd-core-*.usdc and usd-copy-fails.usdc: the scene fuzz contract's own
stage saved as a crate file with a byte or two flipped (tests/data/README.md). Each unwrap runs
in a subprocess: a regression would otherwise end the test run itself, which is how the first one
was seen (a CI run of the suite ended with SIGABRT and no message).
"""
import hashlib
import json
import os
import shutil
import subprocess
import sys

import pytest

pytest.importorskip("pxr")

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DATA = os.path.join(ROOT, "tests", "data")


def _run(args, cwd):
    env = dict(os.environ, PYTHONPATH=ROOT)
    return subprocess.run([sys.executable, "-m", "bd_uv"] + args, cwd=cwd, env=env,
                          capture_output=True, text=True, check=False)


def _usd_core_steps(path, source):
    """The return code of a new process running ``source`` (pxr calls on ``path``)."""
    import pxr
    where = os.path.dirname(os.path.dirname(os.path.abspath(pxr.__file__)))
    return subprocess.run([sys.executable, "-c", source, where, path], capture_output=True,
                          check=False).returncode


# usd-core's steps on each file that end the process: the segfault one dies in Usd.Stage.Open
# itself (bd-uv's reading without the probe died with it, 5 runs of 5); the abort one raises
# there (bd-uv refused it) and dies in the steps after (the copy the writing makes; a process that
# went on after the refusal, as the test run did, died later)
OPEN_ONLY = ("import sys; sys.path.insert(0, sys.argv[1]); from pxr import Usd\n"
             "Usd.Stage.Open(sys.argv[2])")


@pytest.mark.parametrize("name,signal_name,premise", [
    ("usd-core-abort.usdc", "SIGABRT", "probe"),
    ("usd-core-segfault.usdc", "SIGSEGV", "open")])
def test_a_file_usd_core_dies_on_is_refused_by_name_and_nothing_written(tmp_path, name,
                                                                         signal_name, premise):
    import signal
    from bd_uv.scenes import usd_probe
    src = str(tmp_path / name)
    shutil.copy(os.path.join(DATA, name), src)
    code = _usd_core_steps(src, usd_probe._SOURCE if premise == "probe" else OPEN_ONLY)
    if code != -getattr(signal, signal_name):
        pytest.skip(f"usd-core's steps on {name} end with {code}: the premise no longer holds")
    before = hashlib.sha256(open(src, "rb").read()).hexdigest()
    out, rep = tmp_path / "o" / "out.usdc", tmp_path / "r.json"
    run = _run(["unwrap", src, "-o", str(out), "--report", str(rep)], str(tmp_path))
    assert run.returncode == 2, (run.returncode, run.stderr[-2000:])
    assert "Traceback" not in run.stderr
    assert f"{src}: usd-core stops on this file (killed by {signal_name}" in run.stderr
    assert "nothing was written" in run.stderr
    assert not out.exists() and not (tmp_path / "o").exists() or not os.listdir(tmp_path / "o")
    assert hashlib.sha256(open(src, "rb").read()).hexdigest() == before


def test_a_batch_reports_the_file_usd_core_dies_on_and_unwraps_the_rest(tmp_path):
    """One bad file among good ones: its own failed entry, the good file unwrapped, the batch
    alive."""
    inp = tmp_path / "in"
    inp.mkdir()
    shutil.copy(os.path.join(DATA, "usd-core-abort.usdc"), inp / "bad.usdc")
    sys.path.insert(0, os.path.join(ROOT, "tests", "core"))
    try:
        from test_fuzz_scenes import _stage
    finally:
        sys.path.pop(0)
    _stage(str(inp / "good.usda"), "none", 0)
    out = tmp_path / "out"
    run = _run(["batch", str(inp), "-o", str(out)], str(tmp_path))
    assert "Traceback" not in run.stderr, run.stderr[-2000:]
    assert run.returncode == 1, run.stderr[-2000:]      # one file failed, the batch went on
    report = json.load(open(out / "report.json"))
    entries = {os.path.basename(e["input"]): e for e in report["items"]}
    bad, good = entries["bad.usdc"], entries["good.usda"]
    assert bad["status"] == "failed" and bad["error"] == "SceneFileError" and not bad["output"]
    assert "usd-core stops on this file (killed by SIGABRT" in bad["message"]
    assert good["status"] == "certified" and os.path.isfile(good["output"])
    assert sorted(os.listdir(out)) == ["good.usda", "report.json"]


def test_a_root_layer_usd_core_cannot_copy_is_refused_before_the_unwrap(tmp_path):
    """Its stage opens and its meshes read; copying its root layer (how the UVs are written)
    raises: refused when read, with usd-core's words, not after the unwrap with a traceback."""
    from bd_uv.errors import SceneFileError
    from bd_uv.scenes import read_scene
    src = str(tmp_path / "shot.usdc")
    shutil.copy(os.path.join(DATA, "usd-copy-fails.usdc"), src)
    from pxr import Sdf, Tf, Usd
    stage = Usd.Stage.Open(src)                   # the premise: it opens, its copy raises
    assert stage is not None
    with pytest.raises(Tf.ErrorException):
        Sdf.Layer.CreateAnonymous(".usdc").TransferContent(Sdf.Layer.FindOrOpen(src))
    with pytest.raises(SceneFileError) as err:
        read_scene(src)
    assert str(err.value).startswith(f"{src}: USD could not copy its root layer to write the UVs")
    assert "Zero-copy data range out-of-bounds" in str(err.value)
    run = _run(["unwrap", src, "-o", str(tmp_path / "out.usdc")], str(tmp_path))
    assert run.returncode == 2 and "Traceback" not in run.stderr, run.stderr[-2000:]
    assert not (tmp_path / "out.usdc").exists()


def test_a_pxr_message_listing_millions_of_specs_is_cut():
    """A damaged crate file's error listed 10 million skipped specs (400 MB): its one-line form
    is cut at MESSAGE_CHARS, not split whole (which raised MemoryError out of the reader)."""
    from bd_uv.scenes.usd import MESSAGE_CHARS, _pxr_message
    big = RuntimeError("Corrupt asset: " + "spec at index 7 has empty path, " * 200_000)
    said = _pxr_message(big)
    assert said.startswith("Corrupt asset: spec at index 7 has empty path,")
    assert said.endswith(" ...") and len(said) <= MESSAGE_CHARS + 4
    assert _pxr_message(RuntimeError("short  text\n two lines")) == "short text two lines"


def test_a_sound_stage_passes_the_probe_and_is_read(tmp_path):
    from bd_uv.scenes import read_scene
    from bd_uv.scenes.usd_probe import probe
    sys.path.insert(0, os.path.join(ROOT, "tests", "core"))
    try:
        from test_fuzz_scenes import _stage
    finally:
        sys.path.pop(0)
    path = str(tmp_path / "shot.usdc")
    _stage(path, "nested instanceable", 3)
    assert probe(path) is None
    scene = read_scene(path)
    assert len(scene.meshes) >= 1 and all(len(m.mesh.F) > 0 for m in scene.meshes)


@pytest.mark.parametrize("source,refused", [
    ("import os; os.abort()", "killed by SIGABRT"),
    ("import sys; sys.stderr.write('x\\nFATAL ERROR: a spec  gone\\n'); sys.exit(7)",
     "exit 7, FATAL ERROR: a spec gone"),
    ("import sys; sys.stdout.write('the copy\\n raised'); sys.exit(11)", None),
    ("import sys; sys.exit(10)", ""),
    ("raise ImportError('no pxr here')", ""),
    ("pass", "")])
def test_the_probes_end_decides(monkeypatch, tmp_path, source, refused):
    """Dead (a signal, or any exit but 0, 1, 10, 11): refused with how it died and usd-core's
    fatal line; 11: refused with what the copy raised; 0, 10 (the reading refuses it itself) and
    1 (the probe could not run): passed on."""
    from bd_uv.errors import SceneFileError
    from bd_uv.scenes import usd_probe
    monkeypatch.setattr(usd_probe, "_SOURCE", source)
    path = str(tmp_path / "a.usda")
    open(path, "w").write("#usda 1.0\n")
    if refused == "":
        assert usd_probe.probe(path) is None
        return
    with pytest.raises(SceneFileError) as err:
        usd_probe.probe(path)
    if refused is None:
        assert str(err.value) == (f"{path}: USD could not copy its root layer to write the UVs, "
                                  "the file is damaged (the copy raised); nothing was written")
    else:
        assert str(err.value) == (f"{path}: usd-core stops on this file ({refused}): it is "
                                  "damaged or holds something usd-core cannot read; nothing "
                                  "was written")


def test_a_stage_at_zero_time_codes_per_second_is_refused_not_waited_on(tmp_path, capsys):
    """usd-wg/assets' timeCodesPerSecond_0.usda: usd-core never returns from reading a
    time-sampled value of a sublayer through a root layer at timeCodesPerSecond = 0 (the CLI
    waited for ever). The probe names the layer and the fix; the input stays as it was."""
    from pxr import Sdf, Usd, UsdGeom
    from bd_uv.cli import main
    sub = Usd.Stage.CreateNew(str(tmp_path / "anim.usda"))
    mesh = UsdGeom.Mesh.Define(sub, "/World/Tri")
    mesh.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    mesh.CreateFaceVertexCountsAttr([3])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2])
    move = UsdGeom.Xformable(mesh).AddTranslateOp()
    move.Set((0.0, 0.0, 0.0), 0.0)
    move.Set((1.0, 0.0, 0.0), 10.0)
    sub.GetRootLayer().Save()
    root = Sdf.Layer.CreateNew(str(tmp_path / "shot.usda"))
    root.subLayerPaths.append("anim.usda")
    root.timeCodesPerSecond = 0.0
    root.Save()
    before = (tmp_path / "shot.usda").read_bytes()
    assert main(["unwrap", str(tmp_path / "shot.usda"), "-o", str(tmp_path / "o.usda")]) == 2
    err = capsys.readouterr().err
    assert "sets timeCodesPerSecond = 0" in err and "shot.usda" in err
    assert "nothing was written" in err and not (tmp_path / "o.usda").exists()
    assert (tmp_path / "shot.usda").read_bytes() == before


def test_a_probe_that_never_ends_is_refused_after_its_time(monkeypatch, tmp_path):
    from bd_uv.errors import SceneFileError
    from bd_uv.scenes import usd_probe
    monkeypatch.setattr(usd_probe, "_SOURCE", "import time; time.sleep(60)")
    monkeypatch.setattr(usd_probe, "PROBE_SECONDS", 0.5)
    path = str(tmp_path / "a.usda")
    open(path, "w").write("#usda 1.0\n")
    with pytest.raises(SceneFileError) as err:
        usd_probe.probe(path)
    assert str(err.value) == (f"{path}: usd-core did not finish reading this file in 0.5 s (it "
                              "loops on some malformed stages); nothing was written")
