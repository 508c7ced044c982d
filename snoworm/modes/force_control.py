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

Targets and their conversion to link-force references
-----------------------------------------------------
Links are numbered from the front: link ``k`` joins segment ``k`` (ahead) and ``k + 1``; tension is
positive; the tow ``F_tow`` pulls the rear segment back.  In steady motion every segment's
acceleration is zero, so with ``W_k`` the net wheel force of segment ``k`` (traction minus
resistance, summed over its wheels, forward positive)::

    W_k + T_{k-1} - T_k = 0            (T_{-1} = 0, T_{N-1} = F_tow)
    =>  T_k = sum_{j <= k} W_j         (k = 0 .. N-2),      T_{N-2} + W_{N-1} = F_tow

and the net connector force on segment ``k`` is ``C_k = T_{k-1} - T_k = -W_k``.  Every target
below is turned into the wheel forces ``W`` and then into the references ``T_k``:

``link_forces_N: [T_0, ..., T_{N-2}]``
    The references themselves; ``W_k = T_k - T_{k-1}``.  Fig 8: ``[0]``; Fig 11: ``[50, -50]``.
``load_shares: [s_0, ..., s_{N-1}]`` (summing to 1) or a rule
    ``W_k = s_k F_tow``.  Rules: ``even`` (``s_k = 1/N``, the steady state of Fig 6 reached by
    control), ``drawbar`` (``s_k`` proportional to the segment's available drawbar pull, see
    below: a segment with a weakened drivetrain carries less) and ``inverse_slip`` (``s_k``
    proportional to ``1 / i_k``, ``i_k`` the steady slip the segment would have carrying an
    even share at its nominal speed: segments on poorer snow or lighter segments carry less).
``net_connector_N: {k: C_k, ...}``
    Fixes the net connector force on the listed segments (``W_k = -C_k``): 0 is Figs 9-10's
    "zero net connector force on the middle segment", a positive value is Fig 11's segment
    pulled ahead and pushed from behind.  The remaining segments share
    ``F_tow + sum C_k`` by the rule in ``load_shares`` (default ``even``).

Available drawbar pull and impossible targets
---------------------------------------------
:func:`snoworm.steady.max_drawbar_N` is the terrain's limit (peak of the net force over slip);
it does not see the motor.  Per wheel, the steady torque balance
``T_m = reaction(F_t, F_tr, T_rr)`` (``R_w (F_t - F_tr) + T_rr`` in the default ``contact``
convention) with ``T_m <= T_hi(w) = min(T_max, k_w (w_nl - w))`` caps the traction at
``F_t* = (T_hi - reaction(0, F_tr, T_rr)) / R_w``, so the segment's drawbar is at most
``n_wheels (F_t* - F_tr)``, i.e. ``n_wheels (T_hi - T_rr) / R_w`` in the contact convention
(``4 (88.64 - 20.0) / 0.265 = 1036 N`` for FrostyBoy at ``X_t = 0.9``: the terrain's 345 N
binds; a torque limit below ~43 N m binds instead).  The available drawbar is the smaller of
the two, evaluated at the nominal wheel speed and the terrain under the segment at its start
position.  A target asking a segment for more (or, braking, for less than its locked-wheel
limit), or one whose predicted steady set-point exceeds ``max_speed_mps``, is a
:class:`~snoworm.config.schema.ScenarioError` when the scenario is validated, never left to wind up.
Saturation during the run (a set-point pinned at 0 or ``v_max`` at the end) is reported in
the mode summary (``force_control.saturated_at_end``).

Predicted steady state
----------------------
The free segment carries ``W_f`` at its nominal wheel speed, which fixes its slip and the
chain's ground speed ``V``; every controlled segment ``k`` then carries ``W_k`` at ``V``, which
fixes its slip ``i_k`` and its steady set-point ``V / (1 - i_k)``.  For Fig 8 this gives a
leader set-point of 1.679 m/s; for Figs 9-10 1.800 / 1.747 / 1.800 m/s (docs/model.md section 5).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Union

