"""What the single and the vector environment share (:mod:`snoworm.env`): options, spaces, the
map from normalised actions to commands, the normalised observation and the motors' energy."""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from gymnasium import spaces

from ..config.scenario import Scenario, load_scenario
from ..config.schema import quote
from ..modes.command import Observation, observed_fields
from ..simulation.driver import chain_model
from ..simulation.stepwise import DT_MIN_S

if TYPE_CHECKING:
    from numpy.typing import ArrayLike, NDArray

#: ``reward(prev_obs, obs, info) -> float`` (:func:`default_reward` is one).
RewardFunction = Callable[[Observation, Observation, dict[str, Any]], float]

__all__ = [
    "DEFAULT_REWARD",
    "ENV_ID",
    "EnvCore",
    "OBSERVATION_FIELDS",
    "OBSERVATION_SCALES",
    "OBS_LIMIT",
    "REWARD_PRESETS",
    "default_reward",
    "table_fields",
]

#: The registered id (``gymnasium.make(ENV_ID, scenario=...)``).
ENV_ID = "snoworm/Snoworm-v0"

#: Observation arrays in the order they fill the observation vector (then ``t_s / duration_s``):
#: the :class:`~snoworm.modes.command.Observation`'s fields but ``t_s``.
OBSERVATION_FIELDS = Observation.FIELDS[1:]

#: The scale each field is divided by (names of :meth:`EnvCore.scales`): ``distance`` = the fastest
#: no-load wheel speed times ``duration_s``, ``speed`` = the fastest no-load wheel speed R_w w_nl,
#: ``torque`` = each motor's torque limit, ``weight`` = the chain's weight, ``spacing`` = each link's
#: rest spacing, ``stroke`` = each joint's largest stroke (1 m for fixed links), ``right_angle`` =
#: 90 deg (a grade maps into [-1, 1]), ``one`` = 1.
OBSERVATION_SCALES = {
    "x_m": "distance",
    "v_mps": "speed",
    "wheel_speed_mps": "speed",
    "slip": "one",
    "motor_torque_Nm": "torque",
    "xt": "one",
    "grade_deg": "right_angle",
    "link_force_N": "weight",
    "link_length_m": "spacing",
    "joint_extension_m": "stroke",
}

#: Bound of every normalised observation value (values beyond are clipped).
OBS_LIMIT = 10.0

_PAIRS = (("wheel_speed_mps", "wheel_torque_Nm"), ("joint_force_N", "joint_length_m"))


#: The reward presets (``reward=`` of both environments), each a weight of the motors' energy in
#: :func:`default_reward` (progress [m] minus the weight times the energy [J]):
#:
#: * ``"efficiency"`` (the default): the weight is 1 / (the chain's weight m g [N]) unless
#:   ``energy_weight`` is given, so the energy is charged as the height [m] it would lift the chain:
#:   driving pays while the cost of transport E / (m g d) is below 1 (tow6: 0.51-0.54 at every
#:   constant set-point, so driving beats standing still, and faster pays more).
#: * ``"distance"``: progress only (weight 0; ``energy_weight`` is refused).
#:
#: A fixed weight such as the 1e-3 per J of the environments before issue 34 depends on the vehicle:
#: on tow6 (5 297 N, ~2 800 J/m) any weight above ~1/2 900 per J makes standing still pay best.
REWARD_PRESETS = ("efficiency", "distance")
#: The reward preset of both environments by default.
DEFAULT_REWARD = "efficiency"


def default_reward(prev_obs: Observation, obs: Observation, info: Mapping[str, Any], energy_weight: float) -> float:
    """Progress of the chain's mean position [m] minus ``energy_weight`` times the motors' energy
    ``info["motor_energy_J"]`` [J]: the reward of every preset of :data:`REWARD_PRESETS`, with its
    weight (:attr:`EnvCore.energy_weight`)."""
    return float(np.mean(obs.x_m) - np.mean(prev_obs.x_m)) - energy_weight * info["motor_energy_J"]


def _resolve(scenario: Scenario | str | os.PathLike[str]) -> Scenario:
    """A Scenario from a Scenario, a shipped scenario's name or a path."""
    if isinstance(scenario, Scenario):
        return scenario
    if isinstance(scenario, str) or hasattr(scenario, "__fspath__"):
        return load_scenario(scenario)
    raise ValueError(f"scenario: expected a Scenario, a shipped scenario's name or a path, got {scenario!r}")


def _number(name: str, value: Any, rule: str, ok: Callable[[Any], bool]) -> float:
    """``value`` as a float if finite and ``ok(value)``; else ValueError naming ``name`` and ``rule``."""
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float, np.integer, np.floating))
        or not math.isfinite(value)
        or not ok(value)
    ):
        raise ValueError(f"{name}: must be {rule}, got {value!r}")
    return float(value)


