r"""Force-control mode: segments use their wheel speed to set the link forces (paper section 5.2).

"A proportional-integral controller uses a segment's wheel speed as the control variable, and
the force in an adjacent connector as the process value" (paper section 5.2, Figs 8-11).  One
segment (the *free* segment, the rear one by default) drives at its nominal wheel speed and
sets the chain's ground speed; every other segment runs an outer PI loop on one adjacent link:

* a segment **ahead** of the free one controls the link **behind** it (link ``k``, ``sigma = +1``:
  more tension behind -> drive faster),
* a segment **behind** the free one controls the link **ahead** of it (link ``k - 1``,
  ``sigma = -1``: more tension ahead -> drive slower).

So each of the ``N - 1`` links is held by exactly one loop.  The loop itself lives in the chain
kernel (:meth:`snoworm.dynamics.ChainModel.evaluate`)::

    e    = sigma (F_ref - F)
    v_sp = clip(v_nom + kp e + q, 0, v_max)                 [m/s]
    dq/dt = ki e + (ki / kp) (v_sp - (v_nom + kp e + q))    (back-calculation anti-windup)

``q`` starts at 0, so at the motor start time the set-point starts at the nominal speed plus
the proportional term (bumpless; starting from ``v_sp = 0`` the chain can fall into the stall
equilibrium of docs/model.md section 5, Fig 11 note).  ``v_sp >= 0`` is the paper's constraint that
"the lead segment does not drive backwards" (Fig 8).

The targets are turned into link-force references, checked against the available drawbar pull
and their steady state predicted when a run is assembled (``ForceControlConfig.prepare``; not when
the scenario is validated, which builds no chain model): :mod:`snoworm.modes.force_plan`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..config.mode_registry import ModeConfig
from ..config.schema import Config, ScenarioError, field, suggest
from ..config.sections import FINITE_WHY
from ..model.inputs import Controls
from .base import Interval, Mode, refuse_failed_drivetrains, register_mode, rolling_interval, start_times

if TYPE_CHECKING:
    from numpy.typing import NDArray

    from ..config.scenario import Scenario
    from ..config.sections import VehicleConfig
    from ..model.chain import ChainModel
    from .force_plan import ForcePlan

__all__ = ["TargetsConfig", "ForceControlConfig", "ForceControlMode", "SHARE_RULES"]

#: Named load-share rules (``targets.load_shares``).
SHARE_RULES = ("even", "drawbar", "inverse_slip")

#: A set-point within this distance of 0 or ``v_max`` counts as saturated [m/s].
SATURATION_TOL_MPS = 1e-4


@dataclass(frozen=True)
class TargetsConfig(Config):
    """What the force loops should achieve: exactly one kind of target (see the module docstring)."""

    _section = "mode.targets"

    link_forces_N: tuple[float, ...] | None = field(
        None, ge=-1e6, le=1e6, unit="N", doc="link-force references, tension positive, one per link from the front"
    )
    load_shares: str | tuple[float, ...] | None = field(
        None, doc="fractions of the tow per segment (summing to 1), or a rule: even, drawbar, inverse_slip"
    )
    net_connector_N: dict[int, float] | None = field(
        None, ge=-1e6, le=1e6, unit="N", doc="net connector force on chosen segments {index: force}, forward positive"
    )

    def _check(self, path: str) -> None:
        given = [k for k in ("link_forces_N", "load_shares", "net_connector_N") if getattr(self, k) is not None]
        if not given:
            raise ScenarioError(
                f"{path}: give a target: link_forces_N (one per link), load_shares "
                f"(e.g. even, drawbar, or a list of fractions) or net_connector_N "
                "(e.g. {1: 0} for zero net connector force on segment 1)."
            )
        if self.link_forces_N is not None and len(given) > 1:
            raise ScenarioError(
                f"{path}: link_forces_N fixes every link force and cannot be combined with "
                f"{' or '.join(g for g in given if g != 'link_forces_N')}; keep only one."
            )
        ls = self.load_shares
        if isinstance(ls, str) and ls not in SHARE_RULES:
            raise ScenarioError(
                f"{path}.load_shares: unknown rule {ls!r}.{suggest(ls, SHARE_RULES)} "
                f"Use one of {', '.join(SHARE_RULES)} or a list of fractions, one per segment."
            )
        if self.net_connector_N is not None and ls is not None and not isinstance(ls, str):
            raise ScenarioError(
                f"{path}.load_shares: with net_connector_N, load_shares names the rule by which "
                f"the other segments share the rest ({', '.join(SHARE_RULES)}), not a list."
            )
        if isinstance(ls, tuple) and abs(sum(ls) - 1.0) > 1e-6:
            raise ScenarioError(
                f"{path}.load_shares: the fractions of the tow must sum to 1, got "
                f"{sum(ls):.6g}. Scale them, or write load_shares: even."
            )


@dataclass(frozen=True)
class ForceControlConfig(ModeConfig):
    """``mode: {type: force_control, speed_mps: 1.8, start_time_s: 1, targets: {...}}`` (section 5.2)."""

    type: str = field(choices=("force_control",), doc="mode name")
    speed_mps: tuple[float, ...] = field(
        gt=0,
        le=100,
        why=FINITE_WHY,
        unit="m/s",
        doc="nominal wheel speed R_w*omega: the free segment's set-point and the loops' "
        "feed-forward, one for all segments or one per segment",
    )
    start_time_s: tuple[float, ...] = field(
        ge=0, le=1e5, unit="s", doc="motor start time, one for all or one per segment"
    )
    targets: TargetsConfig = field(doc="link forces, load shares or net connector forces")
    free_segment: int | None = field(
        None,
        ge=0,
        le=1000,
        why="A segment index (vehicle.segments is at most 200).",
        doc="segment driven at its nominal speed without a force loop (default: the rear one)",
    )
    kp_mps_per_N: float = field(
        1.6e-3, gt=0, le=1, why=FINITE_WHY, unit="m/s per N", doc="force-loop proportional gain [assumed]"
    )
    ki_mps_per_Ns: float = field(
        4.0e-3, ge=0, le=10, why=FINITE_WHY, unit="m/s per N s", doc="force-loop integral gain [assumed]"
    )
    max_speed_mps: float | None = field(
        None,
        gt=0,
        le=100,
        why=FINITE_WHY,
        unit="m/s",
        doc="upper limit of a loop's set-point (default: the no-load wheel speed R_w*w_nl)",
    )

    #: the state carries the outer force-loop integrators
    force_loop = True
    #: extra plots made by :func:`snoworm.plotting.plot_result` for this mode
    extra_plots: ClassVar[tuple[str, ...]] = ("force_diagram",)

    def check_vehicle(self, vehicle: VehicleConfig, path: str) -> None:
        n = vehicle.segments
        if n < 2:
            raise ScenarioError(
                f"vehicle.segments: force control needs at least 2 segments (a link to control); "
                f"got {n}. Use mode type 'uniform' for one segment."
            )
        start_times(self.start_time_s, n, f"{path}.start_time_s")
        refuse_failed_drivetrains(vehicle, "force_control", "plans every segment's wheel force with its motors")
        if len(self.speed_mps) not in (1, n):
            raise ScenarioError(f"{path}.speed_mps: give one speed for all segments or {n}; got {len(self.speed_mps)}.")
        if self.free_segment is not None and self.free_segment >= n:
            raise ScenarioError(f"{path}.free_segment: segment index out of range 0..{n - 1}, got {self.free_segment}.")
        t = self.targets
        tp = f"{path}.targets"
        if t.link_forces_N is not None and len(t.link_forces_N) != n - 1:
            raise ScenarioError(
                f"{tp}.link_forces_N: give one force per link, {n - 1} for {n} segments "
                f"(link k joins segment k and k+1); got {len(t.link_forces_N)}."
            )
        if isinstance(t.load_shares, tuple) and len(t.load_shares) != n:
            raise ScenarioError(f"{tp}.load_shares: give one fraction per segment ({n}); got {len(t.load_shares)}.")
        if t.net_connector_N is not None:
            for k in t.net_connector_N:
                if not 0 <= k < n:
                    raise ScenarioError(f"{tp}.net_connector_N.{k}: segment index out of range 0..{n - 1}.")
            if len(t.net_connector_N) == n:
                raise ScenarioError(
                    f"{tp}.net_connector_N: fixes every segment; leave at least one segment out "
                    "to share the tow (or give link_forces_N)."
                )

    def prepare(self, sc: Scenario, model: ChainModel) -> ForcePlan:
        """The :class:`~snoworm.modes.force_plan.ForcePlan` on ``model``, made when a run is assembled.

        Feasibility: every segment can pull its share, set-points within [0, v_max]; ScenarioError
        naming the target if not."""
        # root finding (scipy.optimize, slow to import) is loaded when a run starts: validating a
        # scenario imports no solver
        from .force_plan import plan

        return plan(self, sc, model)

    def batch_signature(self) -> tuple:
        """No state events (the plan is computed once per run): members with the same start
        times and free segment have the same intervals and loop layout (targets, gains and
        speeds may differ)."""
        return ("force_control", tuple(self.start_time_s), self.free_segment)


@register_mode
class ForceControlMode(Mode):
    """Outer PI loops on the link forces, wheel-speed set-points in ``[0, v_max]`` (paper section 5.2)."""

    name = "force_control"
    config_class = ForceControlConfig

    def __init__(self, cfg: ForceControlConfig, scenario: Scenario, model: ChainModel) -> None:
        super().__init__(cfg, scenario, model)
        n = model.n
        self.plan = cfg.prepare(scenario, model)
        self.t_start = start_times(cfg.start_time_s, n)
        self.breaks = np.unique(self.t_start)
        p = self.plan
        ref = np.zeros(n)
        ref[p.controlled] = p.link_ref_N[p.fc_link[p.controlled]]
        self._base = Controls.rolling(n, np.zeros(n), p.nominal_mps).with_(
            fc_active=p.controlled.astype(float),
            fc_link=p.fc_link,
            fc_sigma=p.fc_sigma,
            fc_ref_N=ref,
            fc_nominal_mps=p.nominal_mps,
            fc_kp=np.full(n, cfg.kp_mps_per_N),
            fc_ki=np.full(n, cfg.ki_mps_per_Ns),
            fc_vmax_mps=p.vmax_mps,
        )

    def interval(self, t: float, y: NDArray[np.float64]) -> Interval:
        return rolling_interval(t, self.t_start, self.breaks, self._base, "force control")

    def summary(self, result: Any) -> dict:
        """Targets, predicted and final steady state, and saturation of the loops."""
        p = self.plan
        sp = result.segments["speed_setpoint_mps"]
        t = result.t
        F_end = result.links["force_N"][-1]
        sat, frac = [], []
        for k in np.flatnonzero(p.controlled):
            after = t >= self.t_start[k]
            low = sp[after, k] <= SATURATION_TOL_MPS
            high = sp[after, k] >= p.vmax_mps[k] - SATURATION_TOL_MPS
            frac.append(
                {
                    "segment": int(k),
                    "fraction_at_zero": float(np.mean(low)) if low.size else 0.0,
                    "fraction_at_max": float(np.mean(high)) if high.size else 0.0,
                }
            )
            if low.size and low[-1]:
                sat.append({"segment": int(k), "at": "zero"})
            elif high.size and high[-1]:
                sat.append({"segment": int(k), "at": "max_speed"})
        return {
            "force_control": {
                "free_segment": p.free_segment,
                "loops": [
                    {"segment": int(k), "link": int(p.fc_link[k]), "side": "behind" if p.fc_sigma[k] > 0 else "ahead"}
                    for k in np.flatnonzero(p.controlled)
                ],
                "link_force_refs_N": p.link_ref_N.tolist(),
                "wheel_net_targets_N": p.wheel_net_N.tolist(),
                "available_drawbar_N": p.available_drawbar_N.tolist(),
                "drawbar_limited_by": list(p.limited_by),
                "predicted_setpoints_mps": p.predicted_setpoint_mps.tolist(),
                "predicted_ground_speed_mps": p.predicted_ground_speed_mps,
                "final_setpoints_mps": sp[-1].tolist(),
                "final_link_force_errors_N": (F_end - p.link_ref_N).tolist(),
                "saturation": frac,
                "saturated_at_end": sat,
            }
        }