import numpy as np
from scipy.optimize import brentq

from .. import steady, terrain
from ..model.inputs import Controls
from ..config.schema import Config, ScenarioError, field, suggest
from ..config.mode_registry import ModeConfig
from ..config.sections import FINITE_WHY
from .base import Mode, register_mode, rolling_interval, start_times

__all__ = ["TargetsConfig", "ForceControlConfig", "ForceControlMode", "ForcePlan", "plan",
           "available_drawbar_N", "SHARE_RULES"]

#: Named load-share rules (``targets.load_shares``).
SHARE_RULES = ("even", "drawbar", "inverse_slip")

#: A set-point within this distance of 0 or ``v_max`` counts as saturated [m/s].
SATURATION_TOL_MPS = 1e-4


@dataclass(frozen=True)
class TargetsConfig(Config):
    """What the force loops should achieve: exactly one kind of target (see the module docstring)."""

    _section = "mode.targets"

    link_forces_N: Optional[tuple[float, ...]] = field(
        None, ge=-1e6, le=1e6, unit="N", doc="link-force references, tension positive, one per link from the front")
    load_shares: Optional[Union[str, tuple[float, ...]]] = field(
        None, doc="fractions of the tow per segment (summing to 1), or a rule: even, drawbar, inverse_slip")
    net_connector_N: Optional[dict[int, float]] = field(
        None, ge=-1e6, le=1e6, unit="N", doc="net connector force on chosen segments {index: force}, forward positive")

    def _check(self, path):
        given = [k for k in ("link_forces_N", "load_shares", "net_connector_N") if getattr(self, k) is not None]
        if not given:
            raise ScenarioError(f"{path}: give a target: link_forces_N (one per link), load_shares "
                                f"(e.g. even, drawbar, or a list of fractions) or net_connector_N "
                                "(e.g. {1: 0} for zero net connector force on segment 1).")
        if self.link_forces_N is not None and len(given) > 1:
            raise ScenarioError(f"{path}: link_forces_N fixes every link force and cannot be combined with "
                                f"{' or '.join(g for g in given if g != 'link_forces_N')}; keep only one.")
        ls = self.load_shares
        if isinstance(ls, str) and ls not in SHARE_RULES:
            raise ScenarioError(f"{path}.load_shares: unknown rule {ls!r}.{suggest(ls, SHARE_RULES)} "
                                f"Use one of {', '.join(SHARE_RULES)} or a list of fractions, one per segment.")
        if self.net_connector_N is not None and ls is not None and not isinstance(ls, str):
            raise ScenarioError(f"{path}.load_shares: with net_connector_N, load_shares names the rule by which "
                                f"the other segments share the rest ({', '.join(SHARE_RULES)}), not a list.")
        if isinstance(ls, tuple) and abs(sum(ls) - 1.0) > 1e-6:
            raise ScenarioError(f"{path}.load_shares: the fractions of the tow must sum to 1, got "
                                f"{sum(ls):.6g}. Scale them, or write load_shares: even.")


