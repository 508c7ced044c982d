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

The user's own values come from files read here too, with their tags: a parameter-set file
(``vehicle.parameter_set: my_rover.yaml``, :func:`read_parameter_file`), a terrain-model file
(``terrain.model_file``, :func:`read_model_file`) and a scenario's ``sources:`` block
(:func:`source_notes`).
"""

from __future__ import annotations

from pathlib import Path

from ..terrain import TerrainParams
from . import yamlio
from .schema import ScenarioError, quote, suggest

__all__ = [
    "PARAMETER_SETS",
    "SOURCE_TAGS",
    "parameter_set",
    "parameter_sources",
    "terrain_params",
    "parameter_entries",
    "read_parameter_file",
    "read_model_file",
    "source_notes",
]

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
            "com_height_m": (
                0.40,
                "[assumed] no FrostyBoy value published; about the axle height plus half the "
                "chassis depth (only the pitch load transfer on a grade uses it)",
            ),
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
            "standstill": (
                "regularised",
                "[assumed] the paper's Eq. 1, regularised; 'shear' holds a stopped wheel (docs/model.md section 2)",
            ),
            "shear_modulus_K_m": (
                0.025,
                "[assumed] Janosi-Hanamoto shear deformation modulus of snow, the middle of the 1-5 cm "
                "the terramechanics literature gives for snow (Wong 2010); not measured for FrostyBoy",
            ),
            "sinkage": ("off", "[assumed] the paper has no sinkage; 'slip' digs wheels in (docs/model.md section 2)"),
            "sinkage_rate": (0.05, "[assumed] 5 cm of sinkage per metre of slip displacement beyond the onset"),
            "sinkage_onset_slip": (
                0.35,
                "[assumed] above the 30 % slip FrostyBoy held steadily in the field (Table 2 case 5)",
            ),
            "sinkage_relax_length_m": (1.0, "[assumed] about a wheel circumference (1.67 m) or a wheelbase (1.09 m)"),
            "sinkage_max_m": (0.2, "[assumed] most of the wheel radius (0.265 m): the hub reaches the snow"),
            "sinkage_ref_m": (0.1, "[assumed] resistance doubled at 10 cm of sinkage"),
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


# ------------------------------------------------------------------ the user's files of values

#: Source tags a value may carry (docs/model.md; the built-in sets above).
SOURCE_TAGS = ("[paper]", "[field data]", "[fitted]", "[assumed]", "[user]", "[Lines]", "[derived]")


def _tag(value, where):
    if not isinstance(value, str) or not value.startswith(SOURCE_TAGS):
        raise ScenarioError(
            f"{where}: a source must start with one of {', '.join(SOURCE_TAGS)}, e.g. "
            f"'[field data] weighed 2026-01'; got {quote(value)}."
        )
    return value


def source_notes(notes) -> dict:
    """The scenario's ``sources:`` block ({dotted key: tag}), checked."""
    if not isinstance(notes, dict):
        raise ScenarioError(f"sources: expected a mapping of dotted keys to source tags, got {quote(notes)}.")
    return {str(k): _tag(v, f"sources.{k}") for k, v in notes.items()}


def _entries_copy(entries) -> dict:
    """A copy of a parameter set's ``{section: {key: (value, source)}}`` (its entries are immutable
    tuples of scalars, so copying the mappings suffices; a deep copy cost ~2 ms per scenario)."""
    return {sec: dict(items) for sec, items in entries.items()}


def parameter_entries(ps_name, base_dir=None):
    """``({section: {key: (value, source)}}, name to record)`` of a named set or a parameter-set file.

    ``ps_name`` is a name of :data:`~snoworm.config.params.PARAMETER_SETS` or a path to a YAML file of the
    user's own vehicle (relative to the scenario file; see :func:`read_parameter_file`).
    """
    if ps_name is None:
        raise ScenarioError(
            "vehicle.parameter_set: is required but missing. Name the set of physical values "
            f"to start from, one of: {', '.join(PARAMETER_SETS)}, or a YAML parameter-set file."
        )
    if isinstance(ps_name, str) and ps_name in PARAMETER_SETS:
        return _entries_copy(PARAMETER_SETS[ps_name]), ps_name
    if isinstance(ps_name, str) and (ps_name.endswith((".yaml", ".yml")) or "/" in ps_name):
        path = Path(ps_name)
        if not path.is_absolute() and base_dir is not None:
            path = Path(base_dir) / path
        return read_parameter_file(path), str(path.resolve())
    raise ScenarioError(
        f"vehicle.parameter_set: unknown set {quote(ps_name)}.{suggest(str(ps_name), PARAMETER_SETS)} "
        f"Known sets: {', '.join(PARAMETER_SETS)}; or give a YAML parameter-set file (path ending .yaml)."
    )


