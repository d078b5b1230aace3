"""The batch on Dask distributed: ``--scheduler tcp://HOST:8786`` or ``--scheduler local``.

One Dask task per file (``worker.run_file``), submitted largest first through task priorities;
only the task (paths and options) and its report entries travel, the meshes are read and the
outputs written by the worker, so inputs and outputs must be on paths every worker sees (a shared
filesystem), and every worker needs bd-uv installed (``pip install bd-uv`` or the wheel), with
the ``bpy`` module for .blend files.

A worker that dies while unwrapping a file (killed, or by its nanny for exceeding the worker
memory limit) makes the scheduler give the file to another worker; after ``retries`` such deaths
the scheduler gives up (Dask's ``KilledWorker``) and the file is reported as ``WorkerCrashed``.
``--scheduler local`` starts a ``LocalCluster`` of ``jobs`` one-thread worker processes with that
retry bound; a remote scheduler keeps its own (``distributed.scheduler.allowed-failures``,
3 by default). Dask is an optional extra: nothing else in bd-uv imports it.
"""
import contextlib
import importlib
import logging
import uuid

from ..errors import BDError
from .pool import crashed_entry
from .worker import limit_entry, run_file


def run_dask(tasks, order, work, options, seams_mode, scheduler, jobs, done, limits=None,
             retries=2, on_start=None):
    """Run ``work`` on ``tasks[i]`` for ``i`` in ``order`` (first = highest priority) on a Dask
    cluster.

    Parameters
    ----------
    work : callable(task, options, seams_mode) -> report entries, as for ``worker.run_file``: a
        module-level function, pickled by reference (every worker imports its module)
    scheduler : str, a scheduler address, or "local" for a LocalCluster of ``jobs`` workers
    done : callable(i, entries, attempts), called in this process as each file finishes
    on_start : callable(workers: int), called once the client is connected

    Returns
    -------
    workers : int, the number of workers when the batch started
    """
    try:
        import dask
        from distributed import Client, LocalCluster, as_completed
        from distributed.scheduler import KilledWorker
    except ImportError as exc:
        raise BDError("--scheduler needs Dask distributed: pip install 'bd-uv[cluster]' "
                      "(or -r requirements-cluster.txt)") from exc
    with contextlib.ExitStack() as stack:
        # Less bookkeeping in the scheduler, nannies and workers, which compete with the solves
        # for the cores: no statistical profiler (10 ms stack samples for the dashboard's
        # profile page), event-loop watchdog ticks every 1 s instead of 20 ms, system monitor
        # every 2 s. An idle 2-worker LocalCluster then uses 2 % of a core instead of 9 %.
        stack.enter_context(dask.config.set({
            "distributed.scheduler.allowed-failures": retries,
            "distributed.worker.profile.enabled": False,
            "distributed.admin.tick.interval": "1s",
            "distributed.admin.system-monitor.interval": "2s"}))
        try:
            if scheduler == "local":
                cluster = stack.enter_context(LocalCluster(
                    n_workers=jobs, threads_per_worker=1, processes=True,
                    dashboard_address=":0", silence_logs=logging.ERROR))   # any free port
                client = stack.enter_context(Client(cluster))
            else:
                client = stack.enter_context(Client(scheduler, timeout="30s"))
        except (OSError, TimeoutError) as exc:
            raise BDError(f"cannot reach the Dask scheduler {scheduler}: {exc}") from exc
        workers = _warm_up(client, scheduler, work.__module__)
        if on_start is not None:
            on_start(workers)
        run = uuid.uuid4().hex[:12]
        futures = {}
        for rank, i in enumerate(order):
            fut = client.submit(run_file, tasks[i], work, options, seams_mode, limits,
                                key=f"bd-uv-{run}-{i}", priority=len(order) - rank, pure=False)
            futures[fut] = i
        try:
            for fut in as_completed(list(futures)):
                i = futures.pop(fut)
                attempts = 1 + _deaths(client, fut.key)
                if fut.status == "finished":
                    entries = fut.result()
                else:
                    exc = fut.exception()
                    if isinstance(exc, KilledWorker):
                        entries = [crashed_entry(tasks[i], attempts, "Dask gave up on it")]
                    else:
                        entries = [limit_entry(tasks[i], type(exc).__name__,
                                               f"{tasks[i].path}: {exc}")]
                fut.release()
                done(i, entries, attempts)
        except BaseException:
            client.cancel(list(futures))
            raise
    return workers


def _warm_up(client, scheduler, module):
    """Import ``module`` (the work's: the solver stack) on every worker now (so that start-up is
    not counted in the throughput, and a worker without bd-uv is named at once); returns the
    number of workers."""
    from .. import __version__
    try:
        versions = client.run(_worker_version, module)
    except Exception as exc:  # noqa: BLE001 - typically: bd_uv is not installed there
        raise BDError(f"the workers of {scheduler} cannot run bd-uv ({type(exc).__name__}: "
                      f"{exc}); install it on each worker: pip install 'bd-uv[cluster]'") from exc
    other = {w: v for w, v in versions.items() if v != __version__}
    if other:
        raise BDError(f"workers run another bd-uv than {__version__}: {other}")
    return len(versions)


def _worker_version(module):
    importlib.import_module(module)  # the solver stack, imported once per worker
    import bd_uv
    return bd_uv.__version__


def _deaths(client, key):
    """How many workers died while running task ``key`` (the scheduler's ``suspicious`` count;
    0 when the scheduler does not let us ask)."""
    def suspicious(dask_scheduler, key):
        ts = dask_scheduler.tasks.get(key)
        return int(ts.suspicious) if ts is not None else 0
    try:
        return client.run_on_scheduler(suspicious, key=key)
    except Exception:  # noqa: BLE001 - a scheduler that refuses remote code
        return 0
