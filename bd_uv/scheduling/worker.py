"""What a worker runs for one file: the work it is handed (``bd_uv.batch``'s unwrap and write),
its resume hashes, and the per-file limits.

Without limits the file is unwrapped in the worker's own process, as before. With a time or memory
limit it is unwrapped in a forked child that the worker watches: past ``timeout`` seconds, or
above ``memory`` bytes of resident memory, the child is killed and the file fails with that
reason (``FileTimeout``, ``MemoryLimit``); the worker, the pool or the Dask cluster go on. The
child writes the outputs itself (atomically), so a killed child leaves no partial file. Limits
need ``os.fork`` (Linux, macOS).
"""
import os
import pickle
import select
import signal
import sys
import time
from dataclasses import dataclass

from .atomic import file_sha256
from .entries import failed_entry
from .ledger import options_sha256


@dataclass(frozen=True)
class FileLimits:
    """Per-file limits: ``timeout`` seconds of wall time, ``memory`` bytes of resident memory
    (either None for no limit)."""
    timeout: float = None
    memory: int = None

    def __bool__(self):
        return self.timeout is not None or self.memory is not None


def run_file(task, work, options, seams_mode, limits=None):
    """Run ``work(task, options, seams_mode)`` and return its report entries.

    Parameters
    ----------
    task : an object with ``path`` and ``output`` (``bd_uv.batch.FileTask``)
    work : callable(task, options, seams_mode) -> list of report entries, a module-level function
        (it is pickled by reference for a process pool or a Dask worker)

    Each entry gets ``input_sha256``, ``options_sha256`` and ``output_sha256`` (None when no
    output was written) for ``--resume``. Never raises for a bad file.
    """
    digest = file_sha256(task.path)
    if limits:
        entries = _in_child(work, (task, options, seams_mode), limits, task)
    else:
        entries = work(task, options, seams_mode)
    written = any(e.get("output") for e in entries)
    out_digest = file_sha256(task.output) if written else None
    opt = options_sha256(options, seams_mode)
    for e in entries:
        e.update(input_sha256=digest, options_sha256=opt, output_sha256=out_digest)
    return entries


def limit_entry(task, error, message, seconds=None):
    """The entry of a file its worker could not finish (a limit, a crash, a worker error)."""
    return failed_entry(os.path.splitext(os.path.basename(task.path))[0], error, message,
                        seconds=seconds, input=os.path.abspath(task.path), object=None,
                        output=None)


def _in_child(fn, args, limits, task, poll=0.1):
    """``fn(*args)`` in a forked child, within ``limits``; its return value, or a failed entry."""
    r, w = os.pipe()
    t0 = time.monotonic()
    pid = os.fork()
    if pid == 0:  # the child: compute, send the pickled result, leave without cleanup handlers
        status = 0
        try:
            os.close(r)
            _die_with_parent()
            payload = pickle.dumps(("ok", fn(*args)))
        except BaseException as exc:  # noqa: BLE001 - reported by the parent
            payload = pickle.dumps(("error", f"{type(exc).__name__}: {exc}"))
        try:
            with os.fdopen(w, "wb") as fh:
                fh.write(payload)
        except BaseException:  # noqa: BLE001
            status = 1
        os._exit(status)
    os.close(w)
    chunks, reason = [], None
    try:
        while True:
            ready, _, _ = select.select([r], [], [], poll)
            if ready:
                block = os.read(r, 1 << 16)
                if not block:
                    break
                chunks.append(block)
                continue
            elapsed = time.monotonic() - t0
            if limits.timeout is not None and elapsed > limits.timeout:
                reason = ("FileTimeout", f"{task.path}: still unwrapping after --file-timeout "
                          f"{limits.timeout:g} s; stopped")
            elif limits.memory is not None and (rss := _rss(pid)) > limits.memory:
                reason = ("MemoryLimit", f"{task.path}: used {rss / 2**20:.0f} MB, more than "
                          f"--memory-limit {limits.memory / 2**20:.0f} MB; stopped")
            if reason:
                os.kill(pid, signal.SIGKILL)
                break
    finally:
        os.close(r)
        _, wait_status = os.waitpid(pid, 0)
    seconds = round(time.monotonic() - t0, 4)
    if reason:
        return [limit_entry(task, *reason, seconds=seconds)]
    try:
        kind, value = pickle.loads(b"".join(chunks))
    except Exception:  # noqa: BLE001 - nothing (or half) sent: the child died
        sig = -os.waitstatus_to_exitcode(wait_status)
        how = f"killed by signal {sig}" if sig > 0 else f"exit {-sig}"
        return [limit_entry(task, "WorkerCrashed", f"{task.path}: the process unwrapping it "
                            f"died ({how}; a crash, or out of memory)", seconds=seconds)]
    if kind == "error":
        return [limit_entry(task, "WorkerError", f"{task.path}: {value}", seconds=seconds)]
    return value


def _rss(pid):
    """Resident memory of ``pid`` in bytes (0 when it cannot be read)."""
    try:
        import psutil
        return psutil.Process(pid).memory_info().rss
    except ImportError:
        pass
    except Exception:  # noqa: BLE001 - the process just ended
        return 0
    try:
        with open(f"/proc/{pid}/statm") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


def _die_with_parent():
    """Linux: the child is killed when its worker dies (no orphan writing outputs)."""
    if sys.platform.startswith("linux"):
        try:
            import ctypes
            ctypes.CDLL(None).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass
