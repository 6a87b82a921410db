"""Executors of a sweep: in this process, a process pool of our own, or one given by the caller.

Our own pool forks its workers where that is safe (:func:`can_fork`: Linux, and no other thread in
this process), so they start with this process's imports instead of importing NumPy, SciPy and
numba again (about 0.7 s of CPU each), and with the simulator's kernels already loaded: this process
loads them once before the fork (:func:`warm`, 0.2-0.4 s) instead of every worker loading its own
copy; elsewhere it spawns them. The results are the same either way.

The pool's worker processes die with the sweep: each worker asks the kernel for
``SIGKILL`` when its parent ends (Linux ``prctl(PR_SET_PDEATHSIG)``), and elsewhere
watches its parent's pid from a thread. So a sweep killed with ``kill -9`` or
``SIGTERM`` leaves no orphans, and an interrupted sweep (``SIGINT``) cancels the
pending batches and terminates the workers instead of waiting for them.
"""

from __future__ import annotations

import concurrent.futures
import math
import os
import signal
import sys
import threading
import time

__all__ = ["DASK_CPU_SETTINGS", "Executor", "die_with_parent", "NoWorkersError", "STALL_S", "can_fork",
           "is_dask_client", "warm"]

#: Dask settings for a cluster that runs CPU-bound sweeps on a small machine (docs/sweeps.md): the
#: workers' statistical profiler off (it samples the running task every 10 ms) and the periodic
#: checks of every process's event loop less often (the loop's tick every 1 s instead of 20 ms, the
#: memory monitor every 1 s instead of 100 ms, the system monitor every 5 s instead of 0.5 s). An
#: idle local cluster of two workers then costs 0.02 cores instead of 0.17 here. Use them with
#: ``dask.config.set(DASK_CPU_SETTINGS)`` before the cluster starts (a ``LocalCluster`` hands them
#: to its workers), or the same keys in the Dask configuration of every process of the cluster.
DASK_CPU_SETTINGS = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.admin.system-monitor.interval": "5s",
}

_END = object()

#: Seconds a Dask sweep waits with no worker in the cluster before it gives up.
STALL_S = 60.0


class NoWorkersError(RuntimeError):
    """The Dask cluster has had no worker for :data:`STALL_S` seconds while runs were pending."""


def _watch_parent(parent: int) -> None:
    while os.getppid() == parent:
        time.sleep(0.5)
    os._exit(1)


def die_with_parent(parent: int) -> None:
    """Pool initializer: end this worker process when the process ``parent`` ends.

    Parameters
    ----------
    parent : int
        The pid of the sweep's process.
    """
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG = 1
        except (OSError, AttributeError):
            threading.Thread(target=_watch_parent, args=(parent,), daemon=True).start()
    else:
        threading.Thread(target=_watch_parent, args=(parent,), daemon=True).start()
    if os.getppid() != parent:  # the parent ended before the request took effect
        os._exit(1)


def can_fork() -> bool:
    """Whether a worker may be forked from this process: on Linux, while no other thread runs.

    A fork copies only the calling thread; a lock another thread holds at that moment stays held
    in the copy forever (a deadlock waiting to happen). macOS has ``fork`` but its system
    libraries are not fork-safe, which is why Python spawns there by default.

    Examples
    --------
    >>> isinstance(can_fork(), bool)
    True
    """
    return sys.platform.startswith("linux") and threading.active_count() == 1


def is_dask_client(executor) -> bool:
    """Whether ``executor`` is a ``dask.distributed.Client`` (told by its methods; Dask is not imported).

    Parameters
    ----------
    executor : object or None
        What a caller passed as ``executor=``.

    Examples
    --------
    >>> import concurrent.futures
    >>> is_dask_client(concurrent.futures.ThreadPoolExecutor(1)), is_dask_client(None)
    (False, False)
    """
    return executor is not None and hasattr(executor, "scheduler_info") and hasattr(executor, "gather")


def warm() -> None:
    """Load the simulator's compiled kernels in this process (a 10-sample run; from numba's cache).

    Examples
    --------
    >>> warm()  # raises if the run does not
    """
    from ..params import load_preset
    from ..sim.simulate import simulate

    cfg = load_preset("vcm")
    simulate(cfg, "tracking", duration=10 * cfg.observer.dt)


