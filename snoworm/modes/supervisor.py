"""Supervisor mode: roll while the terrain allows it, inch through what immobilises rolling.

Beyond the paper: its section 5 describes rolling (5.2) and inching (5.1) as separate modes;
this supervisor switches between them automatically along a route whose terrain coefficient
X_t changes (paper section 3: X_t is "location dependent").

Rolling
-------
Every segment drives its wheels at ``rolling_speed_mps`` (the uniform mode, paper Figs 6-7);
the prismatic joints hold their length (``Controls.rolling``).  The chain starts with the joints
at the inchworm gait's initial extensions, so the gait can start at any moment.

Immobilisation rule (rolling -> inching)
----------------------------------------
The integration restarts every ``check_interval_s`` while rolling (fixed re-evaluation
intervals, not state events: the rule needs the position history, which a state event
function of ``(t, y)`` cannot see).  At each re-evaluation time ``t`` the chain is declared
immobilised when, after at least ``stuck_window_s`` of rolling,

* the mean ground speed of the chain over the last ``stuck_window_s``,
  ``(xbar(t) - xbar(t - window)) / window``, is below ``stuck_speed_mps``, and
* the leader's wheel slip (Eq. 1, regularised, mean of its axles) exceeds ``stuck_slip``
  (its wheels spin: it is immobilised, not merely stopped).

The supervisor then starts the inchworm gait (an :class:`~snoworm.modes.inchworm.InchwormMode`
built from the ``inching`` settings; its phases and joint force loops are reused unchanged).

Resume rule (inching -> rolling)
--------------------------------
At the end of every complete gait cycle (joints back at their initial extensions) the
supervisor checks the steady rolling feasibility of the whole chain at its current position:

    D_avail = sum over segments k and axles a of  max_drawbar_N(X_t(x_k,a)) / 2  -  F_tow

with ``max_drawbar_N`` the steady-state largest drawbar of a segment on uniform terrain
(:func:`snoworm.steady.max_drawbar_N`, docs/model.md section 2; an axle carries half a segment).
Rolling resumes when ``D_avail >= resume_margin_N``: the segments on good snow can drag those
still on the bad patch and the tow.  A chain on uniform snow with no tow resumes exactly when
X_t is above the immobilisation limit (0.586 for FrostyBoy) by a margin set by
``resume_margin_N``.

Every switch is an event in ``mode.log`` (``kind`` = ``switch_to_inching`` or
``switch_to_rolling``, with time, leader position and cause).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .. import terrain
from ..config.mode_registry import ModeConfig
from ..config.schema import ScenarioError, build, field
from ..config.sections import FINITE_WHY
from ..model.inputs import Controls
from .base import Interval, Mode, register_mode
from .inchworm import InchwormConfig, InchwormMode

if TYPE_CHECKING:
    from numpy.typing import ArrayLike, NDArray

    from ..config.scenario import Scenario
    from ..config.sections import SegmentConfig, VehicleConfig
    from ..model.chain import ChainModel

__all__ = ["SupervisorConfig", "SupervisorMode", "chain_drawbar_surplus_N"]


@dataclass(frozen=True)
class SupervisorConfig(ModeConfig):
    """``mode: {type: supervisor, rolling_speed_mps: ..., inching: {...}, ...}``."""

    type: str = field(choices=("supervisor",), doc="mode name")
    rolling_speed_mps: float = field(
        gt=0, le=100, why=FINITE_WHY, unit="m/s", doc="wheel-speed set-point R_w*omega while rolling"
    )
    start_time_s: float = field(ge=0, le=1e5, unit="s", doc="motor start time (motors off before)")
    check_interval_s: float = field(
        gt=0, le=1e5, unit="s", doc="re-evaluation period of the immobilisation rule while rolling"
    )
    stuck_window_s: float = field(gt=0, le=1e5, unit="s", doc="window of the mean chain ground speed")
    stuck_speed_mps: float = field(gt=0, le=100, unit="m/s", doc="immobilised if the window's mean speed is below this")
    stuck_slip: float = field(gt=0, le=1, doc="... and the leader's wheel slip is above this")
    resume_margin_N: float = field(
        ge=0, le=1e6, unit="N", doc="resume rolling when the chain's steady drawbar surplus is at least this"
    )
    inching: dict = field(doc="inchworm settings (the keys of the inchworm mode except type and start_time_s)")

    def inching_config(self, path: str = "mode") -> InchwormConfig:
        """The :class:`InchwormConfig` used while inching (started at once: ``start_time_s = 0``)."""
        raw = self.inching
        if not isinstance(raw, dict):
            raise ScenarioError(
                f"{path}.inching: expected a mapping of inchworm settings (gait, target_speed_mps, "
                f"mover_wheel_speed_mps, speed_gain_Ns_per_m, hold_margin), got {raw!r}."
            )
        for key in ("type", "start_time_s"):
            if key in raw:
                raise ScenarioError(
                    f"{path}.inching.{key}: not allowed here; the supervisor sets it (inching starts "
                    "when the supervisor detects immobilisation)."
                )
        return build(InchwormConfig, {**raw, "type": "inchworm", "start_time_s": 0.0}, f"{path}.inching")

    def rolling_speed(self) -> float:
        return float(self.rolling_speed_mps)

    def inching_settings(self) -> dict[str, Any]:
        return dict(self.inching)

    def _check(self, path: str) -> None:
        self.inching_config(path)
        if self.stuck_window_s < self.check_interval_s:
            raise ScenarioError(
                f"{path}.stuck_window_s: must be at least check_interval_s ({self.check_interval_s} s), "
                f"got {self.stuck_window_s} s."
            )

    def check_vehicle(self, vehicle: VehicleConfig, path: str) -> None:
        self.inching_config(path).check_vehicle(vehicle, f"{path}.inching")


def chain_drawbar_surplus_N(
    model: ChainModel, segments: Sequence[SegmentConfig], x_m: ArrayLike, wheel_speed_mps: float
) -> float:
    """Steady drawbar the chain could develop rolling at its current position, minus the tow [N].

    ``sum_k sum_axles max_drawbar_N(X_t(axle), grade_k) / 2 - F_tow`` (docs/model.md section 2 per-segment
    maximum drawbar, on the grade under the segment of section 7; each axle carries half a segment; F_tow
    the tow's steady pull, :func:`snoworm.steady.tow_drawbar_N`, a sled's at the rear segment's grade).
    Positive: the chain can roll.

    Parameters
    ----------
    model : ChainModel
        The assembled chain (profile, terrain coefficients, axle offsets, tow).
    segments : list of SegmentConfig
        Per-segment parameters (``VehicleConfig.segment_params()``).
    x_m : array_like (N,)
        Segment positions [m].
    wheel_speed_mps : float
        Rolling wheel-speed set-point [m/s].
    """
    from .. import steady  # root finding (scipy.optimize, slow to import): loaded by a run, not by validation

    X = model.xt_at_axles(x_m)
    grade = np.degrees(np.arcsin(model.grade_terms(x_m)[0]))  # the grade under each segment (section 7)
    total = 0.0
    for k, seg in enumerate(segments):
        for a in range(X.shape[1]):
            total += 0.5 * steady.max_drawbar_N(
                float(X[k, a]), seg, model.tp, wheel_speed_mps, grade_deg=float(grade[k])
            )
    # the tow's steady pull, a sled's at the rear segment's grade included (docs/model.md section 4, "Towed load")
    return total - steady.tow_drawbar_N(  # one chain: the supervisor never runs stacked
        cast(float, model.tow_force_N),
        segments[-1],
        float(grade[-1]),
        cast(float, model.sled_mass_kg),
        cast(float, model.sled_friction),
    )


@register_mode
class SupervisorMode(Mode):
    """Roll; switch to the inchworm gait when immobilised; switch back when rolling is feasible."""

    name = "supervisor"
    config_class = SupervisorConfig
    cfg: SupervisorConfig

    def __init__(self, cfg: SupervisorConfig, scenario: Scenario, model: ChainModel) -> None:
        super().__init__(cfg, scenario, model)
        self.inch_cfg = cfg.inching_config()
        self.segments = scenario.vehicle.segment_params()
        # the joints start (and hold while rolling) at the gait's initial extensions
        self.s0 = InchwormMode(self.inch_cfg, scenario, model).s0
        self.state = "off" if cfg.start_time_s > 0 else "rolling"
        self.since = float(cfg.start_time_s)
        self.history_t: list[float] = []
        self.history_x: list[float] = []
        self.inch: InchwormMode | None = None
        self.timeline = [(0.0, self.state)]
        self.cycles_total = 0
        from .. import steady  # root finding (scipy.optimize, slow to import): loaded by a run, not by validation

        seg0 = self.segments[0]
        tow = steady.tow_drawbar_N(  # one chain: the supervisor never runs stacked
            cast(float, model.tow_force_N),
            self.segments[-1],
            0.0,
            cast(float, model.sled_mass_kg),
            cast(float, model.sled_friction),
        )
        self.rolling_limit_xt = steady.immobilisation_limit_xt(
            seg0, model.tp, drawbar_N=tow / model.n, wheel_speed_mps=cfg.rolling_speed_mps
        )

    def initial_state(self) -> NDArray[np.float64]:
        return self.model.initial_state(joint_extension_m=self.s0)

    # ------------------------------------------------------------------ helpers
    def _x(self, y: NDArray[np.float64]) -> NDArray[np.float64]:
        return self.model.field(self.model.unpack(y), "x_m")

    def _leader_slip(self, y: NDArray[np.float64]) -> float:
        m = self.model
        Y = m.unpack(y)
        w = Y[0, m.layout.omega] * m.seg.wheel_radius_m[0]
        return float(np.mean(terrain.slip(w, m.field(Y, "v_mps")[0], m.tp.slip_eps_mps)))

    def _xt_under(self, y: NDArray[np.float64]) -> NDArray[np.float64]:
        return self.model.xt_at_axles(self._x(y)).mean(-1)

    def _switch(self, t: float, y: NDArray[np.float64], new: str, kind: str, detail: str) -> None:
        self.state = new
        self.since = float(t)
        self.timeline.append((float(t), new))
        self.log.append(
            {
                "t_s": float(t),
                "kind": kind,
                "x_m": float(self._x(y)[0]),
                "detail": detail + f"; X_t under segments {np.round(self._xt_under(y), 3).tolist()}",
            }
        )

    def _stuck(self, t: float, y: NDArray[np.float64]) -> tuple[bool, float | None, float | None]:
        """Immobilisation rule: (stuck?, mean speed over the window, leader slip)."""
        cfg = self.cfg
        if t - self.since < cfg.stuck_window_s - 1e-9:
            return False, None, None
        x_then = float(np.interp(t - cfg.stuck_window_s, self.history_t, self.history_x))
        v_mean = (float(np.mean(self._x(y))) - x_then) / cfg.stuck_window_s
        s_lead = self._leader_slip(y)
        return (v_mean < cfg.stuck_speed_mps and s_lead > cfg.stuck_slip), v_mean, s_lead

    # ------------------------------------------------------------------ Mode interface
    def interval(self, t: float, y: NDArray[np.float64]) -> Interval:
        cfg, n = self.cfg, self.model.n
        if self.state == "off":
            if t < cfg.start_time_s - 1e-12:
                return Interval(cfg.start_time_s, Controls.rolling(n, np.zeros(n), np.zeros(n)), [], "before start")
            self.state, self.since = "rolling", float(t)
            self.timeline.append((float(t), "rolling"))
        if self.state == "rolling":
            self.history_t.append(float(t))
            self.history_x.append(float(np.mean(self._x(y))))
            stuck, v_mean, s_lead = self._stuck(t, y)
            if stuck:
                self._switch(
                    t,
                    y,
                    "inching",
                    "switch_to_inching",
                    f"immobilised: mean chain speed {v_mean:.3f} m/s over {cfg.stuck_window_s:g} s < "
                    f"{cfg.stuck_speed_mps:g} m/s and leader slip {s_lead:.2f} > {cfg.stuck_slip:g}",
                )
                self.inch = InchwormMode(self.inch_cfg, self.scenario, self.model)
                self.inch.log = self.log  # gait events go to the same log
            else:
                ctl = Controls.rolling(n, np.ones(n), np.full(n, cfg.rolling_speed_mps))
                return Interval(t + cfg.check_interval_s, ctl, [], "rolling")
        iv = cast(InchwormMode, self.inch).interval(t, y)  # inching (made above if it was not)
        iv.label = f"inching: {iv.label}"
        return iv

    def on_event(self, t: float, y: NDArray[np.float64], index: int) -> None:
        inch = cast(InchwormMode, self.inch)  # events come from the gait's intervals only
        before = inch.cycles_done
        inch.on_event(t, y, index)
        if inch.cycles_done == before:
            return
        self.cycles_total += 1
        surplus = chain_drawbar_surplus_N(self.model, self.segments, self._x(y), self.cfg.rolling_speed_mps)
        if surplus >= self.cfg.resume_margin_N:
            self._switch(
                t,
                y,
                "rolling",
                "switch_to_rolling",
                f"rolling feasible after gait cycle: chain drawbar surplus {surplus:.0f} N >= "
                f"margin {self.cfg.resume_margin_N:g} N",
            )
            self.inch = None
            self.history_t, self.history_x = [], []

    def summary(self, result: Any) -> dict:
        t = result.t
        xbar = result.segments["x_m"].mean(1)
        bounds = [tt for tt, _ in self.timeline] + [float(t[-1])]
        time_in = {"off": 0.0, "rolling": 0.0, "inching": 0.0}
        dist_in = {"off": 0.0, "rolling": 0.0, "inching": 0.0}
        for (t0, st), t1 in zip(self.timeline, bounds[1:]):
            time_in[st] += max(t1 - t0, 0.0)
            dist_in[st] += float(np.interp(t1, t, xbar) - np.interp(t0, t, xbar))
        return {
            "supervisor": {
                "switches": [e for e in self.log if e["kind"].startswith("switch_")],
                "time_rolling_s": time_in["rolling"],
                "time_inching_s": time_in["inching"],
                "distance_rolling_m": dist_in["rolling"],
                "distance_inching_m": dist_in["inching"],
                "gait_cycles": self.cycles_total + (self.inch.cycles_done if self.inch is not None else 0),
                "rolling_limit_xt": self.rolling_limit_xt,
                "final_state": self.state,
            }
        }
