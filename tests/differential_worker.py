"""Run scenarios and print what they gave, for the differential tests (tests/test_differential.py).

``python -m tests.differential_worker`` reads a JSON list of jobs on standard input and prints
one JSON list of fingerprints: a job is ``{"base": NAME, "overrides": [[KEY, VALUE], ...]}`` (a
run, :func:`run_fingerprint`) or ``{"sweep_case": ...}`` (the same with the sweep's metrics of the
run, :func:`case_fingerprint`).  The tests run a job in a fresh interpreter through it, and the
same jobs in their own process through the same functions, so the two differ only in what ran
before in the process.
"""

from __future__ import annotations

import json
import sys

import numpy as np

#: summary entries that may differ between identical runs (wall-clock time, versions, texts)
_VOLATILE = {"wall_time_s", "snoworm_version", "sources", "scenario"}


def _numbers(obj, prefix=""):
    """The numbers of a nested summary as ``{path: value}`` (volatile entries left out)."""
    out = {}
    if isinstance(obj, dict):
        for k, v in obj.items():
            if k not in _VOLATILE:
                out.update(_numbers(v, f"{prefix}{k}."))
    elif isinstance(obj, (list, tuple)):
        for k, v in enumerate(obj):
            out.update(_numbers(v, f"{prefix}{k}."))
    elif isinstance(obj, bool) or obj is None or isinstance(obj, str):
        out[prefix[:-1]] = obj
    elif isinstance(obj, (int, float)):
        out[prefix[:-1]] = float(obj)
    return out


def run_fingerprint(base, overrides) -> dict:
    """What one run gives: its summary's numbers, solver work, times and every series."""
    from snoworm import load_scenario, simulate

    res = simulate(load_scenario(base, [tuple(o) for o in overrides]))
    fp = {"summary": _numbers(res.summary()), "t": np.asarray(res.t, float).tolist()}
    for table in ("segments", "links"):
        for k, v in getattr(res, table).items():
            a = np.asarray(v)
            if a.dtype.kind in "fi":
                fp[f"{table}.{k}"] = a.astype(float).reshape(-1).tolist()
    return fp


def case_fingerprint(base, overrides) -> dict:
    """The sweep metrics (the numeric columns of ``summary.csv``) of one case run alone."""
    from snoworm import load_scenario, simulate
    from snoworm.studies.sweep.metrics import case_metrics

    m = case_metrics(simulate(load_scenario(base, [tuple(o) for o in overrides])))
    return {k: v for k, v in _numbers(m).items() if not isinstance(v, str)}


def env_fingerprint(base, overrides, steps, seed, num_envs=0) -> dict:
    """Observations and rewards of an environment stepped with seeded random actions: the single
    environment (``num_envs`` 0) or the native vector environment of ``num_envs`` members."""
    from snoworm import load_scenario
    from snoworm.env.single import SnowormEnv
    from snoworm.env.vector import SnowormVectorEnv

    sc = load_scenario(base, [tuple(o) for o in overrides])
    env = SnowormVectorEnv(num_envs, scenario=sc) if num_envs else SnowormEnv(scenario=sc)
    rng = np.random.default_rng(seed)
    obs, _ = env.reset(seed=seed)
    out = {"obs": [np.asarray(obs, float).reshape(-1).tolist()], "reward": []}
    for _ in range(steps):
        obs, reward, *_ = env.step(rng.uniform(-1.0, 1.0, env.action_space.shape))
        out["obs"].append(np.asarray(obs, float).reshape(-1).tolist())
        out["reward"].append(np.asarray(reward, float).reshape(-1).tolist())
    return {"obs": np.ravel(out["obs"]).tolist(), "reward": np.ravel(out["reward"]).tolist()}


def run_job(job) -> dict:
    if "env" in job:
        return env_fingerprint(job["env"], job["overrides"], job["steps"], job["seed"], job.get("num_envs", 0))
    if "sweep_case" in job:
        return case_fingerprint(job["sweep_case"], job["overrides"])
    return run_fingerprint(job["base"], job["overrides"])


if __name__ == "__main__":
    jobs = json.load(sys.stdin)
    print(json.dumps([run_job(j) for j in jobs]))
