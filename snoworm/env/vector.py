"""The native Gymnasium vector environment: B copies of a chain stepped as a few stacked solves.

::

    import gymnasium, snoworm.env
    envs = gymnasium.make_vec("snoworm/Snoworm-v0", num_envs=64, vectorization_mode="vector_entry_point")
    obs, info = envs.reset(seed=0)                            # obs: (64, n_obs) float32
    obs, rewards, terminated, truncated, info = envs.step(envs.action_space.sample())

The members share the scenario and the options of :class:`snoworm.env.single.SnowormEnv` (spaces,
action map, observation normalisation, default reward, termination and truncation: one
:class:`~snoworm.env.core.EnvCore`).  A control period has no gait events, so every member's interval
ends at the same time: the B chains are stepped by the one stepper of one chain or many,
:class:`snoworm.simulation.stepper.ChainStepper` (the Simulator's, and so the single
environment's, with one member): stacks of at most :data:`STACK_MAX_MEMBERS` (64) members and
:data:`STACK_MAX_STATES` states (:meth:`ChainModel.stack`, the kernel with one more leading axis),
of sizes that differ by at most one, each integrated over the period on VODE with its tolerances
divided by sqrt(size) (each member's relative tolerance ``rtol``, by default :data:`VECTOR_RTOL` = 1e-3,
not the scenario's: a stack steps at the pace of its hardest member, so its other members are
solved far more finely than their tolerance; every member stays within 5e-3 of an rtol 1e-9
reference in normalised observation units with stacks of 64), restarted at a period whose command changed and carried on while every
member holds its command (as the single environment).  One stack of all B members cost more per member as
B grew (its steps follow its most demanding member at tighter tolerances, and past 10 000 states
VODE's BLAS calls start threads: 67 s a period for B = 1 000 against 0.3 s for 64); with stacks
the cost per member stays at its floor (~3 ms of CPU for tow6 from B = 64 to 1 024,
``benchmarks/vector_scaling.py``).  ``num_envs`` is at most :data:`MAX_NUM_ENVS` (1 024), the range
measured.
(LSODA, which a batched sweep uses for its max-norm test, took ~585 evaluations a period for
B = 64 against VODE's ~290, and scipy 1.17.1's LSODA keeps ~90 kB of every solver it creates:
memory would grow with every period.)  The model does not depend on time, so members at
different times of their episodes share one period.

* **Autoreset** (Gymnasium 1.x ``AutoresetMode.NEXT_STEP``, ``metadata["autoreset_mode"]``): a
  member whose episode terminated or was truncated in a step is reset in the next ``step`` call,
  which returns its first observation with reward 0, not terminated, not truncated, and ignores its
  action.  ``reset(options={"reset_mask": mask})`` resets only the masked members.
* **Per-member status**: when a stack's solve fails, each of its members' period is solved alone
  from the same start; a member that fails alone (or whose speed leaves the physics,
  :data:`snoworm.simulation.guard.SPEED_SANITY_FACTOR`) keeps its start state, gets reward 0 and
  ``truncated`` true, ``info["solver_failure"]`` true and the message in ``info["solver_error"]``,
  and is reset at the next step; the other members go on.
* **info**: ``t_s``, ``motor_energy_J`` and ``solver_failure`` per member (each with its ``_key``
  mask, as Gymnasium's vector infos).
* **Reward**: a preset of :data:`snoworm.env.core.REWARD_PRESETS` (default ``"efficiency"``); a
  ``reward`` callable is not taken (wrap the vector environment instead).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Literal, cast

import numpy as np
from gymnasium.error import ResetNeeded
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from ..config.schema import quote
from ..model.quantities import output_series
from ..modes.command import CommandState
from ..simulation.driver import assemble
from ..simulation.interval import output_grid
from ..simulation.stepper import STACK_MAX_MEMBERS, STACK_MAX_STATES, ChainStepper, stack_size
from .core import DEFAULT_REWARD, EnvCore, table_fields
from .render import RENDER_MODES, ChainRenderer, check_render_mode

if TYPE_CHECKING:
    from numpy.typing import ArrayLike, NDArray

    from ..config.scenario import Scenario
    from ..model.inputs import Controls

__all__ = ["SnowormVectorEnv", "MAX_NUM_ENVS", "VECTOR_RTOL", "STACK_MAX_MEMBERS", "STACK_MAX_STATES", "stack_size"]

#: Each member's relative tolerance by default (``SnowormVectorEnv(rtol=...)``): a stack of k members
#: runs VODE at ``VECTOR_RTOL / sqrt(k)``; measured with stacks of 64 to keep every member within
#: 5e-3 of an rtol 1e-9 reference (normalised observation units; docs/performance.md).
VECTOR_RTOL = 1e-3

#: Most members of a vector environment: the range over which the cost per member was measured flat
#: (docs/performance.md, "Vector environment"); more are refused (run several environments instead).
MAX_NUM_ENVS = 1024


def _rtol(value: Any) -> float:
    """``value`` as a relative tolerance in (0, 1); else ValueError naming ``rtol``."""
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float, np.integer, np.floating))
        or not 0 < float(value) < 1
    ):
        raise ValueError(
            f"rtol: must be a relative tolerance between 0 and 1 (exclusive), got {quote(value, 60)}; "
            f'the default, "auto", is {VECTOR_RTOL:g} on VODE (each member within 5e-3 of a tight reference with stacks '
            "of 64 members); None uses the scenario's simulation.rtol"
        )
    return float(value)


class SnowormVectorEnv(VectorEnv["NDArray[np.float32]", "ArrayLike", "NDArray[Any]"]):
    """``num_envs`` copies of a scenario's chain, stepped together (see the module docstring).

    Parameters
    ----------
    num_envs : int
        Number of members B, 1 to :data:`MAX_NUM_ENVS` (ValueError beyond).
    scenario, dt_s, action_keys, energy_weight, stall_speed_mps, stall_time_s
        As :class:`snoworm.env.single.SnowormEnv`.
    reward : str
        A preset of :data:`snoworm.env.core.REWARD_PRESETS` (default ``"efficiency"``); a callable
        is refused (wrap the vector environment instead).
    max_episode_steps : int, optional
        Truncate an episode after this many steps if that comes before ``simulation.duration_s``.
    method : str or None
        Solver of the stacked periods: ``"VODE"`` (default; its tolerances divided by the square
        root of the stack's size), another ``simulation.method`` (a stack of several members then
        runs on LSODA, as a batched sweep), or None: the scenario's.
    rtol : float, "auto" or None
        Each member's relative tolerance, in place of the scenario's ``simulation.rtol``; a stack of
        k members runs VODE at ``rtol / sqrt(k)`` (and the scenario's absolute tolerances /
        sqrt(k)).  ``"auto"`` (default): :data:`VECTOR_RTOL` (1e-3) when the stacks run on VODE
        (``method="VODE"``, the default), the scenario's rtol on another method (LSODA's max-norm
        test has no sqrt(k) tightening, so 1e-3 there would give each member the accuracy of one chain
        alone at 1e-3: 2-8e-2 from the reference).  With stacks of 64 members (B = 64 and its multiples) the default keeps every
        member within 5e-3 of an rtol 1e-9 reference in normalised observation units over 20 s of
        random actions, at ~7x the single environment's env-steps per CPU second (docs/performance.md,
        "Vector environment: accuracy and cost against B"; smaller stacks are less accurate at the
        same rtol).  None: the scenario's ``simulation.rtol`` (the single environment's accuracy, ~2.7x
        its speed).
    render_mode : {None, "rgb_array"}
        ``"rgb_array"``: :meth:`render` returns member 0's chain as an ``H x W x 3`` uint8 image (the
        single environment's picture, :mod:`snoworm.env.render`; one member, since a tile of 64
        chains would show none of them); None: no rendering.
    """

    metadata = {"render_modes": RENDER_MODES, "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(
        self,
        num_envs: int = 1,
        scenario: Scenario | str | os.PathLike[str] = "tow6_uniform",
        dt_s: float = 0.1,
        action_keys: str | Sequence[str] = ("wheel_speed_mps",),
        energy_weight: float | None = None,
        stall_speed_mps: float = 0.01,
        stall_time_s: float = 2.0,
        max_episode_steps: int | None = None,
        method: str | None = "VODE",
        render_mode: str | None = None,
        rtol: float | Literal["auto"] | None = "auto",
        reward: str = DEFAULT_REWARD,
    ) -> None:
        if (
            isinstance(num_envs, bool)
            or not isinstance(num_envs, (int, np.integer))
            or not 1 <= num_envs <= MAX_NUM_ENVS
        ):
            raise ValueError(
                f"num_envs: must be a whole number from 1 to {MAX_NUM_ENVS}, got {quote(num_envs, 60)}: "
                f"1 to {MAX_NUM_ENVS} members is the range measured to step at a flat cost per member "
                "(docs/performance.md); for more, run several vector environments (e.g. one per process)"
            )
        render_mode = check_render_mode(render_mode)
        if callable(reward):
            raise ValueError(
                "reward: the vector environment takes a preset name "
                '("efficiency" or "distance"), not a callable; wrap the vector environment to compute your own'
            )
        self.core = core = EnvCore(scenario, dt_s, action_keys, energy_weight, stall_speed_mps, stall_time_s, reward)
        self.num_envs = B = int(num_envs)
        self.max_episode_steps = core.max_episode_steps
        if max_episode_steps is not None:
            if (
                isinstance(max_episode_steps, bool)
                or not isinstance(max_episode_steps, (int, np.integer))
                or max_episode_steps < 1
            ):
                raise ValueError(f"max_episode_steps: must be a whole number >= 1, got {max_episode_steps!r}")
            self.max_episode_steps = min(self.max_episode_steps, int(max_episode_steps))
        sc = core.scenario
        if method is not None and method != sc.simulation.method:
            sc = sc.with_({"simulation.method": method})
        if isinstance(rtol, str) and rtol == "auto":
            rtol = VECTOR_RTOL if sc.simulation.method == "VODE" else None
        if rtol is not None:
            sc = sc.with_({"simulation.rtol": _rtol(rtol)})
        self.scenario, self.dt_s, self.render_mode = sc, core.dt_s, render_mode
        self.metadata = {**self.metadata, "render_fps": 1.0 / core.dt_s}
        self.renderer = ChainRenderer(sc)
        self._command: dict[str, NDArray[np.float64]] | None = None
        self.single_action_space = core.single_action_space
        self.single_observation_space = core.single_observation_space
        self.action_space = batch_space(self.single_action_space, B)
        self.observation_space = batch_space(self.single_observation_space, B)
        self.model = core.model
        self._y0 = np.asarray(assemble(core.scenario, core.model).mode.initial_state(), float)
        seg, lk = output_series(self.model, self._y0[None, :], CommandState(self.model).controls)
        fields0 = table_fields(seg, lk)
        self._obs0 = core.normalised(fields0, 0.0)
        self._xmean0 = float(np.mean(fields0["x_m"]))
        self._grid = np.asarray(output_grid(0.0, core.dt_s, core.scenario.simulation.output_dt_s, include_start=True))
        #: the one stepper of one chain or many (simulation.stepper), kept over the periods
        self.stepper = ChainStepper(self.model, sc.simulation, B, "step")
        self.stats = self.stepper.stats
        self._started = False

    # ------------------------------------------------------------------ reset
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        """Reset every member (or those of ``options["reset_mask"]``): ``(obs, info)``.

        ``seed`` (an int) seeds ``np_random`` and the action spaces' sampling."""
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer))):
            raise ValueError(f"seed: expected an int or None, got {seed!r}")
        super().reset(seed=seed)
        if seed is not None:
            self.action_space.seed(int(seed))
            self.single_action_space.seed(int(seed))
        B = self.num_envs
        mask = np.ones(B, bool)
        if options and "reset_mask" in options:
            mask = np.asarray(options["reset_mask"])
            if mask.shape != (B,) or mask.dtype != bool:
                raise ValueError(f"options['reset_mask']: expected {B} booleans, got {options['reset_mask']!r}")
        if not self._started:
            if not mask.all():
                raise ResetNeeded("SnowormVectorEnv.reset: the first reset must reset every member (no reset_mask)")
            n_s = self._y0.size
            self._y, self._obs = (
                np.empty((B, n_s)),
                np.empty((B,) + cast("tuple[int, ...]", self.single_observation_space.shape), np.float32),
            )
            self._t, self._steps, self._stalled = np.zeros(B), np.zeros(B, int), np.zeros(B)
            self._xmean, self._autoreset = np.zeros(B), np.zeros(B, bool)
            self._cmd = CommandState(self.model, batch=B)
            self._T, self._started = 0.0, True
        self._reset_members(mask)
        return self._obs.copy(), {"t_s": self._t.copy(), "_t_s": np.ones(B, bool)}

    def _reset_members(self, mask: NDArray[np.bool_]) -> None:
        self._y[mask] = self._y0
        self._t[mask], self._steps[mask], self._stalled[mask] = 0.0, 0, 0.0
        self._xmean[mask], self._obs[mask], self._autoreset[mask] = self._xmean0, self._obs0, False

    # ------------------------------------------------------------------ step
    def step(
        self, actions: ArrayLike
    ) -> tuple[NDArray[np.float32], NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_], dict[str, Any]]:
        """One control period of every member: ``(obs, rewards, terminated, truncated, info)``.

        Raises ResetNeeded before the first :meth:`reset`; ValueError for a wrong action shape or a
        non-finite action (nothing changes)."""
        if not self._started:
            raise ResetNeeded("SnowormVectorEnv.step: call reset() before the first step")
        core, B = self.core, self.num_envs
        command = core.physical_action(actions, batch=B)
        held = self._command is not None and all(np.array_equal(command[k], self._command[k]) for k in command)
        # VODE: restarted at every period, but carried on while every member holds its command (a
        # member reset in between changes the state, and the stepper then restarts by itself)
        self.stepper.carry_history = held
        self._command = command
        ctl = self._cmd.apply(command)
        restart = self._autoreset.copy()
        if restart.any():  # NEXT_STEP autoreset: these members start again; their action is ignored
            self._reset_members(restart)
        ts, ys, failed, errors = self._solve(ctl)
        failed &= ~restart
        seg, lk = output_series(self.model, ys, ctl)  # (n_t, B, ...): one kernel call
        fields = table_fields(seg, lk)
        energy = core.energy_J(ts - ts[0], seg)
        t_new = self._t + self.dt_s
        obs = core.normalised(fields, t_new)
        xmean = np.mean(fields["x_m"], axis=-1)
        rewards = (xmean - self._xmean) - core.energy_weight * energy
        moving = (np.mean(fields["v_mps"], axis=-1) >= core.stall_speed_mps) | (not np.any(self._cmd.source > 0))
        stalled = np.where(moving, 0.0, self._stalled + self.dt_s)
        steps = self._steps + 1
        terminated = stalled >= core.stall_time_s - 1e-9
        truncated = (t_new >= core.duration_s - 1e-9) | (steps >= self.max_episode_steps)
        ok = ~failed & ~restart  # the restarted members' periods are discarded (they stay at their start)
        self._y[ok], self._t[ok], self._steps[ok], self._stalled[ok] = ys[-1][ok], t_new[ok], steps[ok], stalled[ok]
        self._xmean[ok], self._obs[ok] = xmean[ok], obs[ok]
        rewards, energy = np.where(failed, 0.0, rewards), np.where(failed, 0.0, energy)
        terminated, truncated = terminated & ok, truncated | failed
        rewards[restart], energy[restart], terminated[restart], truncated[restart] = 0.0, 0.0, False, False
        self._autoreset = terminated | truncated
        self._T += self.dt_s
        info = self._info(energy, failed, errors)
        return self._obs.copy(), rewards.astype(float), terminated, truncated, info

    def render(self) -> NDArray[np.uint8] | None:  # type: ignore[override]
        """Member 0's chain now, as an ``H x W x 3`` uint8 image (``render_mode="rgb_array"``); None
        without a render mode.  Raises ResetNeeded before the first :meth:`reset`."""
        if self.render_mode is None:
            return None
        if not self._started:
            raise ResetNeeded("SnowormVectorEnv.render: call reset() before render()")
        seg, lk = output_series(self.model, self._y[None], self._cmd.controls)  # (1, B, ...): one kernel call
        return self.renderer.image(float(self._t[0]), seg["x_m"][0, 0], lk["force_N"][0, 0])

    def close_extras(self, **kwargs: Any) -> None:
        self.renderer.close()

    def _info(self, energy: NDArray[np.float64], failed: NDArray[np.bool_], errors: dict[int, str]) -> dict[str, Any]:
        B = self.num_envs
        every = np.ones(B, bool)
        info = {
            "t_s": self._t.copy(),
            "_t_s": every,
            "motor_energy_J": energy,
            "_motor_energy_J": every,
            "solver_failure": failed.copy(),
            "_solver_failure": every,
        }
        if failed.any():
            info["solver_error"] = np.array([errors.get(b, "") for b in range(B)], dtype=object)
            info["_solver_error"] = failed.copy()
        return info

    def _solve(
        self, ctl: Controls
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_], dict[int, str]]:
        """One period of every member (:meth:`ChainStepper.solve <snoworm.simulation.stepper.ChainStepper.solve>`):
        ``(ts, ys (n_t, B, n_states), failed (B,), errors {b: message})``."""
        t0 = self._T
        t_eval = t0 + self._grid
        ys, _, failed, errors = self.stepper.solve(ctl, t0, t0 + self.dt_s, self._y, t_eval)
        return t_eval, ys, failed, errors
