"""Batched simulation: several cases of the same structure integrated as ONE stacked system.

Cases that share their structure (same number of segments and state layout, uniform wheel-speed
mode with the same start times, same solver settings and terrain coefficients, X_t constant or
the same profile) differ only in parameter values: segment and link parameters, tow force,
X_t, speed set-points.  :func:`simulate_batch` stacks their models with
:meth:`ChainModel.stack <snoworm.dynamics.ChainModel.stack>` -- the SAME kernel with one more
leading axis on the parameters -- and integrates the member-major state ``(B * N * n_s,)`` in
one ``solve_ivp`` call per interval.  The stacked Jacobian is block-banded with each member's
band, so LSODA's banded solver works unchanged, and the finite-difference Jacobian still costs
one vectorised kernel call.  LSODA's error test is a weighted max-norm, so every member is held
to the same tolerance as when it runs alone.

Each member's :class:`~snoworm.results.Result` is then built from its own slice of the solution
with its own model and mode, exactly as :func:`~snoworm.simulate.simulate` builds it.

:class:`BatchExecutor` plugs this into :func:`snoworm.sweep.run_sweep` (``executor=``, or
``run_sweep(..., batch=100)`` / ``snoworm sweep --batch 100``): it takes the sweep's tasks in
chunks, groups the batchable ones, and runs everything else (event-driven modes, force control,
a batch whose solve fails) one by one through the ordinary :func:`~snoworm.sweep.run_case`.
"""
from __future__ import annotations

import functools
import itertools
import time

import numpy as np
from scipy.integrate import solve_ivp

from . import modes
from .dynamics import ChainModel, Controls
from .results import Result
from .simulate import SolverError, _grid, build_model, solver_options

__all__ = ["batch_key", "simulate_batch", "BatchExecutor"]


def batch_key(sc, model=None):
    """A hashable key shared by the scenarios that can be stacked together, or None if ``sc``
    cannot be batched (only event-free uniform wheel-speed runs without a force loop can)."""
    if sc.mode.type != "uniform":
        return None
    model = model or build_model(sc)
    if model.force_loop:
        return None
    sim = sc.simulation
    profile = "constant" if model.profile.is_constant else model.profile
    return (model.n, model.fields, tuple(model.links.prismatic.tolist()), tuple(sc.mode.start_time_s),
            sim.duration_s, sim.output_dt_s, sim.rtol, sim.atol_scale, sim.method, sim.max_step_s,
            model.tp, profile)


def simulate_batch(scenarios, models=None) -> list:
    """Run scenarios of one :func:`batch_key` as one stacked system; one Result per scenario.

    Raises
    ------
    ValueError
        If the scenarios do not share a batch key.
    SolverError
        If the stacked solve fails (callers fall back to running the cases one by one, with
        :func:`~snoworm.simulate.simulate`'s own method fallbacks).
    """
    wall0 = time.perf_counter()
    scs = list(scenarios)
    models = list(models) if models is not None else [build_model(sc) for sc in scs]
    keys = {batch_key(sc, m) for sc, m in zip(scs, models)}
    if None in keys or len(keys) != 1:
        raise ValueError("simulate_batch needs scenarios with one batch key (uniform mode, same structure)")
    B = len(scs)
    big = ChainModel.stack(models)
    mds = [modes.mode_class(sc.mode)(sc.mode, sc, m) for sc, m in zip(scs, models)]
    sim = scs[0].simulation
    opts = solver_options(big, sim)
    t, T = 0.0, sim.duration_s
    y = np.concatenate([md.initial_state() for md in mds])
    pieces = [[] for _ in range(B)]
    phases = []
    stats = {"nfev": 0, "njev": 0, "nlu": 0, "intervals": 0}
    while t < T - 1e-12:
        ys_b = y.reshape(B, -1)
        ivs = [md.interval(t, ys_b[b]) for b, md in enumerate(mds)]
        t1 = float(min(ivs[0].t_end, T))
        if any(iv.events for iv in ivs) or any(float(min(iv.t_end, T)) != t1 for iv in ivs) or t1 <= t:
            raise ValueError("simulate_batch: the members' intervals differ")
        ctl = Controls.stack([iv.controls for iv in ivs])
        sol = solve_ivp(big.rhs, (t, t1), y, t_eval=_grid(t, t1, sim.output_dt_s, include_start=not phases),
                        args=(ctl,), **opts)
        stats["nfev"] += int(sol.nfev)
        stats["njev"] += int(sol.njev)
        stats["nlu"] += int(sol.nlu)
        if sol.status < 0 or not np.all(np.isfinite(sol.y)):
            raise SolverError(f"batched {sim.method} failed at t = {t:.6g} s: {sol.message}")
        stats["intervals"] += 1
        ts = np.asarray(sol.t, float)
        Ys = np.asarray(sol.y, float).T.reshape(ts.size, B, -1)
        for b in range(B):
            pieces[b].append((ts, Ys[:, b, :], ivs[b].controls))
        phases.append({"t_start_s": t, "t_end_s": t1, "label": ivs[0].label})
        t, y = t1, sol.y[:, -1].copy()
    wall = time.perf_counter() - wall0
    out = []
    for b in range(B):
        st = dict(stats, batch_size=B, wall_time_s=wall / B)
        out.append(Result.from_pieces(scs[b], models[b], mds[b], pieces[b], [dict(p) for p in phases], st))
    return out