@dataclass(frozen=True)
class ForceControlConfig(ModeConfig):
    """``mode: {type: force_control, speed_mps: 1.8, start_time_s: 1, targets: {...}}`` (section 5.2)."""

    type: str = field(choices=("force_control",), doc="mode name")
    speed_mps: tuple[float, ...] = field(
        gt=0, le=100, why=FINITE_WHY, unit="m/s",
        doc="nominal wheel speed R_w*omega: the free segment's set-point and the loops' "
            "feed-forward, one for all segments or one per segment")
    start_time_s: tuple[float, ...] = field(ge=0, le=1e5, unit="s",
                                            doc="motor start time, one for all or one per segment")
    targets: TargetsConfig = field(doc="link forces, load shares or net connector forces")
    free_segment: Optional[int] = field(
        None, ge=0, le=1000, why="A segment index (vehicle.segments is at most 200).",
        doc="segment driven at its nominal speed without a force loop (default: the rear one)")
    kp_mps_per_N: float = field(1.6e-3, gt=0, le=1, why=FINITE_WHY, unit="m/s per N",
                                doc="force-loop proportional gain [assumed]")
    ki_mps_per_Ns: float = field(4.0e-3, ge=0, le=10, why=FINITE_WHY, unit="m/s per N s",
                                 doc="force-loop integral gain [assumed]")
    max_speed_mps: Optional[float] = field(
        None, gt=0, le=100, why=FINITE_WHY, unit="m/s",
        doc="upper limit of a loop's set-point (default: the no-load wheel speed R_w*w_nl)")

    #: the state carries the outer force-loop integrators
    force_loop = True
    #: extra plots made by :func:`snoworm.plotting.plot_result` for this mode
    extra_plots = ("force_diagram",)

    def check_vehicle(self, vehicle, path):
        n = vehicle.segments
        if n < 2:
            raise ScenarioError(f"vehicle.segments: force control needs at least 2 segments (a link to control); "
                                f"got {n}. Use mode type 'uniform' for one segment.")
        start_times(self.start_time_s, n, f"{path}.start_time_s")
        if len(self.speed_mps) not in (1, n):
            raise ScenarioError(f"{path}.speed_mps: give one speed for all segments or {n}; got {len(self.speed_mps)}.")
        if self.free_segment is not None and self.free_segment >= n:
            raise ScenarioError(f"{path}.free_segment: segment index out of range 0..{n - 1}, got {self.free_segment}.")
        t = self.targets
        tp = f"{path}.targets"
        if t.link_forces_N is not None and len(t.link_forces_N) != n - 1:
            raise ScenarioError(f"{tp}.link_forces_N: give one force per link, {n - 1} for {n} segments "
                                f"(link k joins segment k and k+1); got {len(t.link_forces_N)}.")
        if isinstance(t.load_shares, tuple) and len(t.load_shares) != n:
            raise ScenarioError(f"{tp}.load_shares: give one fraction per segment ({n}); got {len(t.load_shares)}.")
        if t.net_connector_N is not None:
            for k in t.net_connector_N:
                if not 0 <= k < n:
                    raise ScenarioError(f"{tp}.net_connector_N.{k}: segment index out of range 0..{n - 1}.")
            if len(t.net_connector_N) == n:
                raise ScenarioError(f"{tp}.net_connector_N: fixes every segment; leave at least one segment out "
                                    "to share the tow (or give link_forces_N).")

    def check_scenario(self, sc, path):
        """Feasibility: every segment can pull its share; set-points within [0, v_max] (the plan)."""
        sc.mode_plan   # noqa: B018 - computing the plan raises ScenarioError if a target is impossible

    def prepare(self, sc):
        """The :class:`ForcePlan`, computed once per scenario (``scenario.mode_plan``)."""
        return plan(self, sc, sc.chain_model)

    def batch_signature(self):
        """No state events (the plan is computed once per scenario): members with the same start
        times and free segment have the same intervals and loop layout (targets, gains and
        speeds may differ)."""
        return ("force_control", tuple(self.start_time_s), self.free_segment)


# ---------------------------------------------------------------------- steady-state helpers
def _hi_torque(seg, wheel_speed_mps):
    w = wheel_speed_mps / seg.wheel_radius_m
    return min(seg.torque_limit_Nm, seg.motor_slope_Nms_per_rad * (seg.no_load_speed_radps - w))


