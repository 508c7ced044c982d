"""Steady-state solutions of one driven segment, by root finding (milliseconds, no ODE).

At steady driving on uniform terrain a segment's wheels all run at the same slip ``i`` and

    n_wheels (F_t(i) - F_tr(V)) - m g sin(theta) = D     (chassis force balance, docs/model.md sections 4, 7)
    T_m = R_w (F_t - F_tr) + T_rr                   (wheel torque balance, per wheel)

with ``V = R_w w (1 - i)``, drawbar ``D`` (tow force) and grade ``theta`` (``grade_deg``, 0: level;
the normal loads are those of :func:`snoworm.terrain.normal_load_N`).  These are the same terrain
kernels as the dynamic simulation (:mod:`snoworm.terrain`), so the two agree to solver tolerance.
Forces and torques per wheel are the means over the two axles (they differ with pitch load transfer).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from . import terrain
from .slope import MAX_GRADE_DEG
from .terrain import TerrainParams

__all__ = [
    "SteadyState",
    "Immobilised",
    "steady_state",
    "max_drawbar_N",
    "net_force_per_segment_N",
    "immobilisation_limit_xt",
    "segment_geometry",
    "state_at_slip",
    "peak_slip",
    "max_grade_deg",
    "tow_drawbar_N",
    "starting_traction_coefficient",
    "from_rest_drawbar_N",
    "max_grade_from_rest_deg",
    "max_grade_below_slip_deg",
    "axle_loads_N",
]


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


def axle_loads_N(seg, grade_deg: float = 0.0):
    """``(F_n front, F_n rear, gravity force)`` of a segment on a constant grade (:func:`terrain.normal_load_N`)."""
    n_w, F_n, _ = segment_geometry(seg)
    th = np.radians(grade_deg)
    transfer = 2.0 * seg.com_height_m / seg.wheelbase_m if seg.wheelbase_m > 0 else 0.0
    Fn = terrain.normal_load_N(F_n, np.sin(th), np.cos(th), transfer)
    return Fn[..., 0], Fn[..., 1], terrain.gravity_force_N(seg.mass_kg, seg.gravity_mps2, np.sin(th))


def net_force_per_segment_N(
    i, X, wheel_speed_mps, seg, tp: TerrainParams, moving: bool = False, grade_deg: float = 0.0
):
    """Drawbar a segment develops at slip ``i`` on grade ``grade_deg`` (vectorised over ``i`` and ``X``).

    With ``moving=True`` the resistance takes its full forward-motion value ``sgn(V) = 1``
    (the smooth sign would let it vanish as ``i -> 1``, ``V -> 0``): the drawbar available
    while the segment actually moves forward.
    """
    n_w, _, _ = segment_geometry(seg)
    V = wheel_speed_mps * (1.0 - np.asarray(i, float))
    if moving:
        V = np.full_like(V, np.inf)
    if grade_deg == 0.0:
        F_n = segment_geometry(seg)[1]
        return n_w * (terrain.traction_force(i, F_n, X, tp) - terrain.resistance_force(V, F_n, X, tp))
    Ff, Fr, G = axle_loads_N(seg, grade_deg)
    per_axle = [terrain.traction_force(i, F, X, tp) - terrain.resistance_force(V, F, X, tp) for F in (Ff, Fr)]
    return n_w / 2 * (per_axle[0] + per_axle[1]) + G


def _state(i, X, wheel_speed_mps, seg, tp, grade_deg=0.0):
    n_w, F_n, R = segment_geometry(seg)
    V = wheel_speed_mps * (1.0 - i)
    G = 0.0
    if grade_deg != 0.0:  # per axle loads on the grade: forces and torque are the axles' means
        Ff, Fr, G = axle_loads_N(seg, grade_deg)
        F_n = np.array([Ff, Fr], float)
    Ft = terrain.traction_force(i, F_n, X, tp)
    Ftr = terrain.resistance_force(V, F_n, X, tp)
    Trr = terrain.resistance_torque(wheel_speed_mps, F_n, X, R, tp)
    T = float(np.mean(terrain.wheel_reaction_torque(Ft, Ftr, Trr, R, tp)))
    Ft, Ftr = float(np.mean(Ft)), float(np.mean(Ftr))
    return SteadyState(float(i), float(V), float(wheel_speed_mps), T, Ft, Ftr, n_w * (Ft - Ftr) + float(G))


def state_at_slip(i, X, wheel_speed_mps, seg, tp: TerrainParams) -> SteadyState:
    """Forces and torque of a segment whose wheels run at slip ``i`` and wheel speed ``R_w w``.

    Not necessarily an equilibrium: its ``drawbar_N`` is whatever the wheels develop at ``i``.
    The calibration uses it to score an immobilised case (``i = 1``).
    """
    return _state(float(i), X, float(wheel_speed_mps), seg, tp)


def peak_slip(X, wheel_speed_mps, seg, tp, grade_deg: float = 0.0):
    """Slip at which a segment's drawbar in forward motion peaks (the stable branch lies below it)."""
    res = minimize_scalar(
        lambda i: -net_force_per_segment_N(i, X, wheel_speed_mps, seg, tp, moving=True, grade_deg=grade_deg),
        bounds=(0.0, 1.0),
        method="bounded",
        options={"xatol": 1e-10},
    )
    return float(res.x)


