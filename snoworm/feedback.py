"""Control laws of the chain: wheel-speed PI, link-force PI, prismatic-joint servos.

The paper's controllers (sections 5.1 and 5.2), as pure NumPy functions vectorised over
segments, links and batch members.  They are continuous-time laws evaluated inside the
right-hand side; their settings for an integration interval come from a mode as
:class:`~snoworm.model.inputs.Controls`.  Which law acts where is decided by the model
(:mod:`snoworm.dynamics`); none of them knows about the chain.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "K_LENGTH",
    "speed_pi",
    "direct_torque",
    "link_force_pi",
    "servo_gain",
    "joint_force_command_N",
    "joint_force_rate_mps",
    "joint_length_rate_mps",
]

#: Gain of the length servo of a length-commanded prismatic joint [1/s].
K_LENGTH = 20.0


def speed_pi(omega_ref, omega, integral_Nm, kp, ki, T_lo, T_hi, on, ki_over_kp=None):
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
        Motor envelope (:func:`snoworm.drivetrain.motor_envelope`).
    on : array_like or None
        1 where the motor runs, 0 where it is off; None: every motor runs (no masking).
    ki_over_kp : array_like, optional
        ``ki / kp`` precomputed (the chain kernel passes it; computed here if omitted).

    Returns
    -------
    (T, dI_dt) : tuple of ndarray
        Applied torque [N m] and the integral's derivative [N m/s].
    """
    e = omega_ref - omega
    u = kp * e + integral_Nm
    T = np.minimum(np.maximum(u, T_lo), T_hi)
    dI = ki * e + (ki / kp if ki_over_kp is None else ki_over_kp) * (T - u)
    if on is None:
        return T, dI
    return T * on, dI * on


def direct_torque(torque_cmd_Nm, T_lo, T_hi, active, T_pi, dI_pi):
    """A directly commanded motor torque where ``active``, the wheel-speed PI elsewhere.

    The command (per wheel, at the wheel) is clipped to the motor envelope ``[T_lo, T_hi]``
    (:func:`snoworm.drivetrain.motor_envelope`, paper section 3); where it acts, the wheel-speed
    PI's integral is frozen (``dI/dt = 0``) so it resumes from where it was when speed control
    returns.

    Returns
    -------
    (T, dI_dt) : tuple of ndarray
        Applied torque [N m] and the PI integral's derivative [N m/s].
    """
    T = np.minimum(np.maximum(torque_cmd_Nm, T_lo), T_hi)
    return np.where(active, T, T_pi), np.where(active, 0.0, dI_pi)


def link_force_pi(force_N, ref_N, sigma, q_mps, nominal_mps, kp, ki, vmax_mps):
    """Outer link-force PI loop of force control (paper section 5.2, Figs 8-11).

    ``e = sigma (F_ref - F)``, ``v_sp = clip(v_nom + kp e + q, 0, v_max)`` and
    ``dq/dt = ki e + (ki / kp) (v_sp - (v_nom + kp e + q))`` (back-calculation anti-windup).
    ``sigma = +1`` for the link behind the segment (more tension: drive faster), ``-1`` ahead.

    Returns
    -------
    (v_sp, dq_dt) : tuple of ndarray
        Wheel-speed set-point ``R_w w_ref`` [m/s] and the integral's derivative [m/s^2]
        (the caller masks it where the loop or the motor is off).
    """
    e = sigma * (ref_N - force_N)
    raw = nominal_mps + kp * e + q_mps
    vsp = np.minimum(np.maximum(raw, 0.0), vmax_mps)
    return vsp, ki * e + (ki / kp) * (vsp - raw)


def servo_gain(force_gain_per_s, stiffness_N_per_m, damping_Ns_per_m):
    """Effective gain of a joint's force servo with the damper in series [m/(N s)].

    The servo sets ``ds/dt = rel + (T - T_ref) g / k``; with ``T = T_spring + c (rel - ds/dt)``
    solving for ``ds/dt`` gives ``rel + (T_spring - T_ref) g_k`` with
    ``g_k = (g / k) / (1 + c g / k)``: the force approaches its reference monotonically at the
    rate ``g / (1 + c g / k)``.
    """
    gk0 = force_gain_per_s / stiffness_N_per_m
    return gk0 / (1.0 + damping_Ns_per_m * gk0)


def joint_force_command_N(
    ff_N, limit_N, zero, kv=None, v_target_mps=None, v_mover_mps=None, ka=None, v_anchor_mps=None
):
    """Magnitude of a joint's force command (paper section 5.1, Eqs. 4-5).

    ``|F| = clip(F_ff + K_v (v_target - v_mover) - K_a max(0, -v_anchor), 0, F_lim)``: a
    feed-forward, a proportional loop on the mover's speed and a reduction while the anchor
    slides backward.  The speed and anchor terms are skipped when their gains are ``None``.
    ``zero`` is a 0-d array 0.0 (the kernel's prepared constant).
    """
    cmd = ff_N
    if kv is not None:
        cmd = cmd + kv * (v_target_mps - v_mover_mps)
    if ka is not None:
        cmd = cmd - ka * np.maximum(-v_anchor_mps, zero)
    return np.minimum(np.maximum(cmd, zero), limit_N)


def joint_force_rate_mps(rel_mps, spring_N, neg_dir, magnitude_N, gain):
    """Extension rate of a force-commanded joint: ``rel + (T_spring - T_ref) g_k``.

    ``T_ref = -dir |F|`` (``dir = +1`` pushes: compression, ``-1`` pulls: tension); the velocity
    feed-forward ``rel`` follows the segments' relative motion so the force tracks without lag.
    ``neg_dir`` is ``-dir``; ``gain`` is :func:`servo_gain`.
    """
    return rel_mps + (spring_N - neg_dir * magnitude_N) * gain


def joint_length_rate_mps(
    extension_m, ref_m, v_target_mps, neg_v_target_mps, rel_mps, spring_N, limit_N, gain, k_length
):
    """Extension rate of a length-commanded joint: a rate-limited servo to ``s_ref``.

    ``ds/dt = clip(K_LENGTH (s_ref - s), -v_target, v_target)``, backed off where the link force
    would leave ``[-F_lim, F_lim]`` (the same force servo as :func:`joint_force_rate_mps`).
    """
    rate = np.minimum(np.maximum(k_length * (ref_m - extension_m), neg_v_target_mps), v_target_mps)
    rate = np.minimum(rate, rel_mps + (spring_N + limit_N) * gain)
    return np.maximum(rate, rel_mps + (spring_N - limit_N) * gain)