def _run_group(tasks, scs, models, fallback):
    """Results (run_case dicts) of one group of batchable tasks; one by one if the batch fails."""
    from .sweep import case_metrics
    wall0 = time.perf_counter()
    try:
        results = simulate_batch(scs, models)
    except (SolverError, ValueError, ArithmeticError, np.linalg.LinAlgError):
        return [fallback(task) for task in tasks]
    wall = (time.perf_counter() - wall0) / len(tasks)
    out = []
    for task, res in zip(tasks, results):
        row = {"index": task["index"], "status": "ok", "error": ""}
        try:
            row.update(case_metrics(res))
            if task.get("save_dir"):
                res.write(task["save_dir"], plot=False)
        except Exception:  # noqa: BLE001 - let the one-by-one path report the case's error
            row = fallback(task)
        row.setdefault("wall_time_s", wall)
        out.append(row)
    return out


def run_chunk(tasks, fn=None, max_group=None) -> list:
    """Run a chunk of sweep tasks: batchable groups stacked, the rest through ``fn`` one by one.

    ``fn`` defaults to :func:`snoworm.sweep.run_case`; the results are its dicts, in any order.
    """
    from .scenario import scenario_from_dict
    from .schema import ScenarioError
    from .sweep import run_case
    fn = fn or run_case
    groups, results = {}, []
    for task in tasks:
        try:
            sc = scenario_from_dict(task["raw"], task.get("source", "scenario"), base_dir=task.get("base_dir"))
            model = build_model(sc)
            key = batch_key(sc, model)
        except (ScenarioError, ValueError):
            key = None
        if key is None:
            results.append(fn(task))
        else:
            groups.setdefault(key, []).append((task, sc, model))
    for members in groups.values():
        size = max_group or len(members)
        for j in range(0, len(members), size):
            part = members[j:j + size]
            if len(part) == 1:
                results.append(fn(part[0][0]))
            else:
                tasks_, scs, models = zip(*part)
                results.extend(_run_group(list(tasks_), list(scs), list(models), fn))
    return results


class BatchExecutor:
    """Sweep executor that stacks batchable cases (see the module docstring).

    Parameters
    ----------
    batch_size : int
        Cases per stacked solve (100-500 is the measured sweet spot, PERFORMANCE.md).
    jobs : int
        Local worker processes, each integrating whole chunks (1: in this process).
    """

    def __init__(self, batch_size: int = 100, jobs: int = 1):
        if int(batch_size) < 1:
            raise ValueError(f"batch size must be at least 1, got {batch_size}")
        self.batch_size = int(batch_size)
        self.jobs = int(jobs)
        self._pool = None
        if self.jobs > 1:
            from .sweep import ProcessExecutor
            self._pool = ProcessExecutor(self.jobs)

    def _chunks(self, tasks):
        it = iter(tasks)
        while True:
            chunk = list(itertools.islice(it, self.batch_size))
            if not chunk:
                return
            yield chunk

    def map_unordered(self, fn, tasks):
        run = functools.partial(run_chunk, fn=fn)
        if self._pool is None:
            for chunk in self._chunks(tasks):
                yield from run(chunk)
        else:
            for rows in self._pool.map_unordered(run, self._chunks(tasks)):
                yield from rows

    def close(self):
        if self._pool is not None:
            self._pool.close()
