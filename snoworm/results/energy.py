"""Energy of a run: electrical energy drawn, energy per metre, cost of transport, energy balance.

Beyond the paper (which reports no energy), computed after the solve from the result's series
(:class:`~snoworm.results.result.Result`), one definition for single runs, sweeps and the mobility map.

Definitions
-----------
Motors (per segment).  The motor rows of docs/model.md section 1 give the torque *at the wheel* with
the 20 % drivetrain loss already folded in (paper section 3), so the mechanical power at the
wheels is ``P_m = n_w sum_axles T_m w``.  Electrical power is the motoring power divided by the
drivetrain efficiency (``vehicle.segment.drivetrain_efficiency``, 0.8 [paper]):
``P_el = max(T_m w, 0) / eta`` per wheel.  Braking power (``T_m w < 0``) is not recovered
(counted as 0, no regeneration), and holding a locked wheel (``w = 0``) costs nothing: the
model has no winding resistance, so stall current losses are not represented [assumed].

Prismatic joints (per link).  The actuator power is ``P_j = -F_spring ds/dt`` (the actuator is
in series with the link spring, ``Result.links['joint_power_W']``).  Electrical energy is the
positive mechanical work divided by ``vehicle.links.joint_efficiency`` [assumed]; work done on
the actuator (``P_j < 0``) is not recovered and holding a force at constant length costs nothing.

Per metre and cost of transport use the distance of the chain's mean position along the track (the
route as driven): ``E / d`` and ``CoT = E / (m_total g d)`` (dimensionless).  On a grade
(docs/model.md section 7) the elevation gained is that of the chain's mean height ``dz`` (each
segment's wheelbase-mean elevation), and the energy per metre climbed is ``E / dz`` (None unless
the chain climbed).
"""

from __future__ import annotations

import numpy as np

__all__ = ["energy_metrics", "energy_balance", "energy_along"]


def _trapz(y, t):
    if len(t) < 2:
        return np.zeros(np.shape(y)[1:])
    return np.trapezoid(y, t, axis=0)


def _cumtrapz(y, t):
    """Cumulative trapezoid integral of ``y`` (n_t, ...) over ``t`` along axis 0, starting at 0."""
    y = np.asarray(y, float)
    out = np.zeros_like(y)
    if len(t) >= 2:
        dt = np.diff(t).reshape((-1,) + (1,) * (y.ndim - 1))
        out[1:] = np.cumsum(0.5 * (y[1:] + y[:-1]) * dt, axis=0)
    return out


def energy_along(result) -> dict:
    """The run's electrical energy as it accumulates, on the output times (same definitions as
    :func:`energy_metrics`, whose totals are the last values).

    Returns
    -------
    dict
        ``t_s`` (n_t,), ``distance_m`` (n_t,: mean advance of the segments since the start),
        ``motor_electrical_J`` and ``joint_electrical_J`` (n_t,: summed over segments/links),
        ``total_electrical_J`` (n_t,).
    """
    t = np.asarray(result.t, float)
    motor = _cumtrapz(result.segments["motor_electrical_power_W"].sum(1), t)
    Pj = result.links["joint_power_W"]
    joint = (
        _cumtrapz(np.maximum(Pj, 0.0).sum(1), t) / result.scenario.vehicle.links.joint_efficiency
        if Pj.shape[1]
        else np.zeros_like(t)
    )
    x = result.segments["x_m"]
    return {
        "t_s": t,
        "distance_m": (x - x[:1]).mean(1) if t.size else t,
        "motor_electrical_J": motor,
        "joint_electrical_J": joint,
        "total_electrical_J": motor + joint,
    }


def energy_metrics(result) -> dict:
    """Electrical energy, energy per metre and cost of transport of a run.

    Parameters
    ----------
    result : Result
        A finished simulation.

    Returns
    -------
    dict
        ``motor_electrical_J`` (per segment), ``motor_mechanical_J`` (net, per segment),
        ``motor_braking_J`` (mechanical energy absorbed while braking, per segment, <= 0),
        ``joint_mechanical_J`` (positive work, per link), ``joint_electrical_J`` (per link),
        ``motor_electrical_total_J``, ``joint_electrical_total_J``, ``total_electrical_J``,
        ``distance_m``, ``energy_per_metre_J_per_m`` and ``cost_of_transport`` (None when the
        chain did not advance), ``mass_total_kg``, ``elevation_gain_m`` and
        ``energy_per_metre_climbed_J_per_m`` (None unless the chain climbed).
    """
    sc = result.scenario
    t = result.t
    P = result.segments["motor_power_W"]
    motor_el = _trapz(result.segments["motor_electrical_power_W"], t)
    motor_mech = _trapz(P, t)
    braking = _trapz(np.minimum(P, 0.0), t)
    Pj = result.links["joint_power_W"]
    joint_mech = _trapz(np.maximum(Pj, 0.0), t) if Pj.shape[1] else np.zeros(0)
    joint_el = joint_mech / sc.vehicle.links.joint_efficiency
    x = result.segments["x_m"]
    dist = float(np.mean(x[-1] - x[0])) if t.size else 0.0
    segs = sc.vehicle.segment_params()
    mass = float(sum(s.mass_kg for s in segs))
    g = float(segs[0].gravity_mps2)
    total = float(motor_el.sum() + joint_el.sum())
    moved = dist > 1e-6
    z = result.segments["elevation_m"]
    rise = float(np.mean(z[-1] - z[0])) if t.size else 0.0
    return {
        "motor_electrical_J": motor_el.tolist(),
        "motor_mechanical_J": motor_mech.tolist(),
        "motor_braking_J": braking.tolist(),
        "joint_mechanical_J": joint_mech.tolist(),
        "joint_electrical_J": joint_el.tolist(),
        "motor_electrical_total_J": float(motor_el.sum()),
        "joint_electrical_total_J": float(joint_el.sum()),
        "total_electrical_J": total,
        "distance_m": dist,
        "mass_total_kg": mass,
        "energy_per_metre_J_per_m": total / dist if moved else None,
        "cost_of_transport": total / (mass * g * dist) if moved else None,
        "elevation_gain_m": rise,
        "energy_per_metre_climbed_J_per_m": total / rise if rise > 1e-6 else None,
    }


