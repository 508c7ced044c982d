"""Gymnasium environments over the chain (optional extra ``gym``): registered, normalised, vectorised.

::

    import gymnasium
    import snoworm.env                                   # registers "snoworm/Snoworm-v0"
    env = gymnasium.make("snoworm/Snoworm-v0", scenario="tow6_uniform", dt_s=0.1)
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    envs = gymnasium.make_vec("snoworm/Snoworm-v0", num_envs=64, vectorization_mode="vector_entry_point")

``gymnasium.make("snoworm.env:snoworm/Snoworm-v0")`` imports this package first (no separate
import needed).  ``import snoworm`` registers the id when gymnasium is already imported (it
imports this package then); otherwise not: it never imports gymnasium (or NumPy), so the command
line starts fast, and gymnasium 1.x has no plugin entry points (removed in 1.0) through which a
package could register without being imported.

* **Action** (:meth:`snoworm.env.core.EnvCore.physical_action`): a ``Box(-1, 1)`` of float32 holding the arrays of
  ``action_keys`` (command keys of :data:`snoworm.modes.command.COMMAND_KEYS`; default the
  wheel-speed set-points) in that order.  Each value ``a`` is clipped to [-1, 1] and mapped
  linearly onto the vehicle's physical range ``[lo, hi]``: ``lo + (a + 1) / 2 (hi - lo)`` with
  wheel speed ``[0, R_w w_no-load]``, torque ``+-`` the motor's limit, joint force ``+-`` its
  limit, joint extension its stroke.  The command is held for ``dt_s`` (zero-order hold).
* **Observation** (:meth:`snoworm.env.core.EnvCore.normalised`): a ``Box(-10, 10)`` of float32, the
  :data:`OBSERVATION_FIELDS` arrays of the :class:`~snoworm.modes.command.Observation` (the
  quantities of the results' tables), each divided by a scale of the vehicle or the scenario
  (:data:`OBSERVATION_SCALES`), then the time as a fraction of ``simulation.duration_s``; a value
  beyond 10 scales is clipped to the box.  ``env.observation`` is the physical Observation.
* **Reward** (:func:`default_reward`): progress of the chain's mean position in the step [m] minus
  ``energy_weight`` times the electrical energy the motors drew in it [J] (trapezoid rule on the
  scenario's output grid).  ``reward=`` names a preset of :data:`REWARD_PRESETS`:
  ``"efficiency"`` (default: the weight is 1 / the chain's weight m g, so the energy counts as the
  height it would lift the chain, and driving beats standing still wherever the cost of transport is
  below 1; ``energy_weight=`` sets another weight) or ``"distance"`` (progress only).  The single
  environment also takes ``reward=f(prev_obs, obs, info)``.
* **Terminated** when the chain is immobilised: its mean ground speed stays below
  ``stall_speed_mps`` for ``stall_time_s`` while a wheel command is held.  **Truncated** at
  ``simulation.duration_s`` (``max_episode_steps`` = ceil(duration / dt_s) steps).  Stepping on
  after either raises :class:`gymnasium.error.ResetNeeded` (the Gymnasium API: reset first).
* **Solver**: ``method="VODE"`` by default (the scenario's tolerances), restarted at a step whose
  command differs from the last one and carried on across a step that holds it
  (:meth:`snoworm.simulation.stepwise.Simulator.step`'s ``restart``): with random actions at dt 0.1 s,
  tow6 needs 104 right-hand-side evaluations per step, against 124 with VODE's history always
  carried on and 168 on LSODA (docs/controllers.md).
* **Copies**: both environments pickle and deep-copy (mid-episode too, VODE's history included):
  a copy steps on to the same observations as the original.
* **Memory**: an episode keeps only the last step (``Simulator(record=False)``); ``record=True``
  keeps every step for ``env.sim.result()``.  (On ``method="LSODA"`` memory grows anyway: scipy
  1.17.1's LSODA keeps the work arrays of every solver it creates, ~9 kB per step here.)

The native vector environment is :class:`snoworm.env.vector.SnowormVectorEnv`.  This package needs
``gymnasium`` (``pip install 'snoworm[gym]'``); nothing else in snoworm imports it.
"""

from __future__ import annotations

try:
    import gymnasium
except ImportError as exc:  # pragma: no cover - depends on the installed extras
    raise ImportError("snoworm.env needs gymnasium: pip install 'snoworm[gym]'") from exc

from .core import (
    DEFAULT_REWARD,
    ENV_ID,
    OBS_LIMIT,
    OBSERVATION_FIELDS,
    OBSERVATION_SCALES,
    REWARD_PRESETS,
    EnvCore,
    default_reward,
    table_fields,
)
from .single import SnowormEnv, make_env
from .vector import SnowormVectorEnv

__all__ = [
    "DEFAULT_REWARD",
    "ENV_ID",
    "SnowormEnv",
    "SnowormVectorEnv",
    "EnvCore",
    "OBSERVATION_FIELDS",
    "OBSERVATION_SCALES",
    "OBS_LIMIT",
    "REWARD_PRESETS",
    "default_reward",
    "make_env",
    "register",
    "table_fields",
]


def register() -> None:
    """Register :data:`ENV_ID` (done on import of this package; again is a no-op)."""
    if ENV_ID not in gymnasium.registry:
        gymnasium.register(
            id=ENV_ID,
            entry_point="snoworm.env.single:make_env",
            vector_entry_point="snoworm.env.vector:SnowormVectorEnv",
            kwargs={"scenario": "tow6_uniform"},
        )


register()
