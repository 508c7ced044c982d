"""Named parameter sets of physical values (MODEL.md sections 1, 2 and 4).

A scenario names one set (``vehicle.parameter_set: frostyboy``); the set fills every physical
value the scenario does not state, and the resolved scenario written with the results lists
every value explicitly.  There are no other defaults for physical parameters.

Sources of the ``frostyboy`` set
--------------------------------
* [paper] Elliott, Lines & Ray, "Mobility modes and control of a passively-articulated
  multi-segment wheeled vehicle": 4 wheels per segment, 40:1 gearbox, 20 % drivetrain loss,
  Table 3 terrain coefficients.
* [Lines] A. Lines' thesis code (``TerramechanicsDynamicsModel``, FrostyBoy branch): mass,
  wheel radius and inertia, wheelbase, motor curve.
* [fitted] resistance-torque law fitted to Table 2 (MODEL.md section 2).
* [assumed] link stiffness/damping/spacing, prismatic joint limits, controller gains and the
  regularisation speeds: no source; exposed as parameters.
"""
from __future__ import annotations

import copy

__all__ = ["PARAMETER_SETS", "parameter_set"]

PARAMETER_SETS = {
    "frostyboy": {
        "segment": {
            "mass_kg": 90.0,                      # [Lines] incl. wheels
            "wheel_radius_m": 0.265,              # [Lines]
            "wheel_inertia_kgm2": 0.415,          # [Lines] 5.91 kg * R_w^2, per wheel
            "wheelbase_m": 1.094,                 # [Lines] axles at +-0.547 m
            "wheels_per_axle": 2,                 # [paper] 4 wheels, 2 axles
            "gravity_mps2": 9.81,
            "motor_slope_Nms_per_rad": 10.0507,   # [Lines] at the wheel
            "no_load_speed_radps": 18.326,        # [Lines] 7000 rpm / 40
            "torque_limit_Nm": 88.64,             # [Lines] 2.77 N m * 40 * 0.8
            "drivetrain_efficiency": 0.8,         # [paper] 20 % loss (for electrical energy)
            "speed_kp_Nms_per_rad": 30.0,         # [assumed] wheel-speed PI
            "speed_ki_Nm_per_rad": 150.0,         # [assumed]
        },
        "terrain_model": {
            "b_tF": 0.7,              # [paper] Table 3
            "b_trF": 0.165,           # [paper] Table 3
            "A": 0.6,                 # [paper] Table 3
            "peak_exponent_d": 2.0,   # [derived] MODEL.md section 2 (d = 1 literal)
            "tau0": 0.1710,           # [fitted]
            "tau1": 1.7096,           # [fitted]
            "slip_eps_mps": 0.05,     # [assumed] regularisation
            "sign_eps_mps": 0.01,     # [assumed] regularisation
            "torque_balance": "contact",
        },
        "links": {
            "stiffness_N_per_m": 2.0e4,     # [assumed]
            "damping_Ns_per_m": 1.5e3,      # [assumed]
            "rest_spacing_m": 1.5,          # [assumed] centre-to-centre at rest
            "stroke_min_m": 0.0,            # [assumed] prismatic joint travel
            "stroke_max_m": 0.3,            # [assumed]
            "force_max_N": 400.0,           # [assumed]
            "rate_max_mps": 0.5,            # [assumed]
            "force_gain_per_s": 50.0,       # [assumed] joint force-loop bandwidth
            "joint_efficiency": 0.7,        # [assumed] prismatic actuator (screw + motor), for electrical energy
        },
    },
}


def parameter_set(name: str) -> dict:
    """A deep copy of the named parameter set (raises ``KeyError`` if unknown)."""
    return copy.deepcopy(PARAMETER_SETS[name])
