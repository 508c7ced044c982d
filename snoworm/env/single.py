"""The single environment :class:`SnowormEnv` (registered as ``snoworm/Snoworm-v0``, see :mod:`snoworm.env`)."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any, SupportsFloat, cast

import gymnasium
import numpy as np
from gymnasium.error import ResetNeeded

from ..model.quantities import output_series
from ..modes.command import Observation
from ..simulation.stepwise import Simulator
from .core import DEFAULT_REWARD, OBSERVATION_FIELDS, EnvCore, RewardFunction, table_fields
from .render import RENDER_MODES, ChainRenderer, check_render_mode

if TYPE_CHECKING:
    from collections.abc import Sequence

    from numpy.typing import ArrayLike, NDArray

    from ..config.scenario import Scenario

__all__ = ["SnowormEnv", "make_env"]


class SnowormEnv(gymnasium.Env["NDArray[np.float32]", "ArrayLike"]):
    """A scenario's chain as a Gymnasium environment (spaces, reward and solver: :mod:`snoworm.env`).

    Parameters
    ----------
    scenario : Scenario, str or path
        The scenario, a shipped scenario's name or a YAML path (default ``"tow6_uniform"``).
    reward : str or callable
        A preset of :data:`snoworm.env.core.REWARD_PRESETS`: ``"efficiency"`` (default: progress [m]
        minus the motors' energy [J] over the chain's weight m g [N], or times ``energy_weight``)
        or ``"distance"`` (progress only); or ``reward(prev_obs, obs, info) -> float`` with
        physical Observations.
    dt_s, action_keys, energy_weight, stall_speed_mps, stall_time_s
        As :class:`snoworm.env.core.EnvCore`.
    method : str or None
        Solver for the control periods (default ``"VODE"``: restarted at a step whose command
        changed, carried on across a held one); None: the scenario's ``simulation.method``.
        Tolerances are the scenario's.
    record : bool
        Keep every step for ``env.sim.result()`` (memory grows with the episode); default False.
    render_mode : {None, "rgb_array"}
        ``"rgb_array"``: :meth:`render` returns the chain as an ``H x W x 3`` uint8 image
        (:mod:`snoworm.env.render`, the drawing of ``snoworm animate``); None: no rendering.
    """

    metadata = {"render_modes": RENDER_MODES}

    def __init__(
        self,
        scenario: Scenario | str | os.PathLike[str] = "tow6_uniform",
        reward: str | RewardFunction = DEFAULT_REWARD,
        dt_s: float = 0.1,
        action_keys: str | Sequence[str] = ("wheel_speed_mps",),
        energy_weight: float | None = None,
        stall_speed_mps: float = 0.01,
        stall_time_s: float = 2.0,
        method: str | None = "VODE",
        record: bool = False,
        render_mode: str | None = None,
    ) -> None:
        self.render_mode = check_render_mode(render_mode)
        preset = DEFAULT_REWARD if callable(reward) else reward
        self.core = EnvCore(scenario, dt_s, action_keys, energy_weight, stall_speed_mps, stall_time_s, preset)
        sc = self.core.scenario
        if method is not None and method != sc.simulation.method:
            sc = sc.with_({"simulation.method": method})
        self.scenario, self.dt_s = sc, self.core.dt_s
        self.reward_fn: RewardFunction | None = reward if callable(reward) else None
        self.action_keys = self.core.action_keys
        self.max_episode_steps = self.core.max_episode_steps
        self.sim = Simulator(sc, record=record)
        self.action_space = self.core.single_action_space
        self.observation_space = self.core.single_observation_space
        self.metadata = {**self.metadata, "render_fps": 1.0 / self.dt_s}  # a frame per step
        self.renderer = ChainRenderer(sc)
        self.observation: Observation | None = None
        self._stalled_s = 0.0
        self._done: bool | None = None
        self._command: dict[str, NDArray[np.float64]] | None = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        """Back to t = 0: ``(obs, info)``.  ``seed`` seeds ``np_random`` and the action space's
        sampling (the chain itself is deterministic)."""
        super().reset(seed=seed)
        if seed is not None:
            self.action_space.seed(seed)
        self.observation = obs = self.sim.reset()
        self._stalled_s, self._done, self._command = 0.0, False, None
        return self.core.normalised({f: getattr(obs, f) for f in OBSERVATION_FIELDS}, 0.0), {"t_s": 0.0}

    def step(self, action: ArrayLike) -> tuple[NDArray[np.float32], SupportsFloat, bool, bool, dict[str, Any]]:
        """Hold ``action`` for ``dt_s``: ``(obs, reward, terminated, truncated, info)``; ``info`` has
        ``t_s`` and ``motor_energy_J``, the motors' electrical energy in the step [J].

        Raises
        ------
        gymnasium.error.ResetNeeded
            Before the first :meth:`reset`, or after the episode terminated or was truncated.
        ValueError
            A wrong action shape or a non-finite action (nothing changes).
        SolverError
            If every solver method fails (the environment stays at the start of the step).
        """
        if self._done is None:
            raise ResetNeeded("SnowormEnv.step: call reset() before the first step")
        if self._done:
            raise ResetNeeded("SnowormEnv.step: the episode has ended (terminated or truncated); call reset()")
        prev, t0, y0 = cast(Observation, self.observation), self.sim.t_s, self.sim.state  # set by reset()
        command = self.core.physical_action(action)
        held = self._command is not None and all(np.array_equal(command[k], self._command[k]) for k in command)
        obs_t = self.sim.step(command, self.dt_s, restart=not held).t_s
        self._command = command
        ts, ys, ctl = cast(tuple, self.sim.last_step)  # the step just made
        if ts[0] > t0:  # record=True: the step's samples leave out its start (the Result has it)
            ts, ys = np.append(t0, ts), np.vstack([y0, ys])
        seg, lk = output_series(self.sim.model, ys, ctl)
        energy = float(self.core.energy_J(ts, seg))
        info = {"t_s": obs_t, "motor_energy_J": energy}
        fields = table_fields(seg, lk)
        obs = Observation(obs_t, **fields)
        if self.reward_fn is None:
            reward = float(np.mean(obs.x_m) - np.mean(prev.x_m)) - self.core.energy_weight * energy
        else:
            reward = self.reward_fn(prev, obs, info)
        moving = float(np.mean(obs.v_mps)) >= self.core.stall_speed_mps or not np.any(self.sim.commands.source > 0)
        self._stalled_s = 0.0 if moving else self._stalled_s + self.dt_s
        terminated = self._stalled_s >= self.core.stall_time_s - 1e-9
        truncated = obs_t >= self.core.duration_s - 1e-9
        self.observation, self._done = obs, bool(terminated or truncated)
        return self.core.normalised(fields, obs_t), float(reward), bool(terminated), bool(truncated), info

    def render(self) -> NDArray[np.uint8] | None:
        """The chain now, as an ``H x W x 3`` uint8 image (``render_mode="rgb_array"``); None without
        a render mode.  Raises ResetNeeded before the first :meth:`reset`."""
        if self.render_mode is None:
            gymnasium.logger.warn("SnowormEnv.render: no render_mode was given (render_mode='rgb_array' draws)")
            return None
        obs = self.observation
        if obs is None:
            raise ResetNeeded("SnowormEnv.render: call reset() before render()")
        return self.renderer.image(obs.t_s, obs.x_m, obs.link_force_N)

    def close(self) -> None:
        self.renderer.close()
        super().close()


def make_env(**kwargs: Any) -> gymnasium.wrappers.TimeLimit:
    """The registered entry point: :class:`SnowormEnv` ``(**kwargs)`` in a ``TimeLimit`` of its
    ``max_episode_steps`` (so ``env.spec.max_episode_steps`` follows the scenario's duration)."""
    env = SnowormEnv(**kwargs)
    return gymnasium.wrappers.TimeLimit(env, env.max_episode_steps)