def max_drawbar_N(X, seg, tp: TerrainParams, wheel_speed_mps: float, grade_deg: float = 0.0) -> float:
    """Largest steady drawbar of one segment on terrain ``X`` and grade ``grade_deg`` [N] (negative: immobilised).

    ``wheel_speed_mps`` is the wheel speed ``R_w w`` at which the slip and the resistance torque
    are evaluated [m/s].  On a grade it is ``cos(theta)`` times the level value minus ``m g sin(theta)``
    (the laws are linear in the normal load).
    """
    i_pk = peak_slip(X, wheel_speed_mps, seg, tp, grade_deg)
    return float(net_force_per_segment_N(i_pk, X, wheel_speed_mps, seg, tp, moving=True, grade_deg=grade_deg))


def tow_drawbar_N(force_N, seg, grade_deg: float = 0.0, sled_mass_kg: float = 0.0, sled_friction: float = 0.0):
    """Steady pull of the towed load on a chain moving forward on a constant grade [N] (docs/model.md
    section 4, "Towed load"): ``D(theta) = force_N + m_s g (sin(theta) + mu cos(theta))``, the constant force
    plus a sled's gravity and friction (:func:`terrain.sled_force_N` at full forward motion; ``g`` the
    segment's)."""
    th = np.radians(grade_deg)
    sled = terrain.sled_force_N(sled_mass_kg * seg.gravity_mps2, sled_friction, np.sin(th), np.cos(th), 1.0)
    return float(force_N + sled)


def _grade_root(f):
    """The grade [deg] where ``f`` (falling with the grade) crosses 0 in [-MAX_GRADE_DEG, MAX_GRADE_DEG];
    ``MAX_GRADE_DEG`` when it is >= 0 even there, None when < 0 even at ``-MAX_GRADE_DEG``."""
    if f(MAX_GRADE_DEG) >= 0:
        return MAX_GRADE_DEG
    if f(-MAX_GRADE_DEG) < 0:
        return None
    return float(brentq(f, -MAX_GRADE_DEG, MAX_GRADE_DEG, xtol=1e-9))