def _tow_force_N(result):
    """The towed load on the rear segment over time [N]: the constant ``tow.force_N``, or with a sled
    (docs/model.md section 4, "Towed load") what the run's link and connector forces say it was,
    ``T_{N-2} - connector_net_{N-1}`` (the connector force on the rear segment is the last link's
    pull minus the tow)."""
    sc = result.scenario
    if not sc.tow.mass_kg > 0:
        return sc.tow.force_N
    pull = result.links["force_N"][:, -1] if sc.vehicle.segments > 1 else 0.0
    return pull - result.segments["connector_net_N"][:, -1]


def energy_balance(result) -> dict:
    """Mechanical energy balance of a run (every term in J; the residual should be ~0).

    ``motor + joint = terrain + damper + tow + d(kinetic) + d(spring) + d(potential) + residual`` with
    motor and joint the net mechanical work of the motors (at the wheels) and the prismatic
    actuators, terrain the power dissipated at the wheel-terrain contacts (slip and
    resistance, :meth:`ChainModel.evaluate`), damper the link dampers' dissipation, tow the work
    done against the towed load, kinetic the chassis and wheel kinetic energy, and potential
    ``sum_k m_k g dz_k`` with ``z_k`` the segment's wheelbase-mean elevation (docs/model.md section 7;
    exactly the work against gravity along the track, 0 on level ground).  The wheel
    kinetic energy uses the mean of each segment's two axle speeds (exact on uniform terrain).
    Drivetrain losses are outside this balance: ``electrical - motoring mechanical`` work.
    """
    sc = result.scenario
    t = result.t
    segs = sc.vehicle.segment_params()
    m = np.array([s.mass_kg for s in segs])
    J = np.array([s.wheel_inertia_kgm2 * 2 * s.wheels_per_axle for s in segs])
    R = np.array([s.wheel_radius_m for s in segs])
    k = sc.vehicle.links.stiffness_N_per_m
    v = result.segments["v_mps"]
    w = result.segments["wheel_speed_mps"] / R
    spring = result.links["spring_force_N"]  # the link spring (in series with damper and actuator)
    kinetic = 0.5 * (m * v**2).sum(1) + 0.5 * (J * w**2).sum(1)
    spring_E = 0.5 * (spring**2).sum(1) / k
    terms = {
        "motor_J": float(np.trapezoid(result.segments["motor_power_W"].sum(1), t)),
        "joint_J": float(np.trapezoid(result.links["joint_power_W"].sum(1), t)),
        "terrain_J": float(np.trapezoid(result.segments["terrain_dissipation_W"].sum(1), t)),
        "damper_J": float(np.trapezoid(result.links["damper_power_W"].sum(1), t)),
        "tow_J": float(np.trapezoid(_tow_force_N(result) * v[:, -1], t)),
        "kinetic_change_J": float(kinetic[-1] - kinetic[0]),
        "spring_change_J": float(spring_E[-1] - spring_E[0]),
        "potential_change_J": float(
            np.sum(
                m
                * np.array([s.gravity_mps2 for s in segs])
                * (result.segments["elevation_m"][-1] - result.segments["elevation_m"][0])
            )
        ),
    }
    terms["residual_J"] = (
        terms["motor_J"]
        + terms["joint_J"]
        - terms["terrain_J"]
        - terms["damper_J"]
        - terms["tow_J"]
        - terms["kinetic_change_J"]
        - terms["spring_change_J"]
        - terms["potential_change_J"]
    )
    terms["throughput_J"] = float(
        np.trapezoid(np.abs(result.segments["motor_power_W"]).sum(1) + np.abs(result.links["joint_power_W"]).sum(1), t)
    )
    return terms