def available_drawbar_N(X, seg, tp, wheel_speed_mps):
    """Largest steady drawbar of one segment [N]: the terrain's limit or the motor's, whichever is lower.

    Parameters
    ----------
    X : float
        Terrain coefficient X_t under the segment.
    seg : SegmentConfig
        Segment parameters (with per-segment overrides, e.g. a lower ``torque_limit_Nm``).
    tp : TerrainParams
        Terrain coefficients.
    wheel_speed_mps : float
        Wheel speed ``R_w w`` at which the motor's envelope is evaluated [m/s].

    Returns
    -------
    (drawbar_N, limited_by) : tuple of float and str
        ``limited_by`` is ``"terrain"`` or ``"motor"``.
    """
    d_terrain = steady.max_drawbar_N(X, seg, tp, wheel_speed_mps)
    n_w, F_n, R = steady.segment_geometry(seg)
    Ftr = float(terrain.resistance_force(np.inf, F_n, X, tp))
    Trr = float(terrain.resistance_torque(wheel_speed_mps, F_n, X, R, tp))
    c = float(terrain.wheel_reaction_torque(0.0, Ftr, Trr, R, tp))
    Ft_star = (_hi_torque(seg, wheel_speed_mps) - c) / R
    d_motor = n_w * (Ft_star - Ftr)
    return (d_terrain, "terrain") if d_terrain <= d_motor else (d_motor, "motor")


def _slip_for(W, X, seg, tp, *, wheel_speed_mps=None, ground_speed_mps=None):
    """Steady slip at which a moving segment's wheels develop the net force ``W`` (stable branch).

    Negative ``W`` below the zero-slip value (the resistance alone) needs negative slip (braking).
    Returns ``None`` if no slip in ``[-i_peak, i_peak]`` gives ``W``.
    """
    ref = wheel_speed_mps if wheel_speed_mps is not None else ground_speed_mps
    i_pk = min(steady.peak_slip(X, ref, seg, tp), 0.999)

    def f(i):
        ws = wheel_speed_mps if wheel_speed_mps is not None else ground_speed_mps / (1.0 - i)
        return float(steady.net_force_per_segment_N(i, X, ws, seg, tp, moving=True)) - W
    lo, hi = f(-i_pk), f(i_pk)
    if lo > 0 or hi < 0:
        return None
    return float(brentq(f, -i_pk, i_pk, xtol=1e-13))


@dataclass(frozen=True)
class ForcePlan:
    """Resolved force-control targets and the predicted steady state (arrays of length N or N-1)."""

    wheel_net_N: np.ndarray          # (N,) steady net wheel force W_k
    link_ref_N: np.ndarray           # (N-1,) link-force references T_k
    free_segment: int
    controlled: np.ndarray           # (N,) bool: runs a force loop
    fc_link: np.ndarray              # (N,) int: controlled link (N-1 for the free segment, unused)
    fc_sigma: np.ndarray             # (N,) +1 link behind, -1 link ahead
    available_drawbar_N: np.ndarray  # (N,)
    limited_by: tuple                # (N,) "terrain" or "motor"
    xt: np.ndarray                   # (N,) X_t used for the checks
    nominal_mps: np.ndarray          # (N,)
    vmax_mps: np.ndarray             # (N,)
    predicted_ground_speed_mps: float
    predicted_setpoint_mps: np.ndarray  # (N,)
    predicted_slip: np.ndarray       # (N,)


def _shares(rule, idx, W_total, xt, segs, tp, nominal):
    """Fractions (summing to 1) of ``W_total`` for the segments ``idx`` under a named rule."""
    if rule == "even":
        w = np.ones(len(idx))
    elif rule == "drawbar":
        w = np.array([available_drawbar_N(xt[k], segs[k], tp, nominal[k])[0] for k in idx])
        if np.any(w <= 0):
            bad = [int(k) for k, v in zip(idx, w) if v <= 0]
            raise ScenarioError(f"mode.targets.load_shares: drawbar shares need every sharing segment to have a "
                                f"positive available drawbar; segment(s) {bad} have none on this terrain.")
    else:  # inverse_slip
        even = W_total / len(idx)
        slips = []
        for k in idx:
            i = _slip_for(even, xt[k], segs[k], tp, wheel_speed_mps=nominal[k])
            if i is None or i <= 0:
                raise ScenarioError(f"mode.targets.load_shares: inverse_slip needs a positive steady slip for each "
                                    f"sharing segment at an even share ({even:.1f} N); segment {int(k)} has "
                                    f"{'none' if i is None else f'{i:.3g}'}. Use even or drawbar.")
            slips.append(i)
        w = 1.0 / np.array(slips)
    return w / w.sum()


