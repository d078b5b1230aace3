"""operators/worker.py: the background job, queue and cancel logic, without Blender.

The worker is loaded straight from its file (the ``operators`` package itself needs ``bpy``), with
a fake solve function whose steps the test drives through events, so no test depends on timing.
"""
import importlib.util
import pathlib
import subprocess
import sys
import queue

import numpy as np
import pytest

WORKER_PATH = pathlib.Path(__file__).resolve().parents[2] / "operators" / "worker.py"


def _load_worker():
    spec = importlib.util.spec_from_file_location("bd_uv_worker_under_test", WORKER_PATH)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


worker = _load_worker()


class FakeCancelled(Exception):
    pass


def stepping_solve(V, F, *, steps, gate, seen, progress, cancel, **kwargs):
    """Reports progress ``steps`` times, taking a token from the queue ``gate`` before each;
    honours ``cancel`` like the core does (checked at every step)."""
    seen["V"] = V.copy()
    seen["kwargs"] = kwargs
    for i in range(steps):
        gate.get()
        if cancel.is_set():
            raise FakeCancelled("cancelled by the user")
        progress((i + 1) / steps, f"step {i + 1}")
    return {"sum": float(V.sum()), "faces": len(F)}


def test_result_and_progress_arrive_through_the_queue():
    V = np.arange(12.0).reshape(4, 3)
    F = np.array([[0, 1, 2], [0, 2, 3]])
    gate, seen = queue.Queue(), {}
    job = worker.UnwrapJob(stepping_solve, V, F, steps=3, gate=gate, seen=seen, bound=5.0)
    job.start()
    assert job.poll() is None and job.fraction == 0.0
    for _ in range(3):
        gate.put(None)
    outcome = job.wait()
    assert isinstance(outcome, worker.Finished)
    assert outcome.result == {"sum": 66.0, "faces": 2}
    assert job.fraction == 1.0 and job.status == "step 3"
    assert seen["kwargs"] == {"bound": 5.0}
    assert job.poll() is outcome  # the end is sticky


def test_arrays_are_copied_before_the_thread_starts():
    V = np.ones((3, 3))
    gate, seen = queue.Queue(), {}
    job = worker.UnwrapJob(stepping_solve, V, np.array([[0, 1, 2]]), steps=1, gate=gate,
                           seen=seen)
    V[:] = -7.0  # Blender's mesh changed after the copy
    job.start()
    gate.put(None)
    outcome = job.wait()
    assert outcome.result["sum"] == 9.0 and (seen["V"] == 1.0).all()


def test_progress_messages_are_in_order():
    seen_fractions = []

    def solve(progress, cancel):
        for k in range(5):
            progress(k / 4, f"island {k}")
        return "ok"

    job = worker.UnwrapJob(solve).start()
    job._thread.join()
    while True:
        message = job.messages.get_nowait()
        if isinstance(message, worker.Progress):
            seen_fractions.append(message.fraction)
        else:
            assert isinstance(message, worker.Finished) and message.result == "ok"
            break
    assert seen_fractions == [0.0, 0.25, 0.5, 0.75, 1.0]


def test_cancel_stops_at_the_next_checkpoint_and_returns_nothing_partial():
    gate, seen = queue.Queue(), {}
    job = worker.UnwrapJob(stepping_solve, np.zeros((3, 3)), np.array([[0, 1, 2]]), steps=100,
                           gate=gate, seen=seen)
    job.start()
    gate.put(None)
    first = job.messages.get()  # blocks until the first step has reported
    assert isinstance(first, worker.Progress) and first.fraction == 0.01
    job.cancel()
    assert job.cancelled
    gate.put(None)
    outcome = job.wait()
    assert isinstance(outcome, worker.Failed)
    assert isinstance(outcome.error, FakeCancelled)
    assert job.fraction < 1.0


def test_errors_are_handed_to_the_main_thread():
    class IslandTrouble(ValueError):
        pass

    def solve(progress, cancel):
        raise IslandTrouble("island 2 is closed: mark seams")

    outcome = worker.UnwrapJob(solve).start().wait()
    assert isinstance(outcome, worker.Failed)
    assert isinstance(outcome.error, IslandTrouble) and "island 2" in str(outcome.error)


def test_worker_imports_neither_bpy_nor_the_core():
    code = (
        "import importlib.util, sys\n"
        f"spec = importlib.util.spec_from_file_location('w', {str(WORKER_PATH)!r})\n"
        "m = importlib.util.module_from_spec(spec); sys.modules['w'] = m\n"
        "spec.loader.exec_module(m)\n"
        "bad = [n for n in ('bpy', 'bmesh', 'mathutils', 'bd_uv') if n in sys.modules]\n"
        "assert not bad, bad\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


@pytest.mark.parametrize("when", ["before_start", "at_first_report"])
def test_real_core_unwrap_is_cancelled(when):
    """With the real ``bd_uv.unwrap``: a set cancel event ends the job with CancelledError."""
    bd_uv = pytest.importorskip("bd_uv")
    if not hasattr(bd_uv, "unwrap"):
        pytest.skip("bd_uv.unwrap has not landed")
    # A bumpy grid disk.
    n = 12
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    V = np.stack([x.ravel(), y.ravel(), 0.2 * np.sin(5 * x.ravel()) * y.ravel()], 1)
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    F = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]).astype(np.int64)
    calls = []

    def solve(V, F, progress, cancel, **kw):
        def progress_then_cancel(fraction, message):
            calls.append(fraction)
            cancel.set()  # as if Esc was pressed while the first step ran
            progress(fraction, message)
        return bd_uv.unwrap(V, F, progress=progress_then_cancel, cancel=cancel, **kw)

    if when == "before_start":
        job = worker.UnwrapJob(bd_uv.unwrap, V, F)
        job.cancel()  # cancelled before it even starts
    else:
        job = worker.UnwrapJob(solve, V, F)
    outcome = job.start().wait()
    assert isinstance(outcome, worker.Failed), outcome
    assert isinstance(outcome.error, bd_uv.CancelledError)
    if when == "at_first_report":
        assert calls and max(calls) < 1.0  # stopped before the end, at a later checkpoint
