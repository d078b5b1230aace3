"""bd_uv batch --resume after the batch process was killed (SIGKILL): nothing lost, nothing done
twice.

The first run is a child process killed once some files are in its journal. The second run, with
--resume, must keep every output the journal certifies untouched (same modification time and
bytes), redo a file whose input changed and one whose output was deleted, run the rest, and end
with a complete report.
"""
import argparse
import json
import os
import pathlib
import signal
import subprocess
import sys
import time

import numpy as np

from bd_uv import batch
from bd_uv.scheduling import file_sha256
from helpers import reference_distortion
from test_batch_dask import asset_folder, read_obj

REPO = pathlib.Path(__file__).resolve().parents[2]


def run(*argv):
    parser = argparse.ArgumentParser()
    batch.add_batch_parser(parser.add_subparsers())
    args = parser.parse_args(["batch", *map(str, argv)])
    return args.func(args)


def journal_lines(path):
    try:
        return path.read_text().splitlines()
    except OSError:
        return []


def test_killed_batch_resumes_without_recomputing_certified_outputs(tmp_path):
    files = asset_folder(tmp_path / "in", big=6, small=40)
    out = tmp_path / "out"
    journal = out / "report.json.journal"
    cmd = [sys.executable, "-m", "bd_uv", "batch", str(tmp_path / "in"), "-o", str(out),
           "--jobs", "1", "--bound", "4", "--seams", "none"]
    proc = subprocess.Popen(cmd, cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    while len(journal_lines(journal)) < 5 and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.005)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    err = proc.stderr.read().decode()
    assert proc.returncode == -signal.SIGKILL, err            # killed, not finished

    first = [json.loads(line) for line in journal_lines(journal)]
    assert 5 <= len(first) < len(files)
    kept = {}
    for rec in first:
        (e,) = rec["entries"]
        assert e["status"] == "certified" and e["output_sha256"] == file_sha256(e["output"])
        kept[os.path.basename(rec["input"])] = (e, os.stat(e["output"]).st_mtime_ns)
    # two of them must be redone: one input changed, one output deleted
    changed, deleted = sorted(kept)[:2]
    V, F, _ = read_obj(kept[changed][0]["output"])
    text = (tmp_path / "in" / changed).read_text()
    (tmp_path / "in" / changed).write_text(text.replace("OFF\n", "OFF\n# edited\n", 1))
    os.remove(kept[deleted][0]["output"])
    untouched = {n: v for n, v in kept.items() if n not in (changed, deleted)}

    time.sleep(0.01)   # a file rewritten now gets a later mtime even on coarse clocks
    assert run(tmp_path / "in", "-o", out, "--jobs", "2", "--bound", "4", "--seams", "none", "--resume") == 1

    rep = json.loads((out / "report.json").read_text())
    s = rep["summary"]
    assert (s["files"], s["meshes"], s["certified"], s["failed"], s["not_run"]) == \
        (len(files), len(files), len(files) - 2, 2, 0)
    assert s["resumed"] == len(untouched) and not s["running"] and not journal.exists()
    items = {os.path.basename(e["input"]): e for e in rep["items"]}
    assert set(items) == {f.name for f in files}
    for name, (entry, mtime) in untouched.items():
        assert items[name] == entry                               # the same report entry
        assert os.stat(entry["output"]).st_mtime_ns == mtime      # and output, not rewritten
        assert file_sha256(entry["output"]) == entry["output_sha256"]
    assert items[changed]["input_sha256"] != kept[changed][0]["input_sha256"]
    assert os.stat(items[changed]["output"]).st_mtime_ns > kept[changed][1]
    assert os.path.isfile(items[deleted]["output"])
    for name, e in items.items():
        if e["status"] != "certified":
            continue
        V, F, uv = read_obj(e["output"])
        D, flipped = reference_distortion(V, F, uv)
        assert not flipped.any() and D.max() <= 4.0 * (1 + 1e-9)
        assert np.isclose(e["max_distortion"], D.max(), rtol=1e-9)
        assert file_sha256(e["output"]) == e["output_sha256"]
    assert not [n for n in os.listdir(out) if n.startswith(".")]  # no temporary file left

    # nothing certified changes on a second resume; other options redo everything
    mtimes = {n: os.stat(e["output"]).st_mtime_ns for n, e in items.items() if e["output"]}
    assert run(tmp_path / "in", "-o", out, "--jobs", "1", "--bound", "4", "--seams", "none", "--resume") == 1
    again = json.loads((out / "report.json").read_text())
    assert again["summary"]["resumed"] == len(files) - 2
    assert {n: os.stat(e["output"]).st_mtime_ns for n, e in items.items() if e["output"]} == mtimes


def test_previous_entries_merge_report_and_journal_and_skip_a_cut_line(tmp_path):
    """The journal's lines override the report's items; a last line cut short by a kill is
    ignored; a file is reusable only with the same input bytes, options and output bytes."""
    from bd_uv.scheduling import options_sha256, read_previous, reusable
    src, out = tmp_path / "a.off", tmp_path / "a.obj"
    src.write_text("OFF\n")
    out.write_text("v 0 0 0\n")
    key = options_sha256({"bound": 3.0}, None)
    entry = {"input": str(src), "output": str(out), "status": "certified", "png": None,
             "input_sha256": file_sha256(src), "options_sha256": key,
             "output_sha256": file_sha256(out)}
    report = tmp_path / "report.json"
    report.write_text(json.dumps({"items": [dict(entry, status="failed"),
                                            {"input": "/x/b.off", "status": "certified"}]}))
    line = json.dumps({"input": str(src), "entries": [entry]})
    (tmp_path / "report.json.journal").write_text(line + "\n" + line[:40])
    previous = read_previous(str(report))
    assert previous == {str(src): [entry], "/x/b.off": [{"input": "/x/b.off",
                                                          "status": "certified"}]}
    task = batch.FileTask(str(src), str(out))
    assert reusable(task, previous[str(src)], key)
    assert not reusable(task, previous[str(src)], options_sha256({"bound": 4.0}, None))
    assert not reusable(batch.FileTask(str(src), str(out), str(tmp_path / "a.png")),
                        previous[str(src)], key)                   # the picture is missing
    out.write_text("v 0 0 1\n")
    assert not reusable(task, previous[str(src)], key)             # the output changed
    out.write_text("v 0 0 0\n")
    src.write_text("OFF\n\n")
    assert not reusable(task, previous[str(src)], key)             # the input changed
