"""Uniform wheel-speed mode: every segment drives at a wheel-speed set-point (paper Figs 6-7).

The simplest way to drive the chain, "without using the inter-segment forces as a control
input" (paper section 5.2).  Each segment's motors switch on at its start time; the
integration restarts there so the switch never falls inside a solver step.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..config.mode_registry import ModeConfig
from ..config.schema import ScenarioError, field
from ..config.sections import FINITE_WHY
from ..model.inputs import Controls
from .base import Interval, Mode, register_mode, rolling_interval, start_times

if TYPE_CHECKING:
    from numpy.typing import NDArray

    from ..config.scenario import Scenario
    from ..config.sections import VehicleConfig
    from ..model.chain import ChainModel

__all__ = ["UniformConfig", "UniformMode"]


@dataclass(frozen=True)
class UniformConfig(ModeConfig):
    """``mode: {type: uniform, speed_mps: ..., start_time_s: ...}``."""

    type: str = field(choices=("uniform",), doc="mode name")
    speed_mps: tuple[float, ...] = field(
        ge=0,
        le=100,
        why=FINITE_WHY,
        unit="m/s",
        doc="wheel-speed set-point R_w*omega, one for all segments or one per segment",
    )
    start_time_s: tuple[float, ...] = field(
        ge=0, le=1e5, unit="s", doc="motor start time, one for all or one per segment"
    )

    def check_vehicle(self, vehicle: VehicleConfig, path: str) -> None:
        start_times(self.start_time_s, vehicle.segments, f"{path}.start_time_s")
        if len(self.speed_mps) not in (1, vehicle.segments):
            raise ScenarioError(
                f"{path}.speed_mps: give one speed for all segments or {vehicle.segments}; got {len(self.speed_mps)}."
            )

    def rolling_speed(self) -> float:
        """The first segment's set-point [m/s]."""
        return float(self.speed_mps[0])

    def batch_signature(self) -> tuple:
        """Members with the same start times have the same intervals (speeds may differ)."""
        return ("uniform", tuple(self.start_time_s))


@register_mode
class UniformMode(Mode):
    """Drive every segment at its wheel-speed set-point from its start time on."""

    name = "uniform"
    config_class = UniformConfig

    def __init__(self, cfg: UniformConfig, scenario: Scenario, model: ChainModel) -> None:
        super().__init__(cfg, scenario, model)
        n = model.n
        self.t_start = start_times(cfg.start_time_s, n)
        self.speed = np.asarray(cfg.speed_mps, float) * np.ones(n)
        self.breaks = np.unique(self.t_start)
        self.base = Controls.rolling(n, np.zeros(n), self.speed)

    def interval(self, t: float, y: NDArray[np.float64]) -> Interval:
        return rolling_interval(t, self.t_start, self.breaks, self.base, "rolling")
