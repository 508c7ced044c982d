"""Motor + 40:1 gearbox envelope and the wheel-speed PI controller (paper section 3, MODEL.md section 1).

Pure NumPy kernels, vectorised over wheels/axles/segments; the chain dynamics call them.
All torques are at the wheel, per wheel, with the 20 % drivetrain loss already folded in.
"""
from __future__ import annotations

import numpy as np

__all__ = ["motor_envelope", "speed_pi"]


def motor_envelope(omega, slope_Nms, no_load_radps, torque_max_Nm):
    """Torque limits of the motor at the wheel for wheel speed ``omega`` [rad/s].

    ``T_hi = min(T_max, k_w (w_nl - w))`` and ``T_lo = -min(T_max, k_w (w_nl + w))``
    (MODEL.md section 1; paper: motor and gearbox "combined into a single equation").

    Returns
    -------
    (T_lo, T_hi) : tuple of ndarray
        Lower and upper torque limits [N m].
    """
    T_hi = np.minimum(torque_max_Nm, slope_Nms * (no_load_radps - omega))
    T_lo = -np.minimum(torque_max_Nm, slope_Nms * (no_load_radps + omega))
    return T_lo, T_hi


def speed_pi(omega_ref, omega, integral_Nm, kp, ki, T_lo, T_hi, on):
    """Wheel-speed PI controller with back-calculation anti-windup.

    ``u = kp (w_ref - w) + I``; the applied torque is ``u`` clipped to the motor envelope, and
    ``dI/dt = ki (w_ref - w) + (ki / kp) (T - u)`` so the integral tracks the saturated output
    instead of winding up.  Before a segment's start time (``on`` = 0) the motor is off:
    torque 0 and the integral frozen.  Locking a wheel is this controller at ``w_ref = 0``
    (paper section 5.1: "closed loop speed control to maintain zero speed").

    Parameters
    ----------
    omega_ref, omega : array_like
        Wheel speed set-point and measured wheel speed [rad/s].
    integral_Nm : array_like
        Integral state ``I`` [N m].
    kp : array_like
        Proportional gain [N m s/rad].
    ki : array_like
        Integral gain [N m/rad].
    T_lo, T_hi : array_like
        Motor envelope (:func:`motor_envelope`).
    on : array_like
        1 where the motor runs, 0 where it is off.

    Returns
    -------
    (T, dI_dt) : tuple of ndarray
        Applied torque [N m] and the integral's derivative [N m/s].
    """
    e = omega_ref - omega
    u = kp * e + integral_Nm
    T = np.minimum(np.maximum(u, T_lo), T_hi)
    dI = ki * e + (ki / kp) * (T - u)
    return T * on, dI * on