def max_grade_deg(
    X,
    seg,
    tp: TerrainParams,
    wheel_speed_mps: float,
    drawbar_N: float = 0.0,
    *,
    segments: int = 1,
    sled_mass_kg: float = 0.0,
    sled_friction: float = 0.0,
) -> float | None:
    """Steepest grade [deg] on which a rolling segment still pulls ``drawbar_N`` (its share of the tow's
    constant force) at wheel speed ``wheel_speed_mps`` on terrain ``X`` (docs/model.md section 7).

    A sled (``sled_mass_kg``, ``sled_friction``) adds its pull on the grade, shared by ``segments``
    segments: the root of ``max_drawbar_N(X, grade) = drawbar_N + m_s g (sin + mu cos) / segments``
    (:func:`tow_drawbar_N`).  The root lies in [-MAX_GRADE_DEG, MAX_GRADE_DEG] (the balance falls
    monotonically with the grade); ``MAX_GRADE_DEG`` when the segment pulls it even there, None when it
    cannot even downhill at ``-MAX_GRADE_DEG``.  The motor torque limit is not applied: check
    ``steady_state(..., grade_deg=...).torque_Nm`` against it.
    """

    def f(g):
        load = _load_N(seg, g, drawbar_N, segments, sled_mass_kg, sled_friction)
        return max_drawbar_N(X, seg, tp, wheel_speed_mps, grade_deg=g) - load

    return _grade_root(f)


