"""Worker processes: a pool for the maps' blocks and the discrepancy workflow's independent fits.

A pool's workers are forked from this process when it runs no other thread (they start in
milliseconds and see its state as it is), each with one BLAS thread (the processes are the
parallelism); they exit with the process that started them, and Ctrl-C is that process's.
:func:`forked_calls` runs independent calls of one function in such workers and returns what
each call returned, in order: nothing but the results is pickled; :func:`cpu_seconds` counts the
CPU time of this process and of the workers it has seen end.
"""
from __future__ import annotations

import os
import signal
import sys
import threading
import time

__all__ = ["cores", "cpu_seconds", "exit_with_parent", "forked_calls", "pool"]


def cores() -> int:
    """The cores this process may run on (its affinity where the platform says, else all).

    >>> cores() >= 1
    True
    """
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:       # macOS, Windows
        return os.cpu_count() or 1


_CALLS = None
"""(function, calls) of the running :func:`forked_calls`: its workers inherit it, nothing is pickled."""
_IN_WORKER = False
"""True in a worker: a call it runs that asks for workers itself runs its calls in turn."""


def _started(parent: int):
    """Worker initialiser: exit with the process that started the pool, and one BLAS thread per
    process (the processes are the parallelism)."""
    global _IN_WORKER
    _IN_WORKER = True
    signal.signal(signal.SIGINT, signal.SIG_IGN)     # Ctrl-C is the parent's (:func:`pool`)
    exit_with_parent(parent)
    from threadpoolctl import threadpool_limits
    threadpool_limits(1)


def exit_with_parent(parent: int, poll_s: float = 0.5) -> None:
    """Make this process exit when ``parent`` (its parent's pid) dies, whatever the signal.

    A parent killed by SIGKILL (an out-of-memory killer, a batch scheduler) runs no clean-up,
    and its pool's workers would live on, reparented, holding their memory.  On Linux the
    kernel sends the worker SIGKILL when its parent dies (``prctl(PR_SET_PDEATHSIG)``); a
    daemon thread polling the parent's pid does the same elsewhere and covers a parent that
    died before the ``prctl`` call.

    In a child (here a separate interpreter, which goes on while its parent lives):

    >>> import subprocess, sys
    >>> code = "import os; from pfmdyn.fitting.workers import exit_with_parent as e; e(os.getppid()); print('on')"
    >>> subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout.strip()
    'on'
    """
    if sys.platform.startswith("linux"):
        import ctypes
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)   # 1: PR_SET_PDEATHSIG

    def watch():
        while os.getppid() == parent:
            time.sleep(poll_s)
        os._exit(1)   # no clean-up to run: a half-written block is redone on the next run

    threading.Thread(target=watch, name="pfmdyn-parent-watch", daemon=True).start()


def pool(workers: int, fork_only: bool = False):
    """A pool of worker processes, started now (before any progress-bar thread exists).

    ``fork`` while this process runs no other thread (workers start in milliseconds and share
    the imported modules; with other threads running a fork could copy a held lock), else
    ``spawn`` as Dask does (then a calling script needs the usual ``if __name__ == "__main__":``),
    or None with ``fork_only``.
    """
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor
    # tqdm's monitor thread (left by an earlier bar) only sleeps; workers never touch its lock
    others = [t for t in threading.enumerate() if t is not threading.main_thread() and t.name != "tqdm_monitor"]
    method = "fork" if not others and "fork" in multiprocessing.get_all_start_methods() else "spawn"
    if fork_only and method != "fork":
        return None
    # Ctrl-C is the parent's (one line; the workers exit with it), and no worker prints a traceback for it.
    # Forked workers inherit a handler that only takes note until their initialiser ignores SIGINT; the
    # parent raises the noted interrupt once its pool exists (ignoring SIGINT here lost it: the map ran on
    # to exit 0).  Spawned workers must start ignoring it (a disposition that survives exec, where a
    # handler does not) since they import pfmdyn before their initialiser runs.
    noted = []
    previous = signal.signal(signal.SIGINT, (lambda *_: noted.append(1)) if method == "fork" else signal.SIG_IGN)
    try:
        executor = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context(method), initializer=_started,
                                   initargs=(os.getpid(),))
        started = [executor.submit(int) for _ in range(workers)]      # spawn starts one worker per waiting task
    finally:
        signal.signal(signal.SIGINT, previous)
    if noted:
        raise KeyboardInterrupt
    for worker in started:
        worker.result()
    return executor


def forked_calls(function, calls, workers: int) -> list:
    """``[function(*args) for args in calls]``, in up to ``workers`` processes forked from this one.

    The workers inherit this process as it is, ``function`` and its arguments included: only
    the results are pickled, and each call computes what it would here.  The calls run in turn
    here with one worker or one call, in a worker, off the main thread, or where ``fork`` is not to
    be had (another thread running, or no ``fork`` on the platform).  A call's exception is raised
    here.  The workers have ended when it returns: their CPU time is in :func:`cpu_seconds`.

    >>> forked_calls(pow, [(2, 3), (3, 2), (10, 0)], 2)
    [8, 9, 1]
    """
    global _CALLS
    calls = list(calls)
    workers = min(workers, len(calls))
    if workers < 2 or _IN_WORKER or threading.current_thread() is not threading.main_thread():
        return [function(*args) for args in calls]
    _CALLS = (function, calls)
    try:
        executor = pool(workers, fork_only=True)
        if executor is None:
            return [function(*args) for args in calls]
        try:
            done = list(executor.map(_call, range(len(calls))))
        except BaseException:
            executor.shutdown(wait=False, cancel_futures=True)
            raise
    finally:
        _CALLS = None
    executor.shutdown()
    return done


def _call(i: int):
    function, calls = _CALLS
    return function(*calls[i])


def cpu_seconds() -> float:
    """CPU seconds of this process and of the workers it has seen end (those of :func:`forked_calls`).

    >>> cpu_seconds() > 0
    True
    """
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system
