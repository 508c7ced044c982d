"""Batched sweep execution: stack cases of one batch key into one solve (:func:`snoworm.driver.simulate_batch`).

:class:`BatchExecutor` plugs into :func:`snoworm.sweep.run_sweep` (``batch=100`` /
``snoworm sweep --batch 100``): it takes the sweep's tasks in chunks, groups the batchable ones
(:func:`snoworm.driver.batch_key`), and runs everything else one by one through
:func:`snoworm.sweep.run_case`.
"""
from __future__ import annotations

import functools
import itertools
import time

from .driver import batch_key, simulate_batch
from .scenario import scenario_from_dict
from .schema import ScenarioError

__all__ = ["BatchExecutor", "run_chunk"]


def _run_group(tasks, scs, fallback, metrics):
    """Rows of one group of batchable tasks (one stacked solve; failing members reported per member)."""
    wall0 = time.perf_counter()
    members = simulate_batch(scs)
    wall = (time.perf_counter() - wall0) / len(tasks)
    out = []
    for task, mem in zip(tasks, members):
        if mem.status != "ok":
            out.append({"index": task["index"], "status": mem.status, "error": mem.error, "wall_time_s": wall})
            continue
        row = {"index": task["index"], "status": "ok", "error": ""}
        try:
            row.update(metrics(mem.result))
            if task.get("save_dir"):
                mem.result.write(task["save_dir"], plot=False)
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
            sc = scenario_from_dict(task["raw"], task.get("source", "scenario"), base_dir=task.get("base_dir"))
            key = batch_key(sc)
        except (ScenarioError, ValueError):
            key = None
        if key is None:
            results.append(fn(task))
        else:
            groups.setdefault(key, []).append((task, sc))
    for members in groups.values():
        size = max_group or len(members)
        for j in range(0, len(members), size):
            part = members[j:j + size]
            if len(part) == 1:
                results.append(fn(part[0][0]))
            else:
                tasks_, scs = zip(*part)
                results.extend(_run_group(list(tasks_), list(scs), fn, metrics))
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
    metrics : callable
        ``metrics(result) -> dict``, the sweep's per-case metrics.
    """

    def __init__(self, batch_size: int = 100, jobs: int = 1, pool=None, metrics=None):
        if int(batch_size) < 1:
            raise ValueError(f"batch size must be at least 1, got {batch_size}")
        self.batch_size = int(batch_size)
        self.jobs = int(jobs)
        self._pool = pool
        self._metrics = metrics

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
