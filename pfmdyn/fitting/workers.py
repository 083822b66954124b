"""Worker processes: a pool for the maps' blocks and the discrepancy workflow's independent fits.

A pool's workers are forked from this process when it runs no other thread (they start in
milliseconds and see its state as it is), each with one BLAS thread (the processes are the
parallelism); they exit with the process that started them, and Ctrl-C is that process's.
:class:`Forked` keeps such workers for a series of independent calls, each returning what it would
here, in order; :func:`cpu_seconds` counts the CPU time of this process and of the workers it has
seen end.
"""
from __future__ import annotations

import os
import pickle
import signal
import sys
import threading
import time

__all__ = ["Forked", "compiling_seconds", "cores", "count_compiling", "cpu_seconds", "exit_with_parent", "pool"]


def cores() -> int:
    """The cores this process may run on (its affinity where the platform says, else all).

    >>> cores() >= 1
    True
    """
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:       # macOS, Windows
        return os.cpu_count() or 1


_STATE = None
"""The ``state`` of the :class:`Forked` whose workers are being forked: they inherit it, nothing is pickled."""
_RECEIVE = None
"""Its ``receive``: how a worker takes what a :meth:`Forked.map` shares."""
_TAKEN = None
"""The token of what this worker last took of what a map shares (taken once per worker, not per call)."""
_IN_WORKER = False
"""True in a worker: a call it runs that asks for workers itself runs its calls in turn."""
_FORK_SAFE = sys.platform.startswith("linux")
"""Whether a process that has used BLAS may fork workers that use it too: on macOS, Accelerate's
threads do not survive a fork (a child's first BLAS call can hang), and Windows has no fork."""


def _started(parent: int):
    """Worker initialiser: exit with the process that started the pool, and one BLAS thread per
    process (the processes are the parallelism): set here only where the parent ran more, since setting a
    limit starts OpenBLAS's thread pool, whose new threads spin a tenth of a second waiting for work, on the
    cores the workers share (a worker's first fit took three times as long)."""
    global _IN_WORKER
    _IN_WORKER = True
    signal.signal(signal.SIGINT, signal.SIG_IGN)     # Ctrl-C is the parent's (:func:`pool`)
    exit_with_parent(parent)
    from threadpoolctl import threadpool_info, threadpool_limits
    if any(pool["num_threads"] > 1 for pool in threadpool_info()):
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


class Forked:
    """``workers`` worker processes forked from this one when first asked (they inherit ``state``, e.g. a
    problem with its data and caches, as it is then), kept for a series of :meth:`map` calls until
    :meth:`close`; ``receive(state, shared)``: how a worker takes what a map shares with every worker (e.g.
    what this process's caches gained); ``prepare(state)``: run here once, just before the workers fork, for
    what each of them would otherwise do on its own (e.g. load compiled kernels: they inherit them).

    Nothing but a call's arguments and result is pickled, and each call computes what it would here.
    Without workers (one asked, or ``fork`` not to be had: another thread running, not on Linux
    (:data:`_FORK_SAFE`), off the main thread, in a worker) the calls run here in turn.  :attr:`seconds`: the
    CPU seconds the workers spent on calls, less their compiling (:func:`cpu_seconds` counts the workers once
    they end).

    >>> with Forked(2, 10) as forked:
    ...     forked.map(pow, [(3,), (2,), (0,)])       # 10 ** 3, 10 ** 2, 10 ** 0
    [1000, 100, 1]
    """

    def __init__(self, workers: int, state, receive=None, prepare=None):
        self.workers, self.state, self.receive, self.prepare, self.seconds = workers, state, receive, prepare, 0.0
        self._executor, self._asked, self._shares, self.took = None, False, 0, []

    def map(self, function, calls, shared=None, costs=None) -> list:
        """``[function(state, *args) for args in calls]`` (``function`` a module's, to be named in a
        worker), in the workers when there are any; a call's exception is raised here.  ``shared``: what each
        worker takes (``receive``) before its first call of this map: pickled once, however many calls,
        and not needed here (the state is this process's).  ``costs``: each call's expected cost (any unit), the
        dearest sent first, so that no worker is left waiting at the end for one long call; :attr:`took`: the CPU
        seconds each call took in a worker (empty when they ran here)."""
        global _STATE, _RECEIVE
        if shared is not None and self.receive is None:
            raise ValueError("a map shares only with a Forked given receive")
        calls = list(calls)
        if not self._asked and len(calls) > 1:
            self._asked = True
            if self.workers > 1 and _FORK_SAFE and not _IN_WORKER and threading.current_thread() is threading.main_thread():
                import gc
                if self.prepare is not None:
                    self.prepare(self.state)
                _STATE, _RECEIVE = self.state, self.receive
                gc.freeze()     # a worker's collections leave the inherited objects (and their pages) alone
                try:
                    self._executor = pool(self.workers, fork_only=True)
                finally:
                    _STATE, _RECEIVE = None, None
                    gc.unfreeze()
        if self._executor is None or len(calls) < 2:
            self.took = []
            return [function(self.state, *args) for args in calls]
        token, blob = None, None
        if shared is not None:
            self._shares += 1
            token, blob = self._shares, pickle.dumps(shared, pickle.HIGHEST_PROTOCOL)
        n = len(calls)
        first = sorted(range(n), key=lambda i: -costs[i]) if costs is not None else range(n)
        done = [None] * n
        for i, out in zip(first, self._executor.map(_call, [function] * n, [calls[i] for i in first], [token] * n,
                                                    [blob] * n)):
            done[i] = out
        self.took = [seconds for _, seconds in done]
        self.seconds += sum(self.took)
        return [out for out, _ in done]

    def close(self) -> None:
        """End the workers (a worker's calls finish first)."""
        if self._executor is not None:
            self._executor.shutdown(cancel_futures=True)
            self._executor = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _call(function, args, token, blob):
    global _TAKEN
    started = time.process_time() - compiling_seconds()
    if token is not None and token != _TAKEN:
        _RECEIVE(_STATE, pickle.loads(blob))
        _TAKEN = token
    out = function(_STATE, *args)
    return out, time.process_time() - compiling_seconds() - started


_COMPILING = None
"""numba's timer of its compilations in this process (and in the workers forked from it), once counting."""


def count_compiling() -> None:
    """Count, from now on, the seconds numba spends compiling (:func:`compiling_seconds`); imports numba."""
    global _COMPILING
    if _COMPILING is None:
        from numba.core import event
        _COMPILING = event.TimingListener()
        event.register("numba:compile", _COMPILING)


def compiling_seconds() -> float:
    """Seconds numba has spent compiling in this process since :func:`count_compiling` (0 before).

    >>> count_compiling(); compiling_seconds() >= 0.0
    True
    """
    return _COMPILING.duration if _COMPILING is not None and _COMPILING.done else 0.0


def cpu_seconds() -> float:
    """CPU seconds of this process and of the workers it has seen end, less numba's compiling here
    (:func:`compiling_seconds`): a budget of CPU seconds then gives a fresh install's first run, which
    compiles the kernels, the report of the next.

    >>> cpu_seconds() > 0
    True
    """
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system - compiling_seconds()
