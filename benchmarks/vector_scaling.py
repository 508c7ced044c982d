"""Cost per member of a step of the vector environment against its size B (issue 30).

Usage (from the repository root)::

    python benchmarks/vector_scaling.py                  # B = 1 16 64 256 1000, 3 periods each (~1 min)
    python benchmarks/vector_scaling.py 64 256 --steps 5
    python benchmarks/vector_scaling.py 1 16 32 64 96 128 --accuracy 50   # + each member's error (~3 min)

tow6_uniform, random wheel-speed actions, dt 0.1 s, the default solver (VODE): for each B one
period to start, then the mean of ``--steps`` periods, in wall and CPU time of this process (on a
loaded machine the wall time is the CPU time plus the waits; OpenBLAS's threads count in both).
The cost per member should fall to a floor by B ~ 64 (the stack size) and stay there.

``--accuracy STEPS`` also gives, for each B, the largest and the median over the members of each
member's largest deviation (normalised observation units, every observation of every step) from the
same member at rtol 1e-9, over ``STEPS`` periods of random actions from the start (the default
tolerance, ``VECTOR_RTOL`` per member, is meant to keep it within 5e-3).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from snoworm.env.vector import VECTOR_RTOL, SnowormVectorEnv  # noqa: E402


def per_member_cost(num_envs: int, steps: int) -> dict:
    """Wall and CPU seconds of one period, per member, and the right-hand-side calls of a period."""
    env = SnowormVectorEnv(num_envs, "tow6_uniform", dt_s=0.1)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = [rng.uniform(-1, 1, env.action_space.shape).astype(np.float32) for _ in range(steps + 1)]
    env.step(actions[0])
    nfev0, wall0, cpu0 = env.stats["nfev"], time.perf_counter(), time.process_time()
    for a in actions[1:]:
        env.step(a)
    wall, cpu = (time.perf_counter() - wall0) / steps, (time.process_time() - cpu0) / steps
    return {
        "wall_ms": 1e3 * wall / num_envs,
        "cpu_ms": 1e3 * cpu / num_envs,
        "nfev": (env.stats["nfev"] - nfev0) / steps,
    }


def member_errors(num_envs: int, steps: int) -> tuple[float, float]:
    """(largest, median) over the members of each member's largest deviation from the same member
    at rtol 1e-9 (normalised observations, every step of ``steps`` random-action periods)."""
    acts = np.random.default_rng(1).uniform(-1, 1, (steps, num_envs, 6)).astype(np.float32)
    runs = []
    for rtol in (VECTOR_RTOL, 1e-9):
        env = SnowormVectorEnv(num_envs, "tow6_uniform", dt_s=0.1, rtol=rtol)
        obs = [env.reset(seed=0)[0]] + [env.step(a)[0] for a in acts]
        runs.append(np.array(obs, float))
    err = np.abs(runs[0] - runs[1]).max(axis=(0, 2))
    return float(err.max()), float(np.median(err))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sizes", nargs="*", type=int, default=[1, 16, 64, 256, 1000], help="values of B")
    ap.add_argument("--steps", type=int, default=3, help="periods measured per B (after one)")
    ap.add_argument(
        "--accuracy", type=int, default=0, metavar="STEPS", help="also each member's error over STEPS periods"
    )
    args = ap.parse_args(argv)
    extra = f" {'worst member err':>17} {'median member err':>18}" if args.accuracy else ""
    print(f"{'B':>6} {'wall ms/member':>15} {'CPU ms/member':>14} {'RHS calls/period':>17}{extra}")
    for b in args.sizes:
        r = per_member_cost(b, args.steps)
        line = f"{b:6d} {r['wall_ms']:15.2f} {r['cpu_ms']:14.2f} {r['nfev']:17.0f}"
        if args.accuracy:
            worst, median = member_errors(b, args.accuracy)
            line += f" {worst:17.2e} {median:18.2e}"
        print(line, flush=True)


if __name__ == "__main__":
    main()
