"""The native vector environment as a stable-baselines3 ``VecEnv`` (optional extra ``rl``).

::

    pip install torch --index-url https://download.pytorch.org/whl/cpu   # CPU-only torch first
    pip install -e ".[rl]"                                               # gymnasium, stable-baselines3

    from stable_baselines3 import PPO
    from snoworm.env.sb3 import SB3VecEnv
    env = SB3VecEnv.make(64, scenario="tow6_uniform")        # or SB3VecEnv(SnowormVectorEnv(64, ...))
    model = PPO("MlpPolicy", env, device="cpu").learn(100_000)

stable-baselines3 steps a ``VecEnv`` with a *same-step* reset: a member whose episode ended in a
step returns the first observation of its next episode at once, its last one in
``infos[b]["terminal_observation"]`` and ``infos[b]["TimeLimit.truncated"]`` true when the episode
was cut short (time limit, or a solver failure) rather than ended by immobilisation.  Gymnasium's
vector API, which :class:`~snoworm.env.vector.SnowormVectorEnv` follows, resets such a member at the
*next* step (``AutoresetMode.NEXT_STEP``); :class:`SB3VecEnv` resets the ended members in the same
call (``reset(options={"reset_mask": done})``), so both see the same episodes.  Each member's
``infos[b]`` also holds ``t_s``, ``motor_energy_J`` and ``solver_failure`` (and ``solver_error``
for a failed member).  The members are one vector environment: ``get_attr`` returns its attribute
for every member, ``set_attr`` sets it for all members at once, ``env_method`` calls it once for all
members; per-member attributes and methods are refused with a ValueError.

This module imports stable-baselines3 (and so torch) when it is imported; nothing else in snoworm
does.
"""

from __future__ import annotations

from typing import Any

import numpy as np

try:
    from stable_baselines3.common.vec_env import VecEnv
except ImportError as exc:  # pragma: no cover - depends on the installed extras
    raise ImportError(
        "snoworm.env.sb3 needs stable-baselines3: pip install torch --index-url "
        "https://download.pytorch.org/whl/cpu, then pip install 'snoworm[rl]'"
    ) from exc

from .vector import SnowormVectorEnv

__all__ = ["SB3VecEnv"]


class SB3VecEnv(VecEnv):
    """A :class:`~snoworm.env.vector.SnowormVectorEnv` as stable-baselines3's ``VecEnv`` (see the
    module docstring).

    Parameters
    ----------
    venv : SnowormVectorEnv
        The native vector environment (not wrapped); it is reset by the first :meth:`reset`.
    """

    def __init__(self, venv: SnowormVectorEnv) -> None:
        if not isinstance(venv, SnowormVectorEnv):
            raise ValueError(
                f"venv: expected a snoworm.env.vector.SnowormVectorEnv, got {type(venv).__name__}; "
                "use SB3VecEnv.make(num_envs, **options) to build one"
            )
        self.venv = venv
        self._actions: np.ndarray | None = None
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)

    @classmethod
    def make(cls, num_envs: int, **options: Any) -> SB3VecEnv:
        """``SB3VecEnv(SnowormVectorEnv(num_envs, **options))``."""
        return cls(SnowormVectorEnv(num_envs, **options))

    def reset(self) -> np.ndarray:
        """Reset every member; the seed of :meth:`seed` (its first member's) seeds the vector env once."""
        obs, info = self.venv.reset(seed=self._seeds[0])
        self._reset_seeds()
        self._reset_options()
        self.reset_infos = [{"t_s": float(info["t_s"][b])} for b in range(self.num_envs)]
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions, np.float32)

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        if self._actions is None:
            raise RuntimeError("SB3VecEnv.step_wait: call step_async(actions) first")
        actions, self._actions = self._actions, None
        obs, rewards, terminated, truncated, info = self.venv.step(actions)
        done = terminated | truncated
        infos = self._infos(info)
        if done.any():
            for b in np.flatnonzero(done):
                infos[b]["terminal_observation"] = obs[b].copy()
                infos[b]["TimeLimit.truncated"] = bool(truncated[b] and not terminated[b])
            obs, _ = self.venv.reset(options={"reset_mask": done})
        return obs, rewards.astype(np.float32), done, infos

    def _infos(self, info: dict[str, Any]) -> list[dict[str, Any]]:
        """Gymnasium's vector info (arrays with ``_key`` masks) as one dict per member."""
        out: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        for key, values in info.items():
            if key.startswith("_"):
                continue
            mask = info.get("_" + key)
            for b in range(self.num_envs):
                if mask is None or mask[b]:
                    out[b][key] = values[b]
        return out

    def close(self) -> None:
        self.venv.close()

    def _all(self, indices: Any, what: str) -> list[int]:
        """The members of ``indices``; ValueError unless they are every member (one shared env)."""
        members = list(self._get_indices(indices))
        if sorted(members) != list(range(self.num_envs)):
            raise ValueError(
                f"{what}: the {self.num_envs} members are one vector environment; "
                f"give indices=None (every member), got {indices!r}"
            )
        return members

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        return [getattr(self.venv, attr_name)] * len(list(self._get_indices(indices)))

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        self._all(indices, "set_attr")
        setattr(self.venv, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any) -> list[Any]:
        members = self._all(indices, "env_method")
        out = getattr(self.venv, method_name)(*method_args, **method_kwargs)
        return [out] * len(members)

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [False] * len(list(self._get_indices(indices)))
