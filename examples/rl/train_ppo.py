"""PPO (stable-baselines3) on snoworm's native vector environment (docs/controllers.md, examples/rl/README.md).

    pip install torch --index-url https://download.pytorch.org/whl/cpu   # CPU-only torch first
    pip install -e ".[rl]"                 # gymnasium + stable-baselines3
    python examples/rl/train_ppo.py --steps 100000 --envs 64

Trains an MLP policy on ``snoworm/Snoworm-v0`` (tow6_uniform, actions: the six wheel-speed
set-points, dt 0.1 s, reward: progress [m] - ``--energy-weight`` x motor energy [J] per step) with B
members stepped as one solve, then prints the wall time and the deterministic policy's episode
return on a single environment, next to two fixed policies: random actions and the paper's
uniform 1.8 m/s (the scenario's own mode).
"""

from __future__ import annotations

import argparse
import time

import gymnasium
import numpy as np
from stable_baselines3 import PPO

import snoworm.env  # noqa: F401  (registers snoworm/Snoworm-v0)
from snoworm.env.sb3 import SB3VecEnv


def episode_return(env, policy, seed=0):
    """One episode's return on a single environment under ``policy(obs) -> action``."""
    obs, _ = env.reset(seed=seed)
    total, done = 0.0, False
    while not done:
        obs, r, term, trunc, _ = env.step(policy(obs))
        total += r
        done = term or trunc
    return total


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=100_000, help="environment steps to train (all members)")
    ap.add_argument("--envs", type=int, default=64, help="members of the vector environment")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--energy-weight",
        type=float,
        default=1e-4,
        help="reward weight of the motors' energy [m per J] (1e-4, the runs of examples/rl/README.md; the "
        "environment's default preset, reward='efficiency', weighs it by 1/(m g), 1.9e-4 on tow6; 1e-3, "
        "the default before issue 34, makes standing still pay best on tow6)",
    )
    ap.add_argument("--save", help="save the trained policy to this .zip file")
    args = ap.parse_args(argv)

    venv = gymnasium.make_vec(
        "snoworm/Snoworm-v0",
        num_envs=args.envs,
        vectorization_mode="vector_entry_point",
        energy_weight=args.energy_weight,
    )
    env = SB3VecEnv(venv.unwrapped)  # same-step resets with terminal_observation, as SB3 expects
    env.seed(args.seed)
    model = PPO(
        "MlpPolicy",
        env,
        n_steps=64,
        batch_size=512,
        n_epochs=5,
        learning_rate=3e-4,
        gamma=0.99,
        seed=args.seed,
        verbose=0,
        device="cpu",
    )
    t0 = time.perf_counter()
    model.learn(total_timesteps=args.steps)
    wall = time.perf_counter() - t0
    print(
        f"trained {model.num_timesteps} env steps ({args.envs} members) in {wall:.1f} s "
        f"({model.num_timesteps / wall:.0f} env-steps/s including the PPO updates)"
    )
    if args.save:
        model.save(args.save)

    single = gymnasium.make("snoworm/Snoworm-v0", energy_weight=args.energy_weight)
    space = single.action_space
    space.seed(args.seed)
    uniform = np.full(6, 2 * 1.8 / single.unwrapped.core.high[0] - 1, np.float32)  # 1.8 m/s on [-1, 1]
    rows = {
        "trained PPO (deterministic)": lambda o: model.predict(o, deterministic=True)[0],
        "random actions": lambda o: space.sample(),
        "uniform 1.8 m/s from t = 0": lambda o: uniform,
    }
    for label, policy in rows.items():
        print(f"  episode return, {label:28s} {episode_return(single, policy, args.seed):9.2f}")


if __name__ == "__main__":
    main()
