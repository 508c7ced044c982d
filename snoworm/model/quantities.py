"""Output quantities of a chain from its states: the one formula behind results and observations.

:func:`output_series` turns solved states (any number of samples) and the controls held while
they were reached into the documented per-segment and per-link quantities, in one vectorised
pass of the force kernel (:meth:`snoworm.dynamics.ChainModel.evaluate`).  The results
(:class:`snoworm.results.result.Result`) call it on every output sample after a solve; a controller's
observation (:mod:`snoworm.modes.command`) calls it on the one state at the start of a control
period, so the slip or motor torque a controller sees is the one the results report.
"""

from __future__ import annotations

import numpy as np

__all__ = ["output_series"]


def output_series(model, ys, ctl):
    """Per-segment and per-link quantities of states ``ys`` reached under controls ``ctl``.

    Parameters
    ----------
    model : ChainModel
        The assembled chain.
    ys : ndarray, shape ``(n_t, n_states)``
        Flat states (one row per sample).
    ctl : Controls
        The controls held while the states were reached (they set the motor torque).

    Returns
    -------
    (seg, lk) : tuple of dict
        ``seg``: name -> ``(n_t, N)`` (the keys of ``snoworm.results.result.SEGMENT_COLUMNS``);
        ``lk``: name -> ``(n_t, N-1)`` (the keys of ``snoworm.results.result.LINK_COLUMNS``).
    """
    eta = model.seg.drivetrain_efficiency
    L = model.layout
    Y = model.unpack(ys)
    dY, out = model.evaluate(Y, ctl, outputs=True)
    R = model.seg.wheel_radius_m
    nw = model.seg.wheels_per_axle
    w = out["omega"]
    Tm = out["motor_torque_Nm"]
    Ft = out["traction_axle_N"].sum(-1)
    Ftr = out["resistance_axle_N"].sum(-1)
    seg = {
        "x_m": Y[..., L.x],
        "v_mps": Y[..., L.v],
        "wheel_speed_mps": (w * R[:, None]).mean(-1),
        "slip": out["slip"].mean(-1),
        "traction_N": Ft,
        "resistance_N": Ftr,
        "net_force_N": Ft - Ftr,
        "motor_torque_Nm": Tm.mean(-1),
        "speed_setpoint_mps": np.array(out["speed_sp_mps"], float),
        "connector_net_N": out["link_net_N"],
        "xt": out["X"].mean(-1),
        "motor_power_W": (Tm * w).sum(-1) * nw,
        "terrain_dissipation_W": out["terrain_dissipation_W"],
        "motor_electrical_power_W": (np.maximum(Tm * w, 0.0)).sum(-1) * nw / eta,
    }
    x = seg["x_m"]
    # the grade under each segment and its potential-energy height (docs/model.md section 7)
    seg["grade_deg"] = np.degrees(np.arcsin(model.grade_terms(x)[0]))
    seg["elevation_m"] = (
        np.zeros(x.shape) if model.elevation is None else model.elevation.mean_elevation(x, model.seg.wheelbase_m / 2.0)
    )
    seg["gravity_N"] = np.asarray(out["gravity_N"], float)
    # slip-sinkage (terrain.model.sinkage: slip, docs/model.md section 2); zeros without it
    seg["sinkage_m"] = np.asarray(out["sinkage_m"], float).mean(-1)
    lk = {
        "force_N": out["link_force_N"],
        "length_m": x[..., :-1] - x[..., 1:],
        "spring_force_N": out["link_spring_N"],
        "damper_power_W": out["link_damper_W"],
    }
    if model.has_joints:
        s = Y[..., :-1, L.s]
        ds = dY[..., :-1, L.s]
        lk["extension_m"] = s
        # the actuator is in series with the link's spring-damper: it carries the link force
        lk["joint_power_W"] = -out["link_force_N"] * ds
    else:
        lk["extension_m"] = np.zeros_like(lk["length_m"])
        lk["joint_power_W"] = np.zeros_like(lk["length_m"])
    return seg, lk
