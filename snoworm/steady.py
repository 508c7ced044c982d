"""Steady-state solutions of one driven segment, by root finding (milliseconds, no ODE).

At steady driving on uniform terrain a segment's wheels all run at the same slip ``i`` and

    n_wheels (F_t(i) - F_tr(V)) = D                 (chassis force balance, docs/model.md section 4)
    T_m = R_w (F_t - F_tr) + T_rr                   (wheel torque balance, per wheel)

with ``V = R_w w (1 - i)`` and drawbar ``D`` (tow force).  These are the same terrain kernels
as the dynamic simulation (:mod:`snoworm.terrain`), so the two agree to solver tolerance.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from . import terrain
from .terrain import TerrainParams

__all__ = ["SteadyState", "Immobilised", "steady_state", "max_drawbar_N", "net_force_per_segment_N",
           "immobilisation_limit_xt", "segment_geometry", "state_at_slip", "peak_slip"]


class Immobilised(ValueError):
    """No steady forward motion exists: the drawbar exceeds what the wheels can pull."""


@dataclass(frozen=True)
class SteadyState:
    """Steady driving of one segment.

    Attributes
    ----------
    slip : float
        Wheel slip (Eq. 1).
    ground_speed_mps : float
        Ground speed V [m/s].
    wheel_speed_mps : float
        Wheel circumferential speed R_w w [m/s].
    torque_Nm : float
        Motor output torque per wheel [N m].
    traction_N, resistance_N : float
        Tractive and resistance force per wheel [N].
    drawbar_N : float
        Drawbar pull of the segment [N].
    """

    slip: float
    ground_speed_mps: float
    wheel_speed_mps: float
    torque_Nm: float
    traction_N: float
    resistance_N: float
    drawbar_N: float


def segment_geometry(seg):
    """``(n_wheels, F_n per wheel, R_w)`` of a segment parameter object (SegmentConfig or similar)."""
    n_wheels = 2 * int(seg.wheels_per_axle)
    F_n = seg.mass_kg * seg.gravity_mps2 / n_wheels
    return n_wheels, F_n, seg.wheel_radius_m


def net_force_per_segment_N(i, X, wheel_speed_mps, seg, tp: TerrainParams, moving: bool = False):
    """Drawbar a segment develops at slip ``i`` (vectorised over ``i`` and ``X``).

    With ``moving=True`` the resistance takes its full forward-motion value ``sgn(V) = 1``
    (the smooth sign would let it vanish as ``i -> 1``, ``V -> 0``): the drawbar available
    while the segment actually moves forward.
    """
    n_w, F_n, _ = segment_geometry(seg)
    V = wheel_speed_mps * (1.0 - np.asarray(i, float))
    if moving:
        V = np.full_like(V, np.inf)
    return n_w * (terrain.traction_force(i, F_n, X, tp) - terrain.resistance_force(V, F_n, X, tp))


def _state(i, X, wheel_speed_mps, seg, tp):
    n_w, F_n, R = segment_geometry(seg)
    V = wheel_speed_mps * (1.0 - i)
    Ft = float(terrain.traction_force(i, F_n, X, tp))
    Ftr = float(terrain.resistance_force(V, F_n, X, tp))
    Trr = float(terrain.resistance_torque(wheel_speed_mps, F_n, X, R, tp))
    T = float(terrain.wheel_reaction_torque(Ft, Ftr, Trr, R, tp))
    return SteadyState(float(i), float(V), float(wheel_speed_mps), T, Ft, Ftr, n_w * (Ft - Ftr))


def state_at_slip(i, X, wheel_speed_mps, seg, tp: TerrainParams) -> SteadyState:
    """Forces and torque of a segment whose wheels run at slip ``i`` and wheel speed ``R_w w``.

    Not necessarily an equilibrium: its ``drawbar_N`` is whatever the wheels develop at ``i``.
    The calibration uses it to score an immobilised case (``i = 1``).
    """
    return _state(float(i), X, float(wheel_speed_mps), seg, tp)


def peak_slip(X, wheel_speed_mps, seg, tp):
    """Slip at which a segment's drawbar in forward motion peaks (the stable branch lies below it)."""
    res = minimize_scalar(lambda i: -net_force_per_segment_N(i, X, wheel_speed_mps, seg, tp, moving=True),
                          bounds=(0.0, 1.0), method="bounded", options={"xatol": 1e-10})
    return float(res.x)


def max_drawbar_N(X, seg, tp: TerrainParams, wheel_speed_mps: float) -> float:
    """Largest steady drawbar of one segment on terrain ``X`` [N] (negative: immobilised).

    ``wheel_speed_mps`` is the wheel speed ``R_w w`` at which the slip and the resistance torque
    are evaluated [m/s].
    """
    i_pk = peak_slip(X, wheel_speed_mps, seg, tp)
    return float(net_force_per_segment_N(i_pk, X, wheel_speed_mps, seg, tp, moving=True))


def steady_state(X, seg, tp: TerrainParams, *, drawbar_N: float = 0.0, wheel_speed_mps: float | None = None,
                 ground_speed_mps: float | None = None) -> SteadyState:
    """Steady slip, speed and torque of one segment at terrain ``X`` and drawbar ``drawbar_N``.

    Give either the wheel speed ``R_w w`` (the controller's set-point) or the ground speed.
    The solution is the lower-slip root (the stable branch, below the peak of the net force).

    Raises
    ------
    Immobilised
        If the drawbar exceeds the segment's maximum drawbar on this terrain.
    """
    if (wheel_speed_mps is None) == (ground_speed_mps is None):
        raise ValueError("give exactly one of wheel_speed_mps or ground_speed_mps")
    if ground_speed_mps is not None:
        # V fixed: solve for the slip with the wheel speed V / (1 - i)
        V = float(ground_speed_mps)

        def g(i):
            return net_force_per_segment_N(i, X, V / (1.0 - i), seg, tp) - drawbar_N
        i_hi = min(peak_slip(X, V, seg, tp), 1.0 - 1e-9)
        if net_force_per_segment_N(i_hi, X, V, seg, tp, moving=True) < drawbar_N:
            raise Immobilised(f"drawbar {drawbar_N:.1f} N exceeds the maximum on X_t = {X:g}")
        i = brentq(g, 0.0, i_hi, xtol=1e-13) if g(0.0) < 0 else 0.0
        return _state(i, X, V / (1.0 - i), seg, tp)
    w = float(wheel_speed_mps)
    i_hi = peak_slip(X, w, seg, tp)

    def f(i):
        return net_force_per_segment_N(i, X, w, seg, tp) - drawbar_N
    d_max = float(net_force_per_segment_N(i_hi, X, w, seg, tp, moving=True))
    if d_max < drawbar_N:
        raise Immobilised(f"drawbar {drawbar_N:.1f} N exceeds the maximum {d_max:.1f} N on X_t = {X:g}")
    i = brentq(f, 0.0, i_hi, xtol=1e-13) if f(0.0) < 0 else 0.0
    return _state(i, X, w, seg, tp)


def immobilisation_limit_xt(seg, tp: TerrainParams, *, wheel_speed_mps: float, drawbar_N: float = 0.0) -> float:
    """Terrain coefficient below which a segment cannot pull ``drawbar_N`` (0.586 for FrostyBoy, no tow)."""
    return float(brentq(lambda X: max_drawbar_N(X, seg, tp, wheel_speed_mps) - drawbar_N, 0.05, 1.0, xtol=1e-10))
