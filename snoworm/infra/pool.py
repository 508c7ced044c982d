"""Local worker processes, shared by every study (sweeps, mobility maps).

:class:`ProcessExecutor` runs a top-level (picklable) function over tasks in ``jobs`` processes,
with at most ``2 * jobs`` tasks in flight.  Workers run one BLAS/OpenMP thread each, start by
``fork`` where that is safe and fast (:func:`start_method`), and end themselves when the parent
process dies instead of lingering.

This module imports nothing else of snoworm, so any layer may use it.
"""

from __future__ import annotations

import functools
import itertools
import multiprocessing
import os
import sys
import threading
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

from threadpoolctl import threadpool_limits

__all__ = ["ProcessExecutor", "interrupt_within", "start_method", "THREAD_ENV"]

#: Thread-pool variables set to 1 in worker processes (unless the user set them), as Dask does:
#: one multi-threaded OpenBLAS per worker oversubscribes the cores and halved the speed here.
THREAD_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def _exit_with_parent(ppid: int, poll_s: float = 1.0):
    """Worker initializer: one BLAS/OpenMP thread per worker, and exit when the parent process is
    gone (killed), instead of lingering.

    A forked worker inherits the parent's already started BLAS thread pool, which the
    ``*_NUM_THREADS`` variables no longer reach; ``threadpoolctl`` limits it at run time
    (measured: 2 forked processes at 1.6x serial with the pool as inherited, 1.8-2.0x with one
    thread each).
    """
    threadpool_limits(limits=1)

    def watch():
        while True:
            time.sleep(poll_s)
            if os.getppid() != ppid:
                os._exit(1)

    threading.Thread(target=watch, name="snoworm-parent-watch", daemon=True).start()


def interrupt_within(exc: BaseException | None) -> KeyboardInterrupt | None:
    """The KeyboardInterrupt (or a subclass, e.g. SIGTERM's ``Terminated``) in ``exc``'s chain of
    causes, or None: a signal handler raising while NumPy or SciPy runs C code comes back as another
    exception (``SystemError: ... returned a result with an exception set``) caused by the interrupt."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


def start_method() -> str:
    """How worker processes start: ``fork`` on Linux with Python < 3.12, else ``spawn``.

    A forked worker inherits the imported modules, so it starts in milliseconds instead of the
    ~1 s a spawned one spends importing NumPy/SciPy (measured: 2 processes gave 1.9x the serial
    throughput with fork, 1.6x with spawn, on a 200-case sweep).  Python 3.12 deprecates fork in
    a process with threads (NumPy's BLAS pool counts), and other platforms fork unsafely, so
    those spawn.
    """
    if (
        sys.platform.startswith("linux")
        and sys.version_info < (3, 12)
        and "fork" in multiprocessing.get_all_start_methods()
    ):
        return "fork"
    return "spawn"


def _indexed(fn, item):
    j, task = item
    return j, fn(task)


class ProcessExecutor:
    """Run tasks in ``jobs`` local processes (forked or spawned, see :func:`start_method`).

    At most ``2 * jobs`` tasks are in flight, so memory stays flat for any number of tasks.
    Workers run with one BLAS/OpenMP thread each (``OMP_NUM_THREADS`` etc. default to 1 while
    the pool lives, unless already set; forked workers also limit the inherited pool).  A script
    using it where workers are spawned needs the usual ``if __name__ == "__main__":`` guard.
    Usable as a context manager (``close`` on exit).
    """

    def __init__(self, jobs: int):
        self.jobs = int(jobs)
        self._env = {k: os.environ.get(k) for k in THREAD_ENV}
        for k, v in self._env.items():
            if v is None:
                os.environ[k] = "1"
        self.pool = ProcessPoolExecutor(
            self.jobs,
            mp_context=multiprocessing.get_context(start_method()),
            initializer=_exit_with_parent,
            initargs=(os.getpid(),),
        )

    def map_unordered(self, fn, tasks):
        """Yield ``fn(task)`` for every task, in completion order (a task's exception is raised here)."""
        it = iter(tasks)
        pending = set()
        for task in itertools.islice(it, 2 * self.jobs):
            pending.add(self.pool.submit(fn, task))
        while pending:
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in done:
                nxt = next(it, None)
                if nxt is not None:
                    pending.add(self.pool.submit(fn, nxt))
                yield fut.result()

    def map(self, fn, tasks) -> list:
        """``[fn(task) for task in tasks]``, computed in the workers, in the order of ``tasks``."""
        tasks = list(tasks)
        out = [None] * len(tasks)
        for j, res in self.map_unordered(functools.partial(_indexed, fn), enumerate(tasks)):
            out[j] = res
        return out

    def close(self):
        try:
            self.pool.shutdown(wait=True, cancel_futures=True)
        finally:
            for k, v in self._env.items():
                if v is None:
                    os.environ.pop(k, None)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