def steady_state(
    X,
    seg,
    tp: TerrainParams,
    *,
    drawbar_N: float = 0.0,
    wheel_speed_mps: float | None = None,
    ground_speed_mps: float | None = None,
    grade_deg: float = 0.0,
) -> SteadyState:
    """Steady slip, speed and torque of one segment at terrain ``X``, drawbar ``drawbar_N`` and grade ``grade_deg``.

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
            return net_force_per_segment_N(i, X, V / (1.0 - i), seg, tp, grade_deg=grade_deg) - drawbar_N

        i_hi = min(peak_slip(X, V, seg, tp, grade_deg), 1.0 - 1e-9)
        if net_force_per_segment_N(i_hi, X, V, seg, tp, moving=True, grade_deg=grade_deg) < drawbar_N:
            raise Immobilised(f"drawbar {drawbar_N:.1f} N exceeds the maximum on X_t = {X:g}")
        i = brentq(g, 0.0, i_hi, xtol=1e-13) if g(0.0) < 0 else 0.0
        return _state(i, X, V / (1.0 - i), seg, tp, grade_deg)
    w = float(wheel_speed_mps)
    i_hi = peak_slip(X, w, seg, tp, grade_deg)

    def f(i):
        return net_force_per_segment_N(i, X, w, seg, tp, grade_deg=grade_deg) - drawbar_N

    d_max = float(net_force_per_segment_N(i_hi, X, w, seg, tp, moving=True, grade_deg=grade_deg))
    if d_max < drawbar_N:
        raise Immobilised(f"drawbar {drawbar_N:.1f} N exceeds the maximum {d_max:.1f} N on X_t = {X:g}")
    i = brentq(f, 0.0, i_hi, xtol=1e-13) if f(0.0) < 0 else 0.0
    return _state(i, X, w, seg, tp, grade_deg)


def immobilisation_limit_xt(seg, tp: TerrainParams, *, wheel_speed_mps: float, drawbar_N: float = 0.0) -> float:
    """Terrain coefficient below which a segment cannot pull ``drawbar_N`` (0.586 for FrostyBoy, no tow)."""
    return float(brentq(lambda X: max_drawbar_N(X, seg, tp, wheel_speed_mps) - drawbar_N, 0.05, 1.0, xtol=1e-10))


# ------------------------------------------------------------------ limits in field terms (docs/model.md section 7)
def _load_N(seg, grade_deg, drawbar_N, segments, sled_mass_kg, sled_friction):
    """A segment's share of the tow on a grade: ``drawbar_N`` plus the sled's steady pull over ``segments``."""
    return drawbar_N + tow_drawbar_N(0.0, seg, grade_deg, sled_mass_kg, sled_friction) / segments


def starting_traction_coefficient(X, tp: TerrainParams) -> float:
    """Traction per unit normal load that a wheel spinning up from rest develops, ``F_t / F_n``
    (docs/model.md section 7, "Starting from rest"): Eq. 2 at slip 1.

    At ``V = 0`` the regularised slip of Eq. 1 is 1 as soon as the wheel turns, past the Magic
    Formula's peak.  With the shear-displacement standstill law (``standstill: shear``) the slip
    ``j / K`` of a wheel started at the rolling speed reaches 1 within ``K / (R_w w)`` (14 ms for
    K = 2.5 cm at 1.8 m/s), before the chain moves, so the start is the same; measured: hill starts
    on X_t 1.0 up to 11.5-11.6 deg (regularised) and 11.7-11.8 deg (shear), this limit 11.4 deg.
    """
    return float(terrain.traction_force(1.0, 1.0, X, tp))


def from_rest_drawbar_N(X, seg, tp: TerrainParams, grade_deg: float = 0.0) -> float:
    """Drawbar a segment at rest on uniform terrain ``X`` and grade ``grade_deg`` develops as it starts [N].

    Each wheel pulls with the starting traction (:func:`starting_traction_coefficient` times its normal
    load), at most what the motor's stall torque ``T_s = min(T_max, k_w w_nl)`` turns against the
    resistance torque, ``(T_s - T_rr) / R_w``; the segment moves only against the full resistance of
    Eq. 3 (``sgn(V) = 1``) and gravity.  Negative: the segment cannot start.
    """
    n_w, _, R = segment_geometry(seg)
    Ff, Fr, G = axle_loads_N(seg, grade_deg)
    c = starting_traction_coefficient(X, tp)
    stall = min(seg.torque_limit_Nm, seg.motor_slope_Nms_per_rad * seg.no_load_speed_radps)
    total = 0.0
    for F in (Ff, Fr):
        torque = float(terrain.resistance_torque(np.inf, F, X, R, tp))
        Ft = min(c * F, (stall - torque) / R)
        total += Ft - float(terrain.resistance_force(np.inf, F, X, tp))
    return float(n_w / 2 * total + G)


def max_grade_from_rest_deg(
    X,
    seg,
    tp: TerrainParams,
    drawbar_N: float = 0.0,
    *,
    segments: int = 1,
    sled_mass_kg: float = 0.0,
    sled_friction: float = 0.0,
) -> float | None:
    """Steepest grade [deg] on which a chain at rest starts rolling: the root of
    ``from_rest_drawbar_N(grade) = drawbar_N + sled / segments`` (the sled moving, as the chain must
    pull it once it moves; docs/model.md section 7).  ``MAX_GRADE_DEG`` / None as :func:`max_grade_deg`;
    a negative value is the downhill grade the chain needs to start at all."""
    return _grade_root(
        lambda g: from_rest_drawbar_N(X, seg, tp, g) - _load_N(seg, g, drawbar_N, segments, sled_mass_kg, sled_friction)
    )


def max_grade_below_slip_deg(
    X,
    seg,
    tp: TerrainParams,
    wheel_speed_mps: float,
    slip_cap: float,
    drawbar_N: float = 0.0,
    *,
    segments: int = 1,
    sled_mass_kg: float = 0.0,
    sled_friction: float = 0.0,
) -> float | None:
    """Steepest grade [deg] a rolling chain climbs with its steady slip at most ``slip_cap``.

    Below the peak slip the drawbar grows with the slip, so the steady slip is at most the cap exactly
    where the drawbar at the cap (or at the peak, if the cap lies beyond it) carries the load: the root
    of ``net_force_per_segment_N(min(cap, peak), grade, moving) = load(grade)``
    (docs/model.md section 7).  ``MAX_GRADE_DEG`` / None as :func:`max_grade_deg`.
    """
    i = min(float(slip_cap), peak_slip(X, wheel_speed_mps, seg, tp))

    def f(g):
        D = float(net_force_per_segment_N(i, X, wheel_speed_mps, seg, tp, moving=True, grade_deg=g))
        return D - _load_N(seg, g, drawbar_N, segments, sled_mass_kg, sled_friction)

    return _grade_root(f)
