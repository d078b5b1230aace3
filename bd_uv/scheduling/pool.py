"""The local process pool: ``python -m bd_uv batch --jobs N`` without ``--scheduler``."""
import concurrent.futures as cf

from .worker import limit_entry, run_file


def run_pool(tasks, order, work, options, seams_mode, jobs, done, limits=None, retries=1):
    """Run ``work`` on ``tasks[i]`` for ``i`` in ``order``, in ``jobs`` processes (in this one
    when 1); ``work`` as for ``worker.run_file``.

    A worker that dies (crash, out of memory) breaks the pool; the files it took down are run
    again, one fresh process each, up to ``retries`` times, so only a file that kills its worker
    every time fails (``WorkerCrashed``, with the number of attempts).

    Parameters
    ----------
    done : callable(i, entries, attempts), called in this process as each file finishes
    """
    if not order:
        return
    if jobs <= 1:
        for i in order:
            done(i, run_file(tasks[i], work, options, seams_mode, limits), 1)
        return
    lost = _run_once(tasks, order, work, options, seams_mode, jobs, done, limits, 1)
    for i in lost:  # isolate: one process per file, so a crash takes down only its own file
        for attempt in range(2, retries + 2):
            if not _run_once(tasks, [i], work, options, seams_mode, 1, done, limits, attempt):
                break
        else:
            done(i, [crashed_entry(tasks[i], retries + 1)], retries + 1)


def _run_once(tasks, order, work, options, seams_mode, jobs, done, limits, attempt):
    """Submit ``order`` to a pool of ``jobs`` processes; returns the indices lost to a crash."""
    lost = []
    with cf.ProcessPoolExecutor(max_workers=min(jobs, len(order))) as pool:
        futures = {pool.submit(run_file, tasks[i], work, options, seams_mode, limits): i
                   for i in order}
        try:
            for fut in cf.as_completed(futures):
                i = futures[fut]
                try:
                    done(i, fut.result(), attempt)
                except cf.process.BrokenProcessPool:
                    lost.append(i)
        except BaseException:
            pool.shutdown(wait=False, cancel_futures=True)
            raise
    return sorted(lost)


def crashed_entry(task, attempts, detail=""):
    """The entry of a file whose worker died on each of its ``attempts``."""
    return limit_entry(task, "WorkerCrashed",
                       f"{task.path}: the worker process died while unwrapping it, "
                       f"{attempts} time(s) (a crash, or killed for running out of memory)"
                       + (f": {detail}" if detail else ""))
