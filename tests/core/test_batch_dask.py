"""bd_uv batch on Dask distributed: a worker killed mid-batch, its file retried elsewhere.

The batch is 40 files made from the test meshes (perturbed copies, one unreadable, one closed).
It runs on a 2-worker LocalCluster (worker processes) while a thread kills one worker's process
after a few files; the result must match a local ``--jobs 2`` run file by file: same statuses and
errors, and certified UVs whose distortion, recomputed from the written OBJs, is the same.
"""
import argparse
import json
import os
import signal
import sys
import threading
import time

import numpy as np
import pytest

from bd_uv import batch
from test_batch import read_obj
from helpers import load_off, reference_distortion

distributed = pytest.importorskip("distributed")
dask = pytest.importorskip("dask")


@pytest.fixture(autouse=True)
def no_shadowing_dask(monkeypatch):
    """Spawned workers get this process's sys.path: drop an entry in which another folder named
    ``dask`` (or ``distributed``) would shadow the real packages there, as the parent of a
    checkout named ``dask`` does when pytest puts it on sys.path for the repo's __init__.py."""
    real = {os.path.dirname(os.path.dirname(m.__file__)) for m in (dask, distributed)}
    monkeypatch.setattr(sys, "path", [
        p for p in sys.path if os.path.abspath(p or ".") in real or not any(
            os.path.isdir(os.path.join(p or ".", name)) for name in ("dask", "distributed"))])


def run(*argv):
    parser = argparse.ArgumentParser()
    batch.add_batch_parser(parser.add_subparsers())
    args = parser.parse_args(["batch", *map(str, argv)])
    return args.func(args)


def write_off(path, V, F):
    with open(path, "w") as fh:
        fh.write(f"OFF\n{len(V)} {len(F)} 0\n")
        np.savetxt(fh, V, fmt="%.17g")
        np.savetxt(fh, np.column_stack([np.full(len(F), 3), F]), fmt="%d")


def asset_folder(folder, big=10, small=30, seed=0):
    """``big`` perturbed copies of three_peaks.off, ``small`` of nefertiti.off, a closed
    tetrahedron (fails with ``--seams none``) and an unreadable PLY: ``big + small + 2``
    files."""
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    for name, count in (("three_peaks", big), ("nefertiti", small)):
        V, F = load_off(f"{name}.off")
        edge = np.linalg.norm(V[F[:, 1]] - V[F[:, 0]], axis=1).mean()
        for k in range(count):
            noise = 0.02 * edge * rng.standard_normal(V.shape)
            write_off(folder / f"{name}-{k:02d}.off", V + noise, F)
    (folder / "tetra.off").write_text("OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                                      "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n")
    (folder / "broken.ply").write_text("ply\nformat ascii 1.0\nelement vertex 3\nend_header\n")
    return sorted(folder.iterdir())


def by_input(report_path):
    rep = json.loads(report_path.read_text())
    return rep, {os.path.basename(e["input"]): e for e in rep["items"]}


def test_dask_batch_survives_a_killed_worker_and_matches_the_local_pool(tmp_path):
    files = asset_folder(tmp_path / "in", big=6, small=32)
    assert len(files) == 40
    assert run(tmp_path / "in", "-o", tmp_path / "pool", "--jobs", "2", "--bound", "4", "--seams", "none") == 1

    with dask.config.set({"distributed.scheduler.allowed-failures": 2}), \
            distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                     dashboard_address=":0", silence_logs=50) as cluster, \
            distributed.Client(cluster) as client:
        pids = client.run(os.getpid)                      # {worker address: pid}
        assert len(set(pids.values()) - {os.getpid()}) == 2
        journal = tmp_path / "dask" / "report.json.journal"
        killed = {}

        def kill_one_worker_mid_run():
            while not journal.exists() or len(journal.read_text().splitlines()) < 4:
                time.sleep(0.01)
            busy = {w: keys for w, keys in client.processing().items() if keys}
            worker = sorted(busy)[0]
            killed.update(worker=worker, keys=list(busy[worker]))
            os.kill(pids[worker], signal.SIGKILL)

        killer = threading.Thread(target=kill_one_worker_mid_run, daemon=True)
        killer.start()
        code = run(tmp_path / "in", "-o", tmp_path / "dask", "--bound", "4", "--seams", "none",
                   "--scheduler", cluster.scheduler_address)
        killer.join(timeout=30)
        assert code == 1 and killed["keys"]
        assert pids[killed["worker"]] not in client.run(os.getpid).values()   # it did die

    pool_rep, pool = by_input(tmp_path / "pool" / "report.json")
    dask_rep, dask_items = by_input(tmp_path / "dask" / "report.json")
    assert set(pool) == set(dask_items) == {f.name for f in files}
    counts = ("files", "meshes", "certified", "partial", "failed", "not_run")
    assert [dask_rep["summary"][k] for k in counts] == [pool_rep["summary"][k] for k in counts] \
        == [40, 40, 38, 0, 2, 0]
    assert dask_rep["summary"]["scheduler"] == cluster.scheduler_address
    assert pool["tetra.off"]["error"] == dask_items["tetra.off"]["error"] == "ClosedIslandError"
    assert pool["broken.ply"]["error"] == dask_items["broken.ply"]["error"] == "InvalidMeshError"

    # the file(s) the killed worker held ran again on a live worker and were certified
    retried = [name for name, e in dask_items.items() if e.get("attempts", 1) > 1]
    assert retried and all(dask_items[n]["status"] == "certified" for n in retried)
    assert all(dask_items[n]["attempts"] == 2 for n in retried)

    for name, e in pool.items():
        d = dask_items[name]
        assert (d["status"], d["error"], d["input_sha256"], d["options_sha256"]) == \
            (e["status"], e["error"], e["input_sha256"], e["options_sha256"])
        if e["status"] != "certified":
            continue
        V, F, uv_pool = read_obj(e["output"])
        V2, F2, uv_dask = read_obj(d["output"])
        assert np.array_equal(V, V2) and np.array_equal(F, F2)
        D_pool, flip_pool = reference_distortion(V, F, uv_pool)
        D_dask, flip_dask = reference_distortion(V, F, uv_dask)
        assert not flip_pool.any() and not flip_dask.any()
        assert D_dask.max() <= 4.0 * (1 + 1e-9)
        np.testing.assert_allclose(D_dask, D_pool, rtol=1e-6)
        assert d["max_distortion"] == pytest.approx(D_dask.max(), rel=1e-9)
        assert d["bound_certified"] == e["bound_certified"] == 4.0


def test_scheduler_local_starts_a_cluster_and_runs_files_in_watched_children(tmp_path):
    """``--scheduler local`` runs a LocalCluster of --jobs workers; with --file-timeout each file
    is unwrapped in a child forked by the worker (the limits themselves: test_batch.py)."""
    asset_folder(tmp_path / "in", big=1, small=2)
    out = tmp_path / "out"
    assert run(tmp_path / "in", "-o", out, "--bound", "4", "--seams", "none", "--scheduler", "local",
               "--jobs", "2", "--file-timeout", "60") == 1
    rep, items = by_input(out / "report.json")
    assert rep["summary"]["scheduler"] == "local" and rep["summary"]["jobs"] == 2
    assert [items[n]["status"] for n in sorted(items)] == [
        "failed", "certified", "certified", "failed", "certified"]
    V, F, uv = read_obj(items["three_peaks-00.off"]["output"])
    D, flipped = reference_distortion(V, F, uv)
    assert not flipped.any() and items["three_peaks-00.off"]["max_distortion"] == \
        pytest.approx(D.max(), rel=1e-9)
