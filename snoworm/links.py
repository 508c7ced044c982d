"""Link law: a spring-damper in series with a prismatic actuator (docs/model.md section 4).

Link ``k`` joins segment ``k`` (ahead) and segment ``k + 1`` (behind); its force is positive in
tension.  A fixed link is the same law with the actuator locked at zero extension::

    T_k = k_c (x_k - x_{k+1} - L_0 - s_k) + c_c (v_k - v_{k+1} - ds_k/dt)
          \\_____________ spring ____________/   \\________ damper ________/

``s_k`` is the extension of the prismatic actuator.  The actuator's physical limits (rate limit
and soft end stops at its stroke limits) are here; what it is *commanded* to do is a control law
(:mod:`snoworm.feedback`).  Pure NumPy, vectorised over links and batch members.
"""

from __future__ import annotations

import numpy as np

__all__ = ["K_STOP", "spring_force_N", "link_force_N", "actuator_rate_mps", "damper_power_W"]

#: Gain of the soft end stops of a prismatic joint [1/s]: the extension rate is limited to
#: ``K_STOP * (distance to the stop)``, so the stroke is never exceeded.
K_STOP = 50.0


def spring_force_N(stretch_m, extension_m, stiffness_N_per_m):
    """Force of the link spring, ``k_c (stretch - s)``, tension positive [N].

    Parameters
    ----------
    stretch_m : array_like
        ``x_k - x_{k+1} - L_0``: centre-to-centre distance minus the rest spacing [m].
    extension_m : array_like or None
        Actuator extension ``s_k`` [m]; ``None`` for fixed links (no actuator state).
    stiffness_N_per_m : array_like
        Link stiffness ``k_c`` [N/m].
    """
    if extension_m is None:
        return stiffness_N_per_m * stretch_m
    return stiffness_N_per_m * (stretch_m - extension_m)


def link_force_N(spring_N, damper_speed_mps, damping_Ns_per_m):
    """Link force: spring plus damper, ``T = F_spring + c_c (v_k - v_{k+1} - ds/dt)`` [N].

    Parameters
    ----------
    spring_N : array_like
        Spring force (:func:`spring_force_N`) [N].
    damper_speed_mps : array_like
        Closing speed across the damper, ``v_k - v_{k+1} - ds_k/dt`` [m/s].
    damping_Ns_per_m : array_like
        Link damping ``c_c`` [N s/m].
    """
    return spring_N + damping_Ns_per_m * damper_speed_mps


def damper_power_W(damper_speed_mps, damping_Ns_per_m):
    """Power dissipated in the link damper, ``c_c (v_k - v_{k+1} - ds/dt)^2`` [W]."""
    return damping_Ns_per_m * damper_speed_mps**2


def actuator_rate_mps(
    rate_cmd_mps, extension_m, rate_max_mps, neg_rate_max_mps, stroke_min_m, stroke_max_m, k_stop_per_s
):
    """Extension rate the actuator can deliver for a commanded rate [m/s].

    The command is clipped to the rate limit ``[-rate_max, rate_max]`` and to the soft end stops
    ``K_STOP (stroke_min - s) <= ds/dt <= K_STOP (stroke_max - s)``, so the stroke is never left.

    Parameters
    ----------
    rate_cmd_mps : array_like
        Commanded extension rate [m/s].
    extension_m : array_like
        Current extension ``s`` [m].
    rate_max_mps, neg_rate_max_mps : array_like
        Rate limit and its negative [m/s] (both passed: the kernel prepares them once).
    stroke_min_m, stroke_max_m : array_like
        Stroke limits [m].
    k_stop_per_s : array_like
        Soft end-stop gain [1/s] (:data:`K_STOP`).
    """
    rate = np.minimum(np.maximum(rate_cmd_mps, neg_rate_max_mps), rate_max_mps)
    rate = np.minimum(rate, k_stop_per_s * (stroke_max_m - extension_m))
    return np.maximum(rate, k_stop_per_s * (stroke_min_m - extension_m))
