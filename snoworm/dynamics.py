r"""Longitudinal dynamics of a chain of wheeled segments: the kernel's public face (docs/model.md section 4).

::

        direction of travel  -->                                   x (forward, m)

      link N-2        link 1          link 0
    [seg N-1]==T==> ... [seg 1]==T==>[seg 0]      T_k > 0: link k in tension
      <-- F_tow                                   segment 0 is the leader (front)
      each segment: 2 axles at x_k +- wheelbase/2, each axle with 2 wheels

    m_k dv_k/dt = n_w * sum_axles (F_t - F_tr) + T_{k-1} - T_k - F_tow [k = N-1] - m_k g sin(theta_k)
    J   dw/dt   = T_m - R_w (F_t - F_tr) - T_rr                 (per wheel, per axle)
    T_k = k_c (x_k - x_{k+1} - L_0 - s_k) + c_c (v_k - v_{k+1} - ds_k/dt)
          (spring-damper in series with the prismatic actuator of extension s_k; s_k = 0 fixed)

F_t is Eq. 2 (Magic Formula traction), F_tr Eq. 3 (terrain resistance), T_rr the fitted
resistance torque and the slip of Eq. 1, regularised or from the shear displacement
(:mod:`snoworm.terrain`, docs/model.md section 2); T_m the motor torque within the
motor's envelope (:mod:`snoworm.drivetrain`) set by the wheel-speed PI (:mod:`snoworm.feedback`);
F_n the normal load of :func:`snoworm.terrain.normal_load_N` on the grade theta_k under the segment
(:mod:`snoworm.slope`, docs/model.md section 7); on level ground every grade term is skipped.

The state layout is named by :class:`~snoworm.model.arrays.StateLayout`: one block of ``n_s``
fields per segment, interleaved so the Jacobian is banded::

    x_m, v_mps, omega_front, omega_rear, integral_front_Nm, integral_rear_Nm
    [, q_mps (outer force-loop integral, force-control mode)]
    [, s_m (extension of the prismatic joint in the link *behind* the segment)]
    [, j_front_m, j_rear_m (shear displacement per axle, terrain.model.standstill: shear)]
    [, z_front_m, z_rear_m (slip-sinkage per axle, terrain.model.sinkage: slip)]

The kernel itself, :class:`ChainModel` (its parameters, the laws it evaluates, the float code it
generates and the outputs it derives), lives in one package, :mod:`snoworm.model`
(:mod:`snoworm.model.chain`); this module names it for users with :class:`Controls`, the inputs
of one interval.
"""

from __future__ import annotations

from .model.chain import ChainModel, StackedConstantProfile
from .model.inputs import Controls

__all__ = ["ChainModel", "Controls", "StackedConstantProfile"]
