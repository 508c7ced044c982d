"""Sweep executors: where the cases run.

An executor is any object with ``map_unordered(fn, tasks)`` yielding ``fn(task)`` for every task
in any order, and ``close()``.  :class:`SerialExecutor` runs them in this process,
:class:`~snoworm.infra.pool.ProcessExecutor` (shared with the other studies) in local processes,
:class:`DaskExecutor` on a Dask cluster, and :class:`BatchExecutor` stacks cases of one batch key
(:func:`snoworm.simulation.driver.batch_key`) into one solve (:func:`snoworm.simulation.driver.simulate_batch`),
running every other case one by one through the sweep's per-case function.
"""

from __future__ import annotations

import functools
import itertools
import threading
import time

from ...config.schema import ScenarioError, quote
from ...infra.pool import ProcessExecutor
from ...simulation.driver import assemble, batch_key, simulate_batch
from .metrics import case_metrics, save_case_series

__all__ = ["SweepExecutionError", "SerialExecutor", "ProcessExecutor", "DaskExecutor", "BatchExecutor", "run_chunk"]


class SweepExecutionError(RuntimeError):
    """The executor failed (not a case): e.g. a worker process died or the Dask cluster was lost."""


class SerialExecutor:
    """Run the cases one after the other in this process."""

    def map_unordered(self, fn, tasks):
        for task in tasks:
            yield fn(task)

    def close(self):
        pass


#: Seconds to wait for a Dask scheduler before the sweep stops with exit 2 (a reachable
#: scheduler answers in milliseconds; Dask's own default would wait 30 s).
CONNECT_TIMEOUT_S = 5


#: Seconds the whole connection (TCP connect and Dask's handshake) may take: a service other than
#: Dask listening at the address accepts the connection and never answers.
HANDSHAKE_TIMEOUT_S = 2 * CONNECT_TIMEOUT_S


def _connect(client_class, address):
    """A ``distributed.Client`` of ``address``, bounded by :data:`HANDSHAKE_TIMEOUT_S` (ScenarioError otherwise).

    Only ``tcp://host:port`` (or ``host:port``) addresses: a ``tls://`` scheduler needs a security
    configuration, ``ucx://`` a UCX install; connect such a ``Client`` yourself and pass it.  The
    client is made in a daemon thread, so a handshake that never ends cannot hang the sweep."""
    text = str(address)
    scheme = text.split("://", 1)[0] if "://" in text else "tcp"
    if scheme != "tcp":
        raise ScenarioError(
            f"--scheduler: {quote(text)} uses {scheme}://; snoworm connects to tcp://host:port "
            "addresses only (for another protocol make a distributed.Client yourself and pass it: "
            "run_sweep(..., scheduler=client))."
        )
    box = {}

    def connect():
        try:
            box["client"] = client_class(text, timeout=f"{CONNECT_TIMEOUT_S}s")
        except BaseException as exc:  # noqa: BLE001 - handed to the caller as bad input
            box["error"] = exc

    th = threading.Thread(target=connect, name="snoworm-dask-connect", daemon=True)
    th.start()
    th.join(HANDSHAKE_TIMEOUT_S)
    if "client" in box:
        return box["client"]
    why = (
        f"no Dask scheduler answered within {HANDSHAKE_TIMEOUT_S} s (something else may be listening there)"
        if th.is_alive()
        else f"{type(box['error']).__name__}: {quote(str(box['error']))}"
    )
    raise ScenarioError(
        f"--scheduler {quote(text)}: cannot connect to the Dask scheduler ({why}). "
        "Check the address (tcp://host:port) and that the scheduler is running."
    )


