"""Mobility modes: controllers that drive the same chain physics (paper section 5).

A mode turns its validated configuration into a sequence of integration intervals, each with
piecewise-constant :class:`~snoworm.dynamics.Controls` and, optionally, state events that end
the interval (a gait phase change).  The physics never changes between modes.

Registry
--------
``MODES`` maps the scenario's ``mode.type`` to ``(ConfigClass, ModeClass)``.  A new mode is a
module in this package with a frozen config dataclass (validated by :mod:`snoworm.schema`) and a
subclass of :class:`Mode`, added to ``MODES``.
"""
from __future__ import annotations

from dataclasses import dataclass, field as dc_field
import numpy as np

from ..schema import ScenarioError, build, suggest

__all__ = ["Mode", "Interval", "MODES", "build_config", "mode_class", "start_times"]


@dataclass
class Interval:
    """One integration interval: controls held constant until ``t_end`` or an event."""

    t_end: float
    controls: object
    events: list = dc_field(default_factory=list)
    label: str = ""


class Mode:
    """Base class of mobility modes.

    Subclasses set ``force_loop`` when they need the outer force-loop integrators in the state,
    and implement :meth:`interval`; event-driven modes also implement :meth:`on_event`.
    """

    #: whether the chain state carries the outer force-loop integrators
    force_loop = False

    def __init__(self, cfg, scenario, model):
        self.cfg = cfg
        self.scenario = scenario
        self.model = model
        self.log = []   # events: dicts with t_s, kind, detail

    def initial_state(self) -> np.ndarray:
        return self.model.initial_state()

    def interval(self, t: float, y: np.ndarray) -> Interval:  # pragma: no cover - abstract
        raise NotImplementedError

    def on_event(self, t: float, y: np.ndarray, index: int) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def summary(self, result) -> dict:
        """Mode-specific summary metrics (added to ``summary.json``)."""
        return {}


def start_times(values, n_segments, path="mode.start_time_s"):
    """One start time for all segments, or one per segment, as an array of length N."""
    v = np.asarray(values, float)
    if v.size == 1:
        return np.full(n_segments, float(v.reshape(-1)[0]))
    if v.size != n_segments:
        raise ScenarioError(f"{path}: give one start time for all segments or {n_segments} (one per segment); "
                            f"got {v.size}.")
    return v


def _registry():
    from . import force_control, inchworm, supervisor, uniform
    return {
        "uniform": (uniform.UniformConfig, uniform.UniformMode),
        "force_control": (force_control.ForceControlConfig, force_control.ForceControlMode),
        "inchworm": (inchworm.InchwormConfig, inchworm.InchwormMode),
        "supervisor": (supervisor.SupervisorConfig, supervisor.SupervisorMode),
    }


MODES: dict = {}


def _modes():
    if not MODES:
        MODES.update(_registry())
    return MODES


def build_config(raw, vehicle):
    """Validate the scenario's ``mode`` section against the config class of its ``type``."""
    reg = _modes()
    if not isinstance(raw, dict):
        raise ScenarioError(f"mode: expected a mapping with a 'type' key ({', '.join(reg)}), got {raw!r}.")
    kind = raw.get("type")
    if kind is None:
        raise ScenarioError(f"mode.type: is required but missing. Choose one of: {', '.join(reg)}.")
    if kind not in reg:
        raise ScenarioError(f"mode.type: unknown mode {kind!r}.{suggest(kind, reg)} Known modes: {', '.join(reg)}.")
    cfg_cls, _ = reg[kind]
    cfg = build(cfg_cls, raw, "mode")
    check = getattr(cfg, "check_vehicle", None)
    if check is not None:
        check(vehicle, "mode")
    return cfg


def mode_class(cfg):
    """The :class:`Mode` subclass for a validated mode config."""
    return _modes()[cfg.type][1]