def read_parameter_file(path) -> dict:
    """A parameter-set file of the user's own vehicle -> ``{section: {key: (value, source)}}``.

    The file holds ``segment``, ``links`` and ``terrain_model`` mappings with the keys of the
    built-in sets; each value is a number (source ``[user] <file>``) or ``{value: ..., source:
    "[field data] ..."}``.  ``base: frostyboy`` starts from a named set (its values keep their
    sources); without it every key must be given (no silent defaults).
    """
    where = f"vehicle.parameter_set: {path}"
    try:
        data = yamlio.read_yaml(path)
    except ScenarioError as exc:
        raise ScenarioError(f"vehicle.parameter_set: {exc}") from None
    if not isinstance(data, dict):
        raise ScenarioError(f"{where} must hold a mapping with segment, links and terrain_model sections.")
    ref = PARAMETER_SETS["frostyboy"]
    for key in data:
        if key not in ("name", "description", "base", *ref):
            raise ScenarioError(
                f"{where}: unknown key {quote(key)}.{suggest(str(key), [*ref, 'base', 'name'])} "
                f"Known keys: name, description, base, {', '.join(ref)}."
            )
    base = data.get("base")
    if base is not None and base not in PARAMETER_SETS:
        raise ScenarioError(f"{where}: base: unknown set {quote(base)}. Known sets: {', '.join(PARAMETER_SETS)}.")
    out = _entries_copy(PARAMETER_SETS[base]) if base else {sec: {} for sec in ref}
    for sec in ref:
        given = data.get(sec) or {}
        if not isinstance(given, dict):
            raise ScenarioError(f"{where}: {sec}: expected a mapping of values, got {quote(given)}.")
        for k, v in given.items():
            if k not in ref[sec]:
                raise ScenarioError(
                    f"{where}: {sec}.{k}: unknown key.{suggest(str(k), ref[sec])} Known keys: {', '.join(ref[sec])}."
                )
            if isinstance(v, dict):
                if set(v) - {"value", "source"} or "value" not in v:
                    raise ScenarioError(
                        f"{where}: {sec}.{k}: give a value, or a mapping {{value: ..., source: "
                        f"'[tag] note'}}; got {quote(v)}."
                    )
                out[sec][k] = (
                    v["value"],
                    _tag(v.get("source", f"[user] {Path(path).name}"), f"{where}: {sec}.{k}.source"),
                )
            else:
                out[sec][k] = (v, f"[user] {Path(path).name}")
        missing = [k for k in ref[sec] if k not in out[sec]]
        if missing:
            raise ScenarioError(
                f"{where}: {sec}: missing {', '.join(missing)}. Give every value of the vehicle, or "
                "start from a named set with 'base: frostyboy'."
            )
    return out


def read_model_file(mfile, base_dir):
    """Terrain-model coefficients from a YAML file (e.g. written by ``snoworm calibrate``).

    The file is a mapping of ``terrain.model`` keys, optionally under a ``terrain_model:`` key;
    a relative path is taken relative to the scenario file.
    """
    if not isinstance(mfile, str):
        raise ScenarioError(f"terrain.model_file: expected a file path, got {quote(mfile)}.")
    path = Path(mfile)
    if not path.is_absolute() and base_dir is not None:
        path = Path(base_dir) / path
    try:
        data = yamlio.read_yaml(path)
    except ScenarioError as exc:
        raise ScenarioError(f"terrain.model_file: {exc}") from None
    if isinstance(data, dict) and "terrain_model" in data:
        data = data["terrain_model"]
    if not isinstance(data, dict):
        raise ScenarioError(
            f"terrain.model_file: {path} must hold a mapping of terrain-model coefficients "
            "(b_tF, b_trF, A, peak_exponent_d, tau0, tau1, ...)."
        )
    return data
