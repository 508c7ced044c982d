r"""The force-control mode's plan: targets -> link-force references, checked and predicted (paper section 5.2).

:func:`plan` runs once per run, when the run is assembled (``ForceControlConfig.prepare``, called by
the mode; ``snoworm validate`` calls it too); :class:`~snoworm.modes.force_control.ForceControlMode` runs the
loops on the :class:`ForcePlan`.  All of it is steady-state root finding on the laws
(:mod:`snoworm.steady`), before any integration.

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
:class:`~snoworm.config.schema.ScenarioError` when the run is assembled (before any solve; ``snoworm
validate`` checks it too), never left to wind up.
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

import numpy as np
from scipy.optimize import brentq

from .. import steady, terrain
from ..config.schema import ScenarioError

__all__ = ["ForcePlan", "plan", "available_drawbar_N"]


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

    wheel_net_N: np.ndarray  # (N,) steady net wheel force W_k
    link_ref_N: np.ndarray  # (N-1,) link-force references T_k
    free_segment: int
    controlled: np.ndarray  # (N,) bool: runs a force loop
    fc_link: np.ndarray  # (N,) int: controlled link (N-1 for the free segment, unused)
    fc_sigma: np.ndarray  # (N,) +1 link behind, -1 link ahead
    available_drawbar_N: np.ndarray  # (N,)
    limited_by: tuple  # (N,) "terrain" or "motor"
    xt: np.ndarray  # (N,) X_t used for the checks
    nominal_mps: np.ndarray  # (N,)
    vmax_mps: np.ndarray  # (N,)
    predicted_ground_speed_mps: float
    predicted_setpoint_mps: np.ndarray  # (N,)
    predicted_slip: np.ndarray  # (N,)


def _shares(rule, idx, W_total, xt, segs, tp, nominal):
    """Fractions (summing to 1) of ``W_total`` for the segments ``idx`` under a named rule."""
    if rule == "even":
        w = np.ones(len(idx))
    elif rule == "drawbar":
        w = np.array([available_drawbar_N(xt[k], segs[k], tp, nominal[k])[0] for k in idx])
        if np.any(w <= 0):
            bad = [int(k) for k, v in zip(idx, w) if v <= 0]
            raise ScenarioError(
                f"mode.targets.load_shares: drawbar shares need every sharing segment to have a "
                f"positive available drawbar; segment(s) {bad} have none on this terrain."
            )
    else:  # inverse_slip
        even = W_total / len(idx)
        slips = []
        for k in idx:
            i = _slip_for(even, xt[k], segs[k], tp, wheel_speed_mps=nominal[k])
            if i is None or i <= 0:
                raise ScenarioError(
                    f"mode.targets.load_shares: inverse_slip needs a positive steady slip for each "
                    f"sharing segment at an even share ({even:.1f} N); segment {int(k)} has "
                    f"{'none' if i is None else f'{i:.3g}'}. Use even or drawbar."
                )
            slips.append(i)
        w = 1.0 / np.array(slips)
    return w / w.sum()


@dataclass(frozen=True)
class _Chain:
    """The chain on its terrain, as the plan's checks need it: per segment the X_t under it, its
    parameters and its nominal and largest wheel-speed set-points [m/s]; the terrain model."""

    xt: np.ndarray
    segs: list
    tp: terrain.TerrainParams
    nominal: np.ndarray
    vmax: np.ndarray


def _check_drawbar(W, T, F_tow, ch: _Chain, tpath):
    """Every segment can pull its net wheel force ``W`` (and the chain the tow); the available drawbar."""
    n = len(W)
    xt = ch.xt
    avail, why = zip(*(available_drawbar_N(xt[j], ch.segs[j], ch.tp, ch.nominal[j]) for j in range(n)))
    avail = np.array(avail)
    if F_tow > avail.sum() + 1e-9:
        raise ScenarioError(
            f"{tpath}: impossible target: the tow of {F_tow:g} N exceeds the drawbar the whole chain can pull, "
            f"{avail.sum():.1f} N (per segment {np.round(avail, 1).tolist()} N on X_t = {np.round(xt, 3).tolist()}); "
            "no load sharing can carry it. Lower tow.force_N or add segments."
        )
    for j in range(n):
        if W[j] > avail[j] + 1e-9:
            raise ScenarioError(
                f"{tpath}: impossible target: segment {j} would have to pull {W[j]:.1f} N (net wheel force; "
                f"link references {np.round(T, 1).tolist()} N, tow {F_tow:g} N) but can pull at most "
                f"{avail[j]:.1f} N on X_t = {xt[j]:g} (limited by the {why[j]}). Lower that segment's share, "
                f"or use load_shares: drawbar."
            )
    return avail, why


def _predict(W, f, controlled, ch: _Chain, path, tpath):
    """Predicted steady state: the free segment ``f`` sets the ground speed; ``(V, set-points, slips)``."""
    n = len(W)
    xt, segs, tp, nominal, vmax = ch.xt, ch.segs, ch.tp, ch.nominal, ch.vmax
    slip = np.full(n, np.nan)
    i_f = _slip_for(W[f], xt[f], segs[f], tp, wheel_speed_mps=nominal[f])
    if i_f is None:
        raise ScenarioError(
            f"{tpath}: impossible target: the free segment {f} cannot develop a net wheel force "
            f"of {W[f]:.1f} N at {nominal[f]:g} m/s on X_t = {xt[f]:g}."
        )
    slip[f] = i_f
    V = nominal[f] * (1.0 - i_f)
    sp = np.array(nominal, float)
    for j in np.flatnonzero(controlled):
        i = _slip_for(W[j], xt[j], segs[j], tp, ground_speed_mps=V)
        if i is None:
            raise ScenarioError(
                f"{tpath}: impossible target: segment {j} cannot develop a net wheel force of "
                f"{W[j]:.1f} N while moving at {V:.3f} m/s on X_t = {xt[j]:g} (it would need more "
                "braking than locked wheels give). Change the link forces."
            )
        slip[j] = i
        sp[j] = V / (1.0 - i)
        if sp[j] > vmax[j]:
            raise ScenarioError(
                f"{tpath}: impossible target: segment {j} would need a wheel-speed set-point of "
                f"{sp[j]:.3f} m/s, above max_speed_mps = {vmax[j]:.3f} m/s. Raise "
                f"{path}.max_speed_mps or lower the segment's share."
            )
    return V, sp, slip


def plan(cfg, sc, model, path="mode") -> ForcePlan:
    """Convert the targets of a :class:`~snoworm.modes.force_control.ForceControlConfig` to link-force
    references and check they are reachable (module docstring).

    Raises
    ------
    ScenarioError
        If a segment is asked for more drawbar than it can pull (or more braking than it can
        give) on the terrain, or a predicted steady set-point exceeds ``max_speed_mps``.
    """
    n = model.n
    segs = sc.vehicle.segment_params()
    tp = model.tp
    # the tow's steady pull on level ground (the plan is level: docs/model.md section 7), a sled's included
    F_tow = steady.tow_drawbar_N(sc.tow.force_N, segs[-1], 0.0, sc.tow.mass_kg, sc.tow.sled_friction)
    nominal = np.asarray(cfg.speed_mps, float) * np.ones(n)
    R = model.seg.wheel_radius_m
    vmax = np.full(n, cfg.max_speed_mps) if cfg.max_speed_mps is not None else R * model.seg.no_load_speed_radps
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
        s = (
            np.asarray(ls, float)
            if not isinstance(ls, str)
            else _shares(ls, np.arange(n), F_tow, xt, segs, tp, nominal)
        )
        W = s * F_tow
    T = np.cumsum(W)[:-1]
    # loop assignment around the free segment
    f = n - 1 if cfg.free_segment is None else int(cfg.free_segment)
    k = np.arange(n)
    controlled = k != f
    sigma = np.where(k < f, 1.0, -1.0)
    link = np.where(k < f, k, k - 1)
    link[f] = n - 1
    ch = _Chain(xt, segs, tp, nominal, vmax)
    avail, why = _check_drawbar(W, T, F_tow, ch, tpath)
    V, sp, slip = _predict(W, f, controlled, ch, path, tpath)
    return ForcePlan(
        W, T, f, controlled, link.astype(int), sigma, avail, tuple(why), xt, nominal, vmax, float(V), sp, slip
    )
