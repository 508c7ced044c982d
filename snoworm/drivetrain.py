"""Motor + 40:1 gearbox envelope at the wheel (paper section 3, docs/model.md section 1).

A pure NumPy kernel, vectorised over wheels/axles/segments/batch members; the chain dynamics
call it.  All torques are at the wheel, per wheel, with the 20 % drivetrain loss already folded
in.  The wheel-speed controller that commands this motor is a control law
(:func:`snoworm.feedback.speed_pi`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["motor_envelope"]


def motor_envelope(omega, slope_Nms, no_load_radps, torque_max_Nm):
    """Torque limits of the motor at the wheel for wheel speed ``omega`` [rad/s].

    ``T_hi = min(T_max, k_w (w_nl - w))`` and ``T_lo = -min(T_max, k_w (w_nl + w))``
    (docs/model.md section 1; paper: motor and gearbox "combined into a single equation").

    Parameters
    ----------
    omega : array_like
        Wheel speed [rad/s].
    slope_Nms : array_like
        Slope ``k_w`` of the torque-speed line at the wheel [N m s/rad].
    no_load_radps : array_like
        No-load wheel speed ``w_nl`` [rad/s].
    torque_max_Nm : array_like
        Torque limit ``T_max`` at the wheel [N m].

    Returns
    -------
    (T_lo, T_hi) : tuple of ndarray
        Lower and upper torque limits [N m].
    """
    T_hi = np.minimum(torque_max_Nm, slope_Nms * (no_load_radps - omega))
    T_lo = -np.minimum(torque_max_Nm, slope_Nms * (no_load_radps + omega))
    return T_lo, T_hi
