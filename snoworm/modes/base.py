"""The mode contract: what a mobility mode provides, and the open registry of modes.

A mode turns its validated configuration into a sequence of integration intervals, each with
piecewise-constant :class:`~snoworm.model.inputs.Controls` and, optionally, state events that end
the interval (a gait phase change).  The physics never changes between modes (paper section 5:
the modes are controllers of the same chain).

A new mode is one module defining a :class:`~snoworm.config.mode_registry.ModeConfig` subclass (its
``mode:`` section, validated on construction) and a :class:`Mode` subclass naming it, registered
with :func:`register_mode` -- also from a user's own module, before the scenario is loaded.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field as dc_field
from typing import TYPE_CHECKING, Any, ClassVar, TypeVar

import numpy as np

from ..config.mode_registry import MODES, ModeConfig
from ..config.schema import ScenarioError
from ..model.inputs import Controls
from .codeload import allowed_paths

if TYPE_CHECKING:
    from numpy.typing import ArrayLike, NDArray

    from ..config.scenario import Scenario
    from ..model.chain import ChainModel

_M = TypeVar("_M", bound="type[Mode]")

__all__ = ["Mode", "Interval", "MODES", "register_mode", "mode_class", "build_mode", "start_times", "rolling_interval"]


@dataclass
class Interval:
    """One integration interval: controls held constant until ``t_end`` or an event.

    Attributes
    ----------
    t_end : float
        End time [s] (``inf``: until an event or the end of the run).
    controls : Controls
        The inputs held during the interval.
    events : list of callable
        Terminal state events ``ev(t, y) -> float`` (zero crossing ends the interval), each
        optionally with a ``direction`` attribute as in :func:`scipy.integrate.solve_ivp`.
    label : str
        A name for the interval (results' ``phases``, error messages).
    """

    t_end: float
    controls: Controls
    events: list[Callable[..., float]] = dc_field(default_factory=list)
    label: str = ""


class Mode:
    """Base class of mobility modes: every hook a mode may provide, with its default.

    Class attributes
    ----------------
    name : str
        The ``mode.type`` this mode answers to.
    config_class : type
        Its :class:`~snoworm.config.mode_registry.ModeConfig` subclass.
    continue_solver : bool
        Whether the solver may carry its history across the boundary between two intervals
        that meet at an interval's end time (``simulation.method: VODE`` only; default False:
        it restarts at every interval start).  Worth it where intervals are short control
        periods, as in the ``controller`` mode.
    steps_asked : bool
        Whether the intervals are steps the scenario asks for at fixed times (a controller's
        periods, bounded in number by its config): the work limit then allows each
        :data:`~snoworm.simulation.guard.WORK_NFEV_PER_INTERVAL` more, as a Simulator's steps.
        Default False: intervals that a mode's events or checks shorten must meet the limit alone.

    Parameters
    ----------
    cfg : ModeConfig
        The validated mode section.
    scenario : Scenario
        The whole scenario (data; ``cfg.prepare(scenario, model)`` makes the config's plan on the model).
    model : ChainModel
        The assembled chain (read its parameters; never change them).

    Hooks
    -----
    1. :meth:`initial_state` -- the state at t = 0 (default: the chain at rest).
    2. :meth:`interval` -- **required**: the controls from time ``t`` and state ``y`` on.
    3. :meth:`on_event` -- called when one of the interval's events ended it (required if
       :meth:`interval` returns events).
    4. :meth:`summary` -- mode-specific metrics for ``summary.json`` (default: none).

    Events worth reporting go to ``self.log`` as dicts with ``t_s``, ``kind`` and ``detail``.
    """

    name: ClassVar[str] = ""
    config_class: ClassVar[type[ModeConfig]] = ModeConfig
    continue_solver: ClassVar[bool] = False
    steps_asked: ClassVar[bool] = False
    runs_code: ClassVar[bool] = False

    def __init__(self, cfg: ModeConfig, scenario: Scenario, model: ChainModel) -> None:
        self.cfg = cfg
        self.scenario = scenario
        self.model = model
        self.log: list[dict[str, Any]] = []  # events: dicts with t_s, kind, detail

    def initial_state(self) -> NDArray[np.float64]:
        """State at t = 0 (flat); default: the chain at rest, joints at zero extension."""
        return self.model.initial_state()

    def interval(self, t: float, y: NDArray[np.float64]) -> Interval:
        """The interval starting at ``t`` in state ``y``."""
        raise NotImplementedError(f"mode {self.name!r} must implement interval(t, y)")

    def on_event(self, t: float, y: NDArray[np.float64], index: int) -> None:
        """Event ``index`` of the current interval's events ended it at ``t`` in state ``y``."""
        raise NotImplementedError(f"mode {self.name!r} returned events but does not implement on_event")

    def summary(self, result: Any) -> dict:
        """Mode-specific summary metrics (added to ``summary.json``) of ``result``, a
        :class:`snoworm.Result` (typed Any: the results layer sits above the modes)."""
        return {}


