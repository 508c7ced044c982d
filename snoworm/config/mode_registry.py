"""The scenario's mode section: the :class:`ModeConfig` base and the registry of mode types.

The config layer validates a ``mode:`` section without importing the modes (they sit above it):
:data:`MODE_CONFIGS` maps a ``type`` to its config class, filled by
:func:`snoworm.modes.register_mode` (through :func:`register_mode_config`); a built-in mode's
module, named in :data:`BUILT_IN_MODES`, is imported when its type is first looked up
(:class:`ModeRegistry`).
"""
from __future__ import annotations

import importlib
from collections.abc import MutableMapping

from .schema import Config, ScenarioError, build, quote, suggest

__all__ = ["ModeConfig", "BUILT_IN_MODES", "ModeRegistry", "MODE_CONFIGS", "register_mode_config", "build_mode_config"]


class ModeConfig(Config):
    """Base of a mobility mode's configuration (the scenario's ``mode`` section).

    Every hook a mode's configuration may provide is declared here with its default; a mode
    (:class:`snoworm.modes.Mode`) names its config class, and registering the mode registers the
    config for its ``type``.

    Attributes
    ----------
    force_loop : bool
        Whether the chain state carries the outer force-loop integrators (``q_mps``).
    extra_plots : tuple of str
        Names of extra figures drawn for this mode (keys of ``snoworm.plotting.PLOT_KINDS``).
    """

    _section = "mode"
    force_loop = False
    extra_plots = ()

    def check_vehicle(self, vehicle, path):
        """Rules that need the vehicle (e.g. one value per segment); raise ScenarioError."""

    def check_scenario(self, scenario, path):
        """Rules that need the whole scenario (terrain, tow); raise ScenarioError."""

    def prepare(self, scenario):
        """A plan computed once per scenario (e.g. force-control targets), or None.

        Available to the mode as ``scenario.mode_plan``; computed at most once per scenario.
        """
        return None

    def rolling_speed(self):
        """The wheel-speed set-point R_w*omega [m/s] this mode rolls at, or None (studies such as the
        mobility map ask it)."""
        return None

    def inching_settings(self):
        """The inchworm settings (keys of the inchworm mode but ``type`` and ``start_time_s``) this
        mode inches with, or None."""
        return None

    def batch_signature(self):
        """A hashable description of the mode's intervals if it can run in a batched stack
        (event-free, the same intervals for every member with the same signature), else None."""
        return None


#: The built-in modes: ``type`` -> the module whose import registers it (:mod:`snoworm.modes`).
BUILT_IN_MODES = {"controller": "snoworm.modes.controller", "force_control": "snoworm.modes.force_control",
                  "inchworm": "snoworm.modes.inchworm", "supervisor": "snoworm.modes.supervisor",
                  "uniform": "snoworm.modes.uniform"}


class ModeRegistry(MutableMapping):
    """A dict of mode ``type`` -> class that imports a built-in mode's module the first time the
    mode is looked up (all of them when the registry is listed).

    :data:`MODE_CONFIGS` (config classes) and ``snoworm.modes.MODES`` (mode classes)
    are two; ``register_mode`` fills both.  So ``import snoworm`` and the command line start
    without the modes (and SciPy), a run imports only its own mode, and a scenario still finds
    every built-in mode.  Writing (registering a mode) imports nothing.

    Parameters
    ----------
    built_in : dict
        ``type`` -> dotted name of the module whose import registers that built-in mode.
    """

    def __init__(self, built_in: dict):
        self._built_in, self._d = dict(built_in), {}

    def _load(self, key):
        if key not in self._d and key in self._built_in:
            importlib.import_module(self._built_in[key])

    def __getitem__(self, key):
        self._load(key)
        return self._d[key]

    def __iter__(self):
        for key in self._built_in:
            self._load(key)
        # built-in modes first, in a fixed order, then the user's in registration order
        return iter([k for k in self._built_in if k in self._d] + [k for k in self._d if k not in self._built_in])

    def __len__(self):
        return len(list(iter(self)))

    def __setitem__(self, key, value):
        self._d[key] = value

    def __delitem__(self, key):
        del self._d[key]

    def __repr__(self):
        return f"ModeRegistry({dict(self.items())!r})"


#: The scenario's ``mode.type`` -> its :class:`ModeConfig` subclass.  Filled by
#: :func:`snoworm.modes.register_mode`; a built-in mode's module is imported (by name: the modes sit
#: above this layer) when the mode is first looked up.
MODE_CONFIGS = ModeRegistry(BUILT_IN_MODES)


def register_mode_config(name: str, cls) -> None:
    """Make ``mode: {type: name, ...}`` validate against the config class ``cls``."""
    if not (isinstance(cls, type) and issubclass(cls, ModeConfig)):
        raise TypeError(f"a mode config must subclass snoworm.ModeConfig, got {cls!r}")
    MODE_CONFIGS[name] = cls


def build_mode_config(raw, path="mode") -> ModeConfig:
    """Validate a ``mode`` mapping against the config class registered for its ``type``."""
    reg = MODE_CONFIGS
    if not isinstance(raw, dict):
        raise ScenarioError(f"{path}: expected a mapping with a 'type' key ({', '.join(reg)}), got {quote(raw)}.")
    kind = raw.get("type")
    if kind is None:
        raise ScenarioError(f"{path}.type: is required but missing. Choose one of: {', '.join(reg)}.")
    if not isinstance(kind, str):
        raise ScenarioError(f"{path}.type: expected the name of a mode ({', '.join(reg)}), got "
                            f"{type(kind).__name__} {quote(kind)}.")
    if kind not in reg:
        raise ScenarioError(f"{path}.type: unknown mode {quote(kind)}.{suggest(kind, reg)} Known modes: {', '.join(reg)}.")
    return build(reg[kind], raw, path)