class Executor:
    """One adapter over the ways to run batches: in this process, a process pool of our own,
    a ``concurrent.futures.Executor`` or a ``dask.distributed.Client`` given by the caller.

    Parameters
    ----------
    executor : object or None
        The caller's executor, or None for our own pool.
    workers : int or None
        Processes of our own pool (default: all cores; 1 runs in this process).
    """

    def __init__(self, executor, workers: int | None) -> None:
        self.owned = executor is None
        if executor is None:
            n = workers if workers is not None else (os.cpu_count() or 1)
            if n > 1:
                import multiprocessing

                fork = can_fork()
                if fork:  # the workers inherit the loaded kernels
                    warm()
                executor = concurrent.futures.ProcessPoolExecutor(
                    max_workers=n, mp_context=multiprocessing.get_context("fork" if fork else "spawn"),
                    initializer=die_with_parent, initargs=(os.getpid(),))
                if fork:  # fork the workers now, before a progress bar starts its thread
                    for _ in range(n):
                        executor.submit(os.getpid)
            self.workers = n
        else:
            self.workers = self._count_workers(executor)
        self.pool = executor
        self.dask = is_dask_client(executor)
        self.futures: list = []

    @staticmethod
    def _count_workers(executor) -> int:
        if hasattr(executor, "nthreads"):  # dask.distributed.Client
            return max(1, sum(executor.nthreads().values()))
        return max(1, getattr(executor, "_max_workers", 1))

    def map_batches(self, fn, batches, *, window: int | None = None):
        """Results of ``fn(batch)`` as they complete (in this process: in order).

        With ``window``, at most that many batches are submitted and not yet collected at any
        time (``batches`` may then be a lazy iterable): the memory of a long study does not grow
        with its number of batches.
        """
        if self.pool is None:
            for batch in batches:
                yield fn(batch)
            return
        if window is not None or self.dask:  # Dask: always watched for a cluster left without workers
            yield from self._windowed(fn, iter(batches), window if window is not None else math.inf)
            return
        self.futures = [self.pool.submit(fn, batch) for batch in batches]
        for fut in concurrent.futures.as_completed(self.futures):
            yield fut.result()

    def _windowed(self, fn, batches, window: float):
        """Results as they complete, with at most ``window`` batches in flight (``inf``: all of them), and
        ``NoWorkersError`` when a Dask cluster stays without workers."""
        if self.dask:
            from distributed import wait
        else:
            from concurrent.futures import wait
        pending: set = set()
        idle_since = None
        while True:
            while len(pending) < window:
                batch = next(batches, _END)
                if batch is _END:
                    break
                pending.add(self.pool.submit(fn, batch))
            self.futures = list(pending)
            if not pending:
                return
            try:
                done, pending = wait(pending, timeout=2.0, return_when="FIRST_COMPLETED")
            except TimeoutError:  # distributed's TimeoutError is the builtin one
                done = set()
            pending = set(pending)
            for fut in done:
                yield fut.result()
            if not self.dask or done or self.pool.nthreads():
                idle_since = None
            elif idle_since is None:
                idle_since = time.monotonic()
            elif time.monotonic() - idle_since > STALL_S:
                raise NoWorkersError(f"the Dask cluster has had no worker for {STALL_S:g} s with "
                                     f"{len(pending)} batches pending")

    def abort(self) -> None:
        """Cancel what is pending and stop our own workers at once (their batches are lost)."""
        if self.pool is None:
            return
        if self.owned:
            processes = list((getattr(self.pool, "_processes", None) or {}).values())
            manager = getattr(self.pool, "_executor_manager_thread", None)
            self.pool.shutdown(wait=False, cancel_futures=True)
            for proc in processes:
                proc.terminate()
            for proc in processes:
                proc.join(2.0)
            if manager is not None:  # let it close its wake-up pipe before the interpreter's exit hook writes to it
                manager.join(2.0)    # (CPython 3.11: "Exception ignored ... OSError: Bad file descriptor" on stderr)
        elif self.dask:
            self.pool.cancel(self.futures)
        else:
            for fut in self.futures:
                fut.cancel()

    def close(self) -> None:
        """Shut our own pool down (waits for idle workers to exit)."""
        if self.owned and self.pool is not None:
            self.pool.shutdown()
