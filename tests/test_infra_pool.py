"""snoworm.infra.pool: the process pool every study shares."""

from __future__ import annotations

import os
import time

import pytest

from snoworm.infra.pool import THREAD_ENV, ProcessExecutor, start_method


def _slow_square(x):
    time.sleep(0.2)
    return x * x, os.getpid(), os.environ.get("OMP_NUM_THREADS")


def _fail_on_three(x):
    if x == 3:
        raise ValueError("task 3 failed")
    return x


def test_pool_runs_in_two_workers_and_returns_every_result(monkeypatch):
    for k in THREAD_ENV:
        monkeypatch.delenv(k, raising=False)
    with ProcessExecutor(2) as pool:
        out = pool.map(_slow_square, range(6))
        unordered = sorted(r[0] for r in pool.map_unordered(_slow_square, range(5)))
    assert [r[0] for r in out] == [0, 1, 4, 9, 16, 25]  # in task order
    assert unordered == [0, 1, 4, 9, 16]
    pids = {r[1] for r in out}
    assert len(pids) == 2 and os.getpid() not in pids
    assert {r[2] for r in out} == {"1"}  # one BLAS thread per worker
    assert all(k not in os.environ for k in THREAD_ENV)  # restored after close


def test_a_task_exception_reaches_the_caller():
    with ProcessExecutor(2) as pool:
        with pytest.raises(ValueError, match="task 3 failed"):
            pool.map(_fail_on_three, range(5))


def test_start_method_is_fork_or_spawn():
    assert start_method() in ("fork", "spawn")
