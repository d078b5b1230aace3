"""A spyrrow solve ended as soon as its layout is narrow enough (the square can shrink no more).

spyrrow 0.9 searches for the time it is given; its only other way out is a Python signal: its
terminator calls ``PyErr_CheckSignals``, which acts on the main thread only, and on an error ends
the search and returns the best layout found (the error is dropped). So a watcher thread drains
the solve's progress queue and, at the first feasible layout no wider than ``narrow``, trips the
main thread's SIGINT flag (``_thread.interrupt_main``: no OS signal). That is done only when the
solve runs on the main thread and Python's own SIGINT handler is installed (a Python process,
``import bpy`` keeps it) or SIGINT is ignored (a process started in the background by a shell
script, ``cmd &``, inherits SIGINT ignored and Python then installs no handler: the pack went
without its longer search there, igl-arm 0.724 -> 0.679 coverage, issue18-pack28-2026-11-29.md;
a SIGINT from outside stays ignored during the solve); elsewhere the solve runs its time, as
before.

A trip the search did not see (it ended by its own clock in between) raises the
``KeyboardInterrupt`` just after ``solve`` returns, before its value is stored: it is caught here
and the last feasible report (spyrrow queues its final layout too) is the result. A user's
Ctrl-C during such a solve (one not tripped by the watcher, told apart by a SIGINT handler of
its own for the solve's time) ends the search and is raised after it, not dropped as spyrrow
drops it.
"""
import _thread
import signal
import threading

POLL = 0.005  # seconds between two drains of the progress queue


def can_stop():
    """True where a solve on this thread can be ended early (see the module's docstring)."""
    return (threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGINT) in (signal.default_int_handler, signal.SIG_IGN))


def solve_until(inst, cfg, queue, feasible, narrow, on_report=None):
    """``inst.solve(cfg, queue)``, ended at the first feasible report (kind in ``feasible``) of
    width at most ``narrow`` when :func:`can_stop`; ``on_report``, optional: called on the
    watcher's thread with each feasible report's solution as it is drained (its errors are
    raised here once the solve is over).

    Returns
    -------
    solution, [(kind, solution)] every report drained, in order, and whether it was ended early
    """
    drained, done, lock = [], threading.Event(), threading.Lock()
    tripped = [False]
    watch = can_stop()
    failed = []

    def watcher():
        while not done.is_set():
            for kind, sol in queue.drain():   # per report
                drained.append((kind, sol))
                if on_report is not None and not failed and int(kind) in feasible:
                    try:
                        on_report(sol)
                    except Exception as exc:   # raised on the solve's thread, after it
                        failed.append(exc)
                if watch and not tripped[0] and int(kind) in feasible and sol.width <= narrow:
                    with lock:
                        if not done.is_set():
                            tripped[0] = True
                            _thread.interrupt_main()
            done.wait(POLL)

    thread = threading.Thread(target=watcher, daemon=True)
    sol = None
    user = [False]      # a Ctrl-C of the user's, which spyrrow would end its search on and drop
    before = signal.getsignal(signal.SIGINT) if watch else None

    def on_sigint(signum, frame):
        if not tripped[0]:
            if before is signal.SIG_IGN:
                return   # (SIGINT ignored by the process: a signal from outside stays so)
            user[0] = True
        raise KeyboardInterrupt
    if watch:
        signal.signal(signal.SIGINT, on_sigint)
    try:
        try:
            thread.start()
            sol = inst.solve(cfg, queue)
        finally:
            with lock:
                done.set()
            _settled()   # a trip the search did not see is raised here at the latest
    except KeyboardInterrupt:
        if not tripped[0] or user[0]:
            raise
    finally:
        done.set()
        if watch:
            signal.signal(signal.SIGINT, before)
        if thread.ident is not None:
            thread.join()
        drained.extend(queue.drain())
    if user[0]:
        raise KeyboardInterrupt   # the user's, not the watcher's: passed on, not dropped
    if failed:
        raise failed[0]
    if sol is None:
        sol = [s for kind, s in drained if int(kind) in feasible][-1]
    return sol, drained, tripped[0]


def _settled():
    """A call: the interpreter handles a pending signal at it."""
    return None