class EnvCore:
    """What the single and the vector environment share: options, spaces, action and observation maps.

    Parameters
    ----------
    scenario : Scenario, str or path
        The scenario (a shipped name such as ``"tow6_uniform"``, or a YAML path); its mode gives
        only the initial state.
    dt_s : float
        How long each action is held [s], at least :data:`~snoworm.simulation.stepwise.DT_MIN_S` (1 us).
    action_keys : sequence of str
        Command keys that make up the action (not both keys of a pair such as
        ``wheel_speed_mps`` and ``wheel_torque_Nm``).
    energy_weight : float or None
        Weight of the motors' electrical energy in the reward [m per J], >= 0; None: the preset's
        (:data:`REWARD_PRESETS`; 1 / (m g) for ``"efficiency"``).
    reward : str
        A preset of :data:`REWARD_PRESETS` (default :data:`DEFAULT_REWARD`): the weight of the
        energy when ``energy_weight`` is None.  (The single environment also takes a callable,
        :class:`~snoworm.env.single.SnowormEnv`, and then passes ``"efficiency"`` here.)
    stall_speed_mps, stall_time_s : float
        Immobilisation test: mean speed below ``stall_speed_mps`` (>= 0) for ``stall_time_s`` (> 0).
    """

    def __init__(
        self,
        scenario: Scenario | str | os.PathLike[str],
        dt_s: float = 0.1,
        action_keys: str | Sequence[str] = ("wheel_speed_mps",),
        energy_weight: float | None = None,
        stall_speed_mps: float = 0.01,
        stall_time_s: float = 2.0,
        reward: str = DEFAULT_REWARD,
    ) -> None:
        self.scenario = _resolve(scenario)
        self.dt_s = _number("dt_s", dt_s, f"a number of seconds >= {DT_MIN_S:g}", lambda v: v >= DT_MIN_S)
        if not isinstance(reward, str) or reward not in REWARD_PRESETS:
            raise ValueError(
                f"reward: expected one of the presets {', '.join(map(repr, REWARD_PRESETS))} "
                f"(or, for the single environment, a callable reward(prev_obs, obs, info)), got {quote(reward, 60)}"
            )
        if energy_weight is not None:
            energy_weight = _number("energy_weight", energy_weight, "a finite number >= 0 [m per J]", lambda v: v >= 0)
            if reward == "distance":
                raise ValueError(
                    f'energy_weight: reward="distance" does not charge the energy; got {energy_weight!r}, '
                    'leave it out or use reward="efficiency"'
                )
        self.reward = reward
        self.stall_speed_mps = _number(
            "stall_speed_mps", stall_speed_mps, "a finite speed >= 0 [m/s]", lambda v: v >= 0
        )
        self.stall_time_s = _number("stall_time_s", stall_time_s, "a positive number of seconds", lambda v: v > 0)
        if isinstance(action_keys, str):
            action_keys = (action_keys,)
        self.action_keys = tuple(action_keys)
        self.model = chain_model(self.scenario)  # built once per environment
        self.duration_s = float(self.scenario.simulation.duration_s)
        #: steps until truncation: the first step whose end reaches ``simulation.duration_s``
        self.max_episode_steps = max(1, math.ceil(self.duration_s / self.dt_s - 1e-9))
        #: the weight of the motors' energy in the reward [m per J] (:data:`REWARD_PRESETS`)
        self.energy_weight = 0.0 if reward == "distance" else 1.0 / self.scales()["weight"]
        if energy_weight is not None:
            self.energy_weight = float(energy_weight)
        self.low, self.high, self.sizes = self._action_bounds()
        self.scale = self._observation_scale()
        n_act, n_obs = self.low.size, self.scale.size + 1
        self.single_action_space = spaces.Box(-1.0, 1.0, shape=(n_act,), dtype=np.float32)
        self.single_observation_space = spaces.Box(-OBS_LIMIT, OBS_LIMIT, shape=(n_obs,), dtype=np.float32)

    def _action_bounds(self) -> tuple[NDArray[np.float64], NDArray[np.float64], list[int]]:
        model = self.model
        seg, links, n = model.seg, model.links, model.n
        bounds = {
            "wheel_speed_mps": (np.zeros(n), seg.no_load_speed_radps * seg.wheel_radius_m),
            "wheel_torque_Nm": (-seg.torque_limit_Nm, seg.torque_limit_Nm),
            "joint_force_N": (-links.force_max_N, links.force_max_N),
            "joint_length_m": (links.stroke_min_m, links.stroke_max_m),
        }
        if not self.action_keys:
            raise ValueError(f"action_keys: give at least one of {', '.join(bounds)}")
        for key in self.action_keys:
            if key not in bounds:
                raise ValueError(f"action_keys: {key!r} cannot be an action; choose among {', '.join(bounds)}")
            if key.startswith("joint_") and not model.has_joints:
                raise ValueError(f"action_keys: {key!r} needs a vehicle with prismatic joints")
        if len(set(self.action_keys)) != len(self.action_keys):
            raise ValueError(f"action_keys: {self.action_keys!r} names a key twice")
        for a, b in _PAIRS:
            if a in self.action_keys and b in self.action_keys:
                raise ValueError(f"action_keys: {a!r} and {b!r} command the same actuator; give one of them")
        lo = [np.asarray(bounds[k][0], float) for k in self.action_keys]
        hi = [np.asarray(bounds[k][1], float) for k in self.action_keys]
        return np.concatenate(lo), np.concatenate(hi), [a.size for a in lo]

    def scales(self) -> dict:
        """The physical scales of :data:`OBSERVATION_SCALES` (arrays per segment or link, or floats)."""
        seg, links = self.model.seg, self.model.links
        vnl = float(np.max(seg.no_load_speed_radps * seg.wheel_radius_m))
        stroke = np.maximum(np.abs(links.stroke_min_m), np.abs(links.stroke_max_m))
        return {
            "distance": vnl * self.duration_s,
            "speed": vnl,
            "torque": np.asarray(seg.torque_limit_Nm, float),
            "weight": float(np.sum(seg.mass_kg * seg.gravity_mps2)),
            "one": 1.0,
            "right_angle": 90.0,
            "spacing": np.asarray(links.rest_spacing_m, float),
            "stroke": np.where(links.prismatic > 0, np.where(stroke > 0, stroke, 1.0), 1.0),
        }

    def _observation_scale(self) -> NDArray[np.float64]:
        sc, n = self.scales(), self.model.n
        sizes = {f: (n - 1 if f.startswith(("link_", "joint_")) else n) for f in OBSERVATION_FIELDS}
        return np.concatenate([np.broadcast_to(sc[OBSERVATION_SCALES[f]], (sizes[f],)) for f in OBSERVATION_FIELDS])

    def physical_action(self, action: ArrayLike, batch: int | None = None) -> dict[str, NDArray[np.float64]]:
        """The command mapping of normalised actions (shape ``(n,)``, or ``(batch, n)``), clipped to [-1, 1].

        Raises ValueError for a wrong shape (a scalar is not broadcast), a complex or a non-finite value.
        """
        shape = self.single_action_space.shape if batch is None else (batch,) + self.single_action_space.shape
        try:
            a = np.asarray(action)
            real = a.dtype.kind != "c"
            a = a.astype(float) if real else a
        except (TypeError, ValueError):
            raise ValueError(f"action: expected numbers in [-1, 1] of shape {shape}, got {quote(action, 60)}") from None
        if not real:
            raise ValueError(
                f"action: expected real numbers in [-1, 1], got complex values {quote(action, 60)}; "
                "pass the real part (np.real) if that is what you mean"
            )
        if a.shape != shape:
            raise ValueError(f"action: expected an array of shape {shape} in [-1, 1], got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError("action: every value must be finite (NaN or inf given)")
        phys = self.low + (np.clip(a, -1.0, 1.0) + 1.0) * 0.5 * (self.high - self.low)
        cmd, j = {}, 0
        for key, size in zip(self.action_keys, self.sizes):
            cmd[key] = phys[..., j : j + size]
            j += size
        return cmd

    def normalised(self, fields: Mapping[str, ArrayLike], t_s: ArrayLike) -> NDArray[np.float32]:
        """The float32 observation vector(s) of ``fields`` (name -> array ``(..., N)`` or ``(..., N-1)``
        for each of :data:`OBSERVATION_FIELDS`, e.g. :func:`table_fields`) at time(s) ``t_s``."""
        v = np.concatenate([fields[f] for f in OBSERVATION_FIELDS], axis=-1) / self.scale
        t = np.broadcast_to(np.asarray(t_s, float) / self.duration_s, v.shape[:-1])[..., None]
        return np.clip(np.concatenate([v, t], axis=-1), -OBS_LIMIT, OBS_LIMIT).astype(np.float32)

    def energy_J(
        self, ts: NDArray[np.float64], seg: Mapping[str, NDArray[np.float64]]
    ) -> np.float64 | NDArray[np.float64]:
        """Motors' electrical energy over a step [J]: trapezoid rule on the samples ``ts`` (per member)."""
        p = seg["motor_electrical_power_W"].sum(-1)
        dt = np.diff(ts).reshape((-1,) + (1,) * (p.ndim - 1))
        return np.sum(0.5 * (p[1:] + p[:-1]) * dt, axis=0)


def table_fields(seg: Mapping[str, Any], lk: Mapping[str, Any], row: int = -1) -> dict[str, Any]:
    """The :data:`OBSERVATION_FIELDS` arrays at sample ``row`` of output tables ``seg, lk``
    (:func:`snoworm.model.quantities.output_series`)."""
    return observed_fields(seg, lk, row)