def _check_drawbar(W, T, F_tow, xt, segs, tp, nominal, tpath):
    """Every segment can pull its net wheel force ``W`` (and the chain the tow); the available drawbar."""
    n = len(W)
    avail, why = zip(*(available_drawbar_N(xt[j], segs[j], tp, nominal[j]) for j in range(n)))
    avail = np.array(avail)
    if F_tow > avail.sum() + 1e-9:
        raise ScenarioError(
            f"{tpath}: impossible target: the tow of {F_tow:g} N exceeds the drawbar the whole chain can pull, "
            f"{avail.sum():.1f} N (per segment {np.round(avail, 1).tolist()} N on X_t = {np.round(xt, 3).tolist()}); "
            "no load sharing can carry it. Lower tow.force_N or add segments.")
    for j in range(n):
        if W[j] > avail[j] + 1e-9:
            raise ScenarioError(
                f"{tpath}: impossible target: segment {j} would have to pull {W[j]:.1f} N (net wheel force; "
                f"link references {np.round(T, 1).tolist()} N, tow {F_tow:g} N) but can pull at most "
                f"{avail[j]:.1f} N on X_t = {xt[j]:g} (limited by the {why[j]}). Lower that segment's share, "
                f"or use load_shares: drawbar.")
    return avail, why


def _predict(W, f, controlled, xt, segs, tp, nominal, vmax, path, tpath):
    """Predicted steady state: the free segment ``f`` sets the ground speed; ``(V, set-points, slips)``."""
    n = len(W)
    slip = np.full(n, np.nan)
    i_f = _slip_for(W[f], xt[f], segs[f], tp, wheel_speed_mps=nominal[f])
    if i_f is None:
        raise ScenarioError(f"{tpath}: impossible target: the free segment {f} cannot develop a net wheel force "
                            f"of {W[f]:.1f} N at {nominal[f]:g} m/s on X_t = {xt[f]:g}.")
    slip[f] = i_f
    V = nominal[f] * (1.0 - i_f)
    sp = np.array(nominal, float)
    for j in np.flatnonzero(controlled):
        i = _slip_for(W[j], xt[j], segs[j], tp, ground_speed_mps=V)
        if i is None:
            raise ScenarioError(f"{tpath}: impossible target: segment {j} cannot develop a net wheel force of "
                                f"{W[j]:.1f} N while moving at {V:.3f} m/s on X_t = {xt[j]:g} (it would need more "
                                "braking than locked wheels give). Change the link forces.")
        slip[j] = i
        sp[j] = V / (1.0 - i)
        if sp[j] > vmax[j]:
            raise ScenarioError(f"{tpath}: impossible target: segment {j} would need a wheel-speed set-point of "
                                f"{sp[j]:.3f} m/s, above max_speed_mps = {vmax[j]:.3f} m/s. Raise "
                                f"{path}.max_speed_mps or lower the segment's share.")
    return V, sp, slip


