"""Named parameter sets of physical values, with their sources (docs/model.md sections 1, 2 and 4).

A scenario names one set (``vehicle.parameter_set: frostyboy``); the set fills every physical
value the scenario does not state, and the resolved scenario written with the results lists
every value explicitly.  This module is the only copy of these values: there are no other
defaults for physical parameters anywhere in snoworm.

Each value is stored with its source tag:

* [paper] Elliott, Lines & Ray, "Mobility modes and control of a passively-articulated
  multi-segment wheeled vehicle": 4 wheels per segment, 40:1 gearbox, 20 % drivetrain loss,
  Table 3 terrain coefficients.
* [Lines] A. Lines' thesis code (``TerramechanicsDynamicsModel``, FrostyBoy branch): mass,
  wheel radius and inertia, wheelbase, motor curve.
* [derived] follows from the paper's numbers (the exponent d of Eq. 2, docs/model.md section 2).
* [fitted] resistance-torque law fitted to Table 2 (docs/model.md section 2).
* [assumed] link stiffness/damping/spacing, prismatic joint limits, controller gains and the
  regularisation speeds: no source; exposed as parameters.
"""
from __future__ import annotations

from ..terrain import TerrainParams

__all__ = ["PARAMETER_SETS", "parameter_set", "parameter_sources", "terrain_params"]

#: ``{set name: {section: {key: (value, source)}}}``; sections ``segment``, ``terrain_model``, ``links``.
PARAMETER_SETS = {
    "frostyboy": {
        "segment": {
            "mass_kg": (90.0, "[Lines] incl. wheels"),
            "wheel_radius_m": (0.265, "[Lines]"),
            "wheel_inertia_kgm2": (0.415, "[Lines] 5.91 kg * R_w^2, per wheel"),
            "wheelbase_m": (1.094, "[Lines] axles at +-0.547 m"),
            "wheels_per_axle": (2, "[paper] 4 wheels, 2 axles"),
            "gravity_mps2": (9.81, "[paper] standard gravity"),
            "motor_slope_Nms_per_rad": (10.0507, "[Lines] at the wheel"),
            "no_load_speed_radps": (18.326, "[Lines] 7000 rpm / 40"),
            "torque_limit_Nm": (88.64, "[Lines] 2.77 N m * 40 * 0.8"),
            "drivetrain_efficiency": (0.8, "[paper] 20 % loss (for electrical energy)"),
            "speed_kp_Nms_per_rad": (30.0, "[assumed] wheel-speed PI"),
            "speed_ki_Nm_per_rad": (150.0, "[assumed] wheel-speed PI"),
        },
        "terrain_model": {
            "b_tF": (0.7, "[paper] Table 3"),
            "b_trF": (0.165, "[paper] Table 3"),
            "A": (0.6, "[paper] Table 3"),
            "peak_exponent_d": (2.0, "[derived] docs/model.md section 2 (d = 1 literal)"),
            "tau0": (0.1710, "[fitted] Table 2"),
            "tau1": (1.7096, "[fitted] Table 2"),
            "slip_eps_mps": (0.05, "[assumed] regularisation"),
            "sign_eps_mps": (0.01, "[assumed] regularisation"),
            "torque_balance": ("contact", "[paper] section 3 (docs/model.md section 2)"),
        },
        "links": {
            "stiffness_N_per_m": (2.0e4, "[assumed]"),
            "damping_Ns_per_m": (1.5e3, "[assumed]"),
            "rest_spacing_m": (1.5, "[assumed] centre-to-centre at rest"),
            "stroke_min_m": (0.0, "[assumed] prismatic joint travel"),
            "stroke_max_m": (0.3, "[assumed] prismatic joint travel"),
            "force_max_N": (400.0, "[assumed]"),
            "rate_max_mps": (0.5, "[assumed]"),
            "force_gain_per_s": (50.0, "[assumed] joint force-loop bandwidth"),
            "joint_efficiency": (0.7, "[assumed] prismatic actuator (screw + motor), for electrical energy"),
        },
    },
}


def parameter_set(name: str) -> dict:
    """The values of the named parameter set, ``{section: {key: value}}`` (a fresh copy).

    Raises
    ------
    KeyError
        If the set is unknown.
    """
    return {sec: {k: v for k, (v, _) in entries.items()} for sec, entries in PARAMETER_SETS[name].items()}


def parameter_sources(name: str) -> dict:
    """The source tag of every value of the named set, ``{section: {key: tag}}``."""
    return {sec: {k: src for k, (_, src) in entries.items()} for sec, entries in PARAMETER_SETS[name].items()}


def terrain_params(name: str) -> TerrainParams:
    """The terrain coefficients of the named set as the laws' :class:`~snoworm.terrain.TerrainParams`."""
    return TerrainParams(**parameter_set(name)["terrain_model"])
