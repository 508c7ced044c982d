"""Cost per member of a step of the vector environment against its size B (issue 30).

Usage (from the repository root)::

    python benchmarks/vector_scaling.py                  # B = 1 16 64 256 1000, 3 periods each (~1 min)
    python benchmarks/vector_scaling.py 64 256 --steps 5

tow6_uniform, random wheel-speed actions, dt 0.1 s, the default solver (VODE): for each B one
period to start, then the mean of ``--steps`` periods, in wall and CPU time of this process (on a
loaded machine the wall time is the CPU time plus the waits; OpenBLAS's threads count in both).
The cost per member should fall to a floor by B ~ 64 (the stack size) and stay there.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from snoworm.env.vector import SnowormVectorEnv  # noqa: E402


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


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sizes", nargs="*", type=int, default=[1, 16, 64, 256, 1000], help="values of B")
    ap.add_argument("--steps", type=int, default=3, help="periods measured per B (after one)")
    args = ap.parse_args(argv)
    print(f"{'B':>6} {'wall ms/member':>15} {'CPU ms/member':>14} {'RHS calls/period':>17}")
    for b in args.sizes:
        r = per_member_cost(b, args.steps)
        print(f"{b:6d} {r['wall_ms']:15.2f} {r['cpu_ms']:14.2f} {r['nfev']:17.0f}")


if __name__ == "__main__":
    main()