def plan(cfg: ForceControlConfig, sc, model, path="mode") -> ForcePlan:
    """Convert the targets to link-force references and check they are reachable (module docstring).

    Raises
    ------
    ScenarioError
        If a segment is asked for more drawbar than it can pull (or more braking than it can
        give) on the terrain, or a predicted steady set-point exceeds ``max_speed_mps``.
    """
    n = model.n
    segs = sc.vehicle.segment_params()
    tp = model.tp
    F_tow = float(sc.tow.force_N)
    nominal = np.asarray(cfg.speed_mps, float) * np.ones(n)
    R = model.seg.wheel_radius_m
    vmax = (np.full(n, cfg.max_speed_mps) if cfg.max_speed_mps is not None
            else R * model.seg.no_load_speed_radps)
    # terrain under each segment at its start position (worst axle)
    x0 = model.field(model.unpack(model.initial_state()), "x_m")
    xt = np.min(model.xt_at_axles(x0), axis=-1)
    t = cfg.targets
    tpath = f"{path}.targets"
    if t.link_forces_N is not None:
        T = np.asarray(t.link_forces_N, float)
        W = np.append(T, F_tow) - np.concatenate([[0.0], T])
    elif t.net_connector_N is not None:
        W = np.zeros(n)
        fixed = np.zeros(n, bool)
        for k, C in t.net_connector_N.items():
            W[k], fixed[k] = 0.0 - float(C), True  # 0.0 - avoids -0.0
        rest = np.flatnonzero(~fixed)
        remaining = F_tow - W[fixed].sum()
        W[rest] = remaining * _shares(t.load_shares or "even", rest, remaining, xt, segs, tp, nominal)
    else:
        ls = t.load_shares
        s = (np.asarray(ls, float) if not isinstance(ls, str)
             else _shares(ls, np.arange(n), F_tow, xt, segs, tp, nominal))
        W = s * F_tow
    T = np.cumsum(W)[:-1]
    # loop assignment around the free segment
    f = n - 1 if cfg.free_segment is None else int(cfg.free_segment)
    k = np.arange(n)
    controlled = k != f
    sigma = np.where(k < f, 1.0, -1.0)
    link = np.where(k < f, k, k - 1)
    link[f] = n - 1
    avail, why = _check_drawbar(W, T, F_tow, xt, segs, tp, nominal, tpath)
    V, sp, slip = _predict(W, f, controlled, xt, segs, tp, nominal, vmax, path, tpath)
    return ForcePlan(W, T, f, controlled, link.astype(int), sigma, avail, tuple(why), xt, nominal, vmax,
                     float(V), sp, slip)


@register_mode
class ForceControlMode(Mode):
    """Outer PI loops on the link forces, wheel-speed set-points in ``[0, v_max]`` (paper section 5.2)."""

    name = "force_control"
    config_class = ForceControlConfig

    def __init__(self, cfg, scenario, model):
        super().__init__(cfg, scenario, model)
        n = model.n
        self.plan = scenario.mode_plan
        self.t_start = start_times(cfg.start_time_s, n)
        self.breaks = np.unique(self.t_start)
        p = self.plan
        ref = np.zeros(n)
        ref[p.controlled] = p.link_ref_N[p.fc_link[p.controlled]]
        self._base = Controls.rolling(n, np.zeros(n), p.nominal_mps).with_(
            fc_active=p.controlled.astype(float), fc_link=p.fc_link, fc_sigma=p.fc_sigma, fc_ref_N=ref,
            fc_nominal_mps=p.nominal_mps, fc_kp=np.full(n, cfg.kp_mps_per_N), fc_ki=np.full(n, cfg.ki_mps_per_Ns),
            fc_vmax_mps=p.vmax_mps)

    def interval(self, t, y):
        return rolling_interval(t, self.t_start, self.breaks, self._base, "force control")

    def summary(self, result) -> dict:
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
            frac.append({"segment": int(k), "fraction_at_zero": float(np.mean(low)) if low.size else 0.0,
                         "fraction_at_max": float(np.mean(high)) if high.size else 0.0})
            if low.size and low[-1]:
                sat.append({"segment": int(k), "at": "zero"})
            elif high.size and high[-1]:
                sat.append({"segment": int(k), "at": "max_speed"})
        return {"force_control": {
            "free_segment": p.free_segment,
            "loops": [{"segment": int(k), "link": int(p.fc_link[k]), "side": "behind" if p.fc_sigma[k] > 0 else "ahead"}
                      for k in np.flatnonzero(p.controlled)],
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
        }}