def register_mode(cls: _M) -> _M:
    """Register a :class:`Mode` subclass under ``cls.name`` (usable as a class decorator).

    Makes ``mode: {type: <name>, ...}`` in a scenario validate against ``cls.config_class`` and
    run with ``cls``: both read the one registry, :data:`snoworm.config.mode_registry.MODES`
    (also ``snoworm.modes.MODES``).
    """
    if not (isinstance(cls, type) and issubclass(cls, Mode)) or not cls.name:
        raise TypeError(f"register_mode needs a Mode subclass with a name, got {cls!r}")
    return MODES.register(cls)


def mode_class(cfg: ModeConfig) -> type[Mode]:
    """The :class:`Mode` subclass registered for a validated mode config."""
    return MODES[cfg.type]


def build_mode(
    cfg: ModeConfig, scenario: Scenario, model: ChainModel, allow_code: Iterable[str | os.PathLike[str]] = ()
) -> Mode:
    """A new instance of the mode of ``cfg`` for one run of ``scenario`` on ``model``.

    ``allow_code``: the paths whose controller code the user allowed (``--allow-code``,
    ``allow_code=``), handed only to a mode that runs the user's code (``runs_code``, the
    controller mode, which loads it through :mod:`snoworm.modes.codeload`); checked here for
    every mode (an empty path is a ScenarioError, :func:`~snoworm.modes.codeload.allowed_paths`).
    """
    allowed = allowed_paths(allow_code)
    cls = mode_class(cfg)
    if cls.runs_code:  # such a mode's __init__ takes allow_code (the controller mode's)
        return cls(cfg, scenario, model, allow_code=allowed)  # type: ignore[call-arg]
    return cls(cfg, scenario, model)


def refuse_failed_drivetrains(vehicle: Any, mode_name: str, why: str) -> None:
    """ScenarioError naming the first segment whose drivetrain has failed (docs/model.md section 4,
    "Failed drivetrain"), for a mode that plans every segment as driven (``why``: what it needs of them)."""
    for k, seg in enumerate(vehicle.segment_params()):
        if seg.drivetrain != "working":
            raise ScenarioError(
                f"vehicle.segment_overrides.{k}.drivetrain: the {mode_name} mode {why}, and segment {k}'s "
                "drivetrain has failed (no torque). Run a chain with a failed segment in mode 'uniform' or with "
                "a controller, or set its drivetrain to 'working'."
            )


def start_times(values: ArrayLike, n_segments: int, path: str = "mode.start_time_s") -> NDArray[np.float64]:
    """One start time for all segments, or one per segment, as an array of length N."""
    v = np.asarray(values, float)
    if v.size == 1:
        return np.full(n_segments, float(v.reshape(-1)[0]))
    if v.size != n_segments:
        raise ScenarioError(
            f"{path}: give one start time for all segments or {n_segments} (one per segment); got {v.size}."
        )
    return v


def rolling_interval(
    t: float, t_start: NDArray[np.float64], breaks: NDArray[np.float64], base: Controls, label: str
) -> Interval:
    """Motors on from each segment's start time: ``base`` with ``motor_on`` set, until the next start.

    Shared by the modes whose only switches are motor start times (uniform, force control); the
    integration restarts at every start time so no switch falls inside a solver step.
    """
    on = (t_start <= t + 1e-12).astype(float)
    later = breaks[breaks > t + 1e-12]
    t_end = float(later[0]) if later.size else np.inf
    return Interval(t_end, base.with_(motor_on=on), [], label)