class DaskExecutor:
    """Run the cases on a Dask distributed cluster at ``address`` (``tcp://host:port``).

    The workers need snoworm installed; ``save_cases`` and a relative ``terrain.model_file``
    need a file system shared with the workers.  At most ``4 * workers`` cases are in flight.
    Connecting waits at most :data:`CONNECT_TIMEOUT_S` seconds.
    """

    def __init__(self, address):
        try:
            from distributed import Client  # optional dependency (snoworm[dask]): imported only when used
        except ImportError:
            raise ScenarioError(
                f"--scheduler {address}: Dask is not installed. Install it with "
                "pip install 'snoworm[dask]' (or pip install 'dask[distributed]')."
            ) from None
        self.address = address
        self.client = address if hasattr(address, "submit") else _connect(Client, address)
        self._own = not hasattr(address, "submit")

    def map_unordered(self, fn, tasks):
        from distributed import as_completed  # optional dependency, see __init__

        n_workers = max(len(self.client.scheduler_info().get("workers", {})), 1)
        window = 4 * n_workers
        it = iter(tasks)
        first = [self.client.submit(fn, t, pure=False) for t in itertools.islice(it, window)]
        if not first:
            return
        ac = as_completed(first)
        for fut in ac:
            nxt = next(it, None)
            if nxt is not None:
                ac.add(self.client.submit(fn, nxt, pure=False))
            result = fut.result()
            fut.release()
            yield result

    def close(self):
        if self._own:
            self.client.close()


def _run_group(tasks, cases, fallback, metrics):
    """Rows of one group of batchable tasks, assembled (one stacked solve; failing members reported per member)."""
    wall0 = time.perf_counter()
    members = simulate_batch(cases)
    wall = (time.perf_counter() - wall0) / len(tasks)
    out = []
    for task, mem in zip(tasks, members):
        if mem.status != "ok":
            out.append({"index": task.index, "status": mem.status, "error": mem.error, "wall_time_s": wall})
            continue
        row = {"index": task.index, "status": "ok", "error": ""}
        try:
            row.update(metrics(mem.result))
            if task.save_dir:
                row.update(
                    save_case_series(mem.result, task.save_dir, task.lock_token)
                )  # an I/O failure stops the sweep
        except Exception:  # noqa: BLE001 - let the one-by-one path report the case's error
            row = fallback(task)
        row.setdefault("wall_time_s", wall)
        out.append(row)
    return out


def run_chunk(tasks, fn, metrics, max_group=None) -> list:
    """Run a chunk of sweep tasks: batchable groups stacked, the rest through ``fn`` one by one."""
    groups, results = {}, []
    for task in tasks:
        try:
            sc = task.validated()
            task = task.with_scenario(sc)  # validated once: fn (run_case) reuses it
            # assembled once (model and mode): the key reads its model, the stack runs it
            case = assemble(sc) if sc.mode.batch_signature() is not None else None
            key = None if case is None else batch_key(case)
        except (ScenarioError, ValueError):
            key = None  # fn reports an invalid case (e.g. a target the chain cannot carry)
        if key is None:
            results.append(fn(task))
        else:
            groups.setdefault(key, []).append((task, case))
    for members in groups.values():
        size = max_group or len(members)
        for j in range(0, len(members), size):
            part = members[j : j + size]
            if len(part) == 1:
                results.append(fn(part[0][0]))
            else:
                tasks_, cases = zip(*part)
                results.extend(_run_group(list(tasks_), list(cases), fn, metrics))
    return results


class BatchExecutor:
    """Sweep executor that stacks batchable cases (see the module docstring).

    Parameters
    ----------
    batch_size : int
        Cases per stacked solve (100-500 is the measured sweet spot).
    jobs : int
        Local worker processes, each integrating whole chunks (1: in this process).
    pool : object, optional
        A process executor with ``map_unordered`` (made by the caller when ``jobs > 1``).
    metrics : callable, optional
        ``metrics(result) -> dict``, the per-case metrics (default: :func:`snoworm.studies.sweep.metrics.case_metrics`).
    """

    def __init__(self, batch_size: int = 100, jobs: int = 1, pool=None, metrics=None):
        if int(batch_size) < 1:
            raise ValueError(f"batch size must be at least 1, got {batch_size}")
        self.batch_size = int(batch_size)
        self.jobs = int(jobs)
        self._pool = pool
        self._metrics = case_metrics if metrics is None else metrics

    def _chunks(self, tasks):
        it = iter(tasks)
        while True:
            chunk = list(itertools.islice(it, self.batch_size))
            if not chunk:
                return
            yield chunk

    def map_unordered(self, fn, tasks):
        run = functools.partial(run_chunk, fn=fn, metrics=self._metrics)
        if self._pool is None:
            for chunk in self._chunks(tasks):
                yield from run(chunk)
        else:
            for rows in self._pool.map_unordered(run, self._chunks(tasks)):
                yield from rows

    def close(self):
        if self._pool is not None:
            self._pool.close()
