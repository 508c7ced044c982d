"""The scenario's mode section: the :class:`ModeConfig` base and the one registry of modes.

:data:`MODES` maps a ``mode.type`` to its mode class (a :class:`snoworm.modes.Mode` subclass
naming its :class:`ModeConfig` subclass): the config layer validates a ``mode:`` section with it
and the driver builds the mode from it.  :func:`snoworm.modes.register_mode` adds a mode; a
built-in mode's module, named in :data:`BUILT_IN_MODES`, is imported when its type is first
looked up (:class:`ModeRegistry`), since the modes sit above this layer.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any, ClassVar, TypeVar

from .schema import Config, ScenarioError, build, quote, suggest

__all__ = ["ModeConfig", "BUILT_IN_MODES", "ModeRegistry", "MODES", "build_mode_config"]


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
    #: the mode's name (each subclass declares it as its first field)
    type: str
    force_loop: ClassVar[bool] = False
    extra_plots: ClassVar[tuple[str, ...]] = ()

    @classmethod
    def resolve_paths(cls, raw: dict, base_dir: Path) -> dict:
        """The ``mode:`` mapping ``raw`` with its relative file paths taken from ``base_dir`` (the
        scenario file's folder), before validation; default: unchanged.  Called by
        :func:`snoworm.config.scenario.scenario_from_dict`, which knows the folder."""
        return raw

    def check_vehicle(self, vehicle: Any, path: str) -> None:
        """Rules that need the vehicle (e.g. one value per segment); raise ScenarioError."""

    def check_scenario(self, scenario: Any, path: str) -> None:
        """Rules that need the whole scenario (terrain, tow) but not its chain model; raise ScenarioError.

        Validation calls it: it must build no chain model and run no solver (a scenario is data)."""

    def prepare(self, scenario: Any, model: Any) -> Any:
        """What the mode needs of the assembled chain ``model`` (e.g. the force-control plan), or None.

        Called when a run is assembled (:func:`snoworm.simulation.driver.assemble`: the mode calls
        it once per run, in its ``__init__``) and by :func:`snoworm.simulation.driver.check_assembly`
        (``snoworm validate``); it runs no user code.  Raises ScenarioError if the scenario cannot
        run on that chain (e.g. a target it cannot carry).
        """
        return None

    def rolling_speed(self) -> float | None:
        """The wheel-speed set-point R_w*omega [m/s] this mode rolls at, or None (studies such as the
        mobility map ask it)."""
        return None

    def inching_settings(self) -> dict | None:
        """The inchworm settings (keys of the inchworm mode but ``type`` and ``start_time_s``) this
        mode inches with, or None."""
        return None

    def batch_signature(self) -> tuple | None:
        """A hashable description of the mode's intervals if it can run in a batched stack
        (event-free, the same intervals for every member with the same signature), else None."""
        return None


#: The built-in modes: ``type`` -> the module of :mod:`snoworm.modes` whose import registers it.
#: The one list of them: a new built-in mode adds its line here (docs/architecture.md).
BUILT_IN_MODES = {
    "controller": "snoworm.modes.controller",
    "force_control": "snoworm.modes.force_control",
    "inchworm": "snoworm.modes.inchworm",
    "supervisor": "snoworm.modes.supervisor",
    "uniform": "snoworm.modes.uniform",
}


_T = TypeVar("_T", bound=type)


class ModeRegistry(Mapping[str, Any]):
    """The registry of mobility modes: ``type`` -> the registered mode class.

    The one registry of modes: validation reads a mode's config class from it
    (``registry.config_class(type)``, the mode class's ``config_class``) and the driver its mode
    class (``registry[type]``, through :func:`snoworm.modes.mode_class`).  A built-in mode's module
    (:data:`BUILT_IN_MODES`) is imported the first time its type is looked up (all of them when
    the registry is listed), so ``import snoworm`` and the command line start without the modes
    (and SciPy), a run imports only its own mode, and a scenario finds every built-in mode from a
    fresh interpreter.  A user's mode is added by :meth:`register` (``snoworm.register_mode``),
    which imports nothing.  The modes sit above this layer, so built-in modes are named here by
    their module's dotted name, never imported statically.

    Parameters
    ----------
    built_in : dict
        ``type`` -> dotted name of the module whose import registers that built-in mode.
    """

    def __init__(self, built_in: dict):
        self._built_in: dict[str, str] = dict(built_in)
        self._d: dict[str, Any] = {}

    def _load(self, key: str) -> None:
        if key not in self._d and key in self._built_in:
            importlib.import_module(self._built_in[key])

    def __getitem__(self, key: str) -> Any:
        self._load(key)
        return self._d[key]

    def __iter__(self) -> Iterator[str]:
        for key in self._built_in:
            self._load(key)
        # built-in modes first, in a fixed order, then the user's in registration order
        return iter([k for k in self._built_in if k in self._d] + [k for k in self._d if k not in self._built_in])

    def __len__(self) -> int:
        return len(list(iter(self)))

    def __repr__(self) -> str:
        return f"ModeRegistry({dict(self.items())!r})"

    def register(self, mode_cls: _T) -> _T:
        """Register a mode class under its ``name`` (its ``config_class`` validates the section).

        The modes layer checks that ``mode_cls`` is a :class:`snoworm.modes.Mode` subclass
        (:func:`snoworm.modes.register_mode`); this checks what validation relies on.

        Raises
        ------
        TypeError
            If ``mode_cls`` is not a class with a non-empty ``name`` and a :class:`ModeConfig`
            subclass as ``config_class``.
        """
        name = getattr(mode_cls, "name", None) if isinstance(mode_cls, type) else None
        if not name or not isinstance(name, str):
            raise TypeError(f"register_mode needs a Mode subclass with a name, got {mode_cls!r}")
        cfg = getattr(mode_cls, "config_class", None)
        if not (isinstance(cfg, type) and issubclass(cfg, ModeConfig)):
            raise TypeError(f"mode {name!r}: its config_class must subclass snoworm.ModeConfig, got {cfg!r}")
        self._d[name] = mode_cls
        return mode_cls

    def unregister(self, name: str) -> None:
        """Remove a registered mode (a user's; a built-in one comes back when next looked up)."""
        self._d.pop(name, None)

    def config_class(self, name: str) -> type[ModeConfig]:
        """The :class:`ModeConfig` subclass that validates ``mode: {type: name, ...}`` (KeyError if unknown)."""
        return self[name].config_class


#: The registry of mobility modes (``mode.type`` -> mode class): the one both the scenario's
#: validation and the driver read.  ``snoworm.modes.MODES`` is this object.
MODES = ModeRegistry(BUILT_IN_MODES)


def build_mode_config(raw: Mapping[str, Any] | ModeConfig, path: str = "mode") -> ModeConfig:
    """Validate a ``mode`` mapping against the config class registered for its ``type`` (a made
    :class:`ModeConfig`, validated already, is returned as it is)."""
    if isinstance(raw, ModeConfig):
        return raw
    reg = MODES
    if not isinstance(raw, dict):
        raise ScenarioError(f"{path}: expected a mapping with a 'type' key ({', '.join(reg)}), got {quote(raw)}.")
    kind = raw.get("type")
    if kind is None:
        raise ScenarioError(f"{path}.type: is required but missing. Choose one of: {', '.join(reg)}.")
    if not isinstance(kind, str):
        raise ScenarioError(
            f"{path}.type: expected the name of a mode ({', '.join(reg)}), got {type(kind).__name__} {quote(kind)}."
        )
    if kind not in reg:
        raise ScenarioError(
            f"{path}.type: unknown mode {quote(kind)}.{suggest(kind, reg)} Known modes: {', '.join(reg)}."
        )
    return build(reg.config_class(kind), raw, path)
