"""snoworm.env.SnowormEnv as it was on main before issue 27 (main at bb09471, relative imports made
absolute), kept verbatim as the speed baseline of benchmarks/run.py (bench_rl): the ratio of the
new environments is measured against it in the same run.  Not part of the package."""

from __future__ import annotations

import numpy as np

try:
    import gymnasium
    from gymnasium import spaces
except ImportError as exc:  # pragma: no cover - depends on the installed extras
    raise ImportError("snoworm.env needs gymnasium: pip install 'snoworm[gym]'") from exc

from snoworm.model.quantities import output_series
from snoworm.simulation.stepwise import Simulator

__all__ = ["SnowormEnv", "OBSERVATION_FIELDS", "default_reward"]

#: Observation arrays in the order they fill the observation vector.
OBSERVATION_FIELDS = (
    "x_m",
    "v_mps",
    "wheel_speed_mps",
    "slip",
    "motor_torque_Nm",
    "xt",
    "link_force_N",
    "link_length_m",
    "joint_extension_m",
)


def default_reward(prev_obs, obs, info, energy_weight=1e-3) -> float:
    """Progress of the chain's mean position [m] minus ``energy_weight`` times the motors' energy [J]."""
    return float(np.mean(obs.x_m) - np.mean(prev_obs.x_m)) - energy_weight * info["motor_energy_J"]


class SnowormEnv(gymnasium.Env):
    """A scenario's chain as a Gymnasium environment (see the module docstring for spaces and reward).

    Parameters
    ----------
    scenario : Scenario
        The validated scenario; its mode gives only the initial state.
    reward : callable, optional
        ``reward(prev_obs, obs, info) -> float``; default :func:`default_reward`.
    dt_s : float
        How long each action is held [s].
    action_keys : tuple of str
        Command keys that make up the action vector.
    energy_weight : float
        Weight of the motors' electrical energy in the default reward [1/J per m].
    stall_speed_mps, stall_time_s : float
        Immobilisation test: mean speed below ``stall_speed_mps`` for ``stall_time_s``.
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        scenario,
        reward=None,
        dt_s=0.1,
        action_keys=("wheel_speed_mps",),
        energy_weight=1e-3,
        stall_speed_mps=0.01,
        stall_time_s=2.0,
    ):
        if not dt_s > 0:
            raise ValueError(f"dt_s: the step length must be positive, got {dt_s!r}")
        self.sim = Simulator(scenario)
        self.scenario, self.dt_s = scenario, float(dt_s)
        self.reward_fn = reward
        self.energy_weight, self.stall_speed_mps, self.stall_time_s = energy_weight, stall_speed_mps, stall_time_s
        self.action_keys = tuple(action_keys)
        lo, hi = self._action_bounds()
        self.action_space = spaces.Box(lo, hi, dtype=np.float64)
        n_obs = self._vector(self.sim.observation()).size
        self.observation_space = spaces.Box(-np.inf, np.inf, shape=(n_obs,), dtype=np.float64)
        self._obs, self._stalled_s = None, 0.0

    def _action_bounds(self):
        model = self.sim.model
        seg, links, n = model.seg, model.links, model.n
        bounds = {
            "wheel_speed_mps": (np.zeros(n), seg.no_load_speed_radps * seg.wheel_radius_m),
            "wheel_torque_Nm": (-seg.torque_limit_Nm, seg.torque_limit_Nm),
            "joint_force_N": (-links.force_max_N, links.force_max_N),
            "joint_length_m": (links.stroke_min_m, links.stroke_max_m),
        }
        for key in self.action_keys:
            if key not in bounds:
                raise ValueError(f"action_keys: {key!r} cannot be an action; choose among {', '.join(bounds)}")
            if key.startswith("joint_") and not model.has_joints:
                raise ValueError(f"action_keys: {key!r} needs a vehicle with prismatic joints")
        lo = np.concatenate([np.asarray(bounds[k][0], float) for k in self.action_keys])
        hi = np.concatenate([np.asarray(bounds[k][1], float) for k in self.action_keys])
        return lo, hi

    @staticmethod
    def _vector(obs):
        return np.concatenate([getattr(obs, f) for f in OBSERVATION_FIELDS]).astype(np.float64)

    def _command(self, action):
        a = np.clip(np.asarray(action, float).reshape(-1), self.action_space.low, self.action_space.high)
        if a.size != self.action_space.shape[0]:
            raise ValueError(f"action: expected {self.action_space.shape[0]} values, got {a.size}")
        cmd, j = {}, 0
        for key in self.action_keys:
            size = self.sim.model.n - (1 if key.startswith("joint_") else 0)
            cmd[key] = a[j : j + size]
            j += size
        return cmd

    def reset(self, *, seed=None, options=None):
        """Back to t = 0 (the chain is deterministic; ``seed`` seeds the spaces' sampling): ``(obs, info)``."""
        super().reset(seed=seed)
        self._obs, self._stalled_s = self.sim.reset(), 0.0
        return self._vector(self._obs), {"t_s": self._obs.t_s}

    def step(self, action):
        """Hold ``action`` for ``dt_s``: ``(obs, reward, terminated, truncated, info)``; ``info`` has
        ``t_s`` and ``motor_energy_J``, the motors' electrical energy in the step [J]."""
        prev = self._obs
        obs = self.sim.step(self._command(action), self.dt_s)
        ts, ys, ctl = self.sim.last_step
        power = output_series(self.sim.model, ys, ctl)[0]["motor_electrical_power_W"].sum(-1)
        energy = float(np.sum(0.5 * (power[1:] + power[:-1]) * np.diff(ts)))  # trapezoid rule
        info = {"t_s": obs.t_s, "motor_energy_J": energy}
        reward = (self.reward_fn or (lambda p, o, i: default_reward(p, o, i, self.energy_weight)))(prev, obs, info)
        moving = float(np.mean(obs.v_mps)) >= self.stall_speed_mps or not np.any(self.sim.commands.source > 0)
        self._stalled_s = 0.0 if moving else self._stalled_s + self.dt_s
        terminated = self._stalled_s >= self.stall_time_s - 1e-9
        truncated = obs.t_s >= self.scenario.simulation.duration_s - 1e-9
        self._obs = obs
        return self._vector(obs), float(reward), bool(terminated), bool(truncated), info
