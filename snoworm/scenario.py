"""Scenario files: YAML -> validated, frozen, SI configuration objects.

Data flows one way: ``load_scenario(path, overrides)`` reads YAML, applies ``--set`` overrides,
fills physical values from the named parameter set (``vehicle.parameter_set``), validates every
key (unknown keys are rejected with suggestions) and returns a frozen :class:`Scenario`.
``dump_scenario`` writes it back with every value filled in, so it re-runs identically.
"""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import yaml

from . import modes
from .params import PARAMETER_SETS, parameter_set
from .schema import ScenarioError, build, dump, field, suggest
from .terrain import STEP_WIDTH_M

__all__ = [
    "Scenario", "SegmentConfig", "LinkConfig", "TerrainConfig", "PatchConfig", "RandomTerrainConfig", "TerrainModelConfig", "TowConfig",
    "VehicleConfig", "SimulationConfig", "load_scenario", "scenario_from_dict", "dump_scenario",
    "apply_overrides", "parse_set_option", "read_model_file", "ScenarioError",
]


@dataclass(frozen=True)
class SegmentConfig:
    """Physical parameters of one segment (MODEL.md section 1)."""

    mass_kg: float = field(gt=0, unit="kg", doc="segment mass including wheels")
    wheel_radius_m: float = field(gt=0, unit="m", doc="wheel radius R_w")
    wheel_inertia_kgm2: float = field(gt=0, unit="kg m^2", doc="inertia of one wheel J")
    wheelbase_m: float = field(ge=0, unit="m", doc="distance between the two axles")
    wheels_per_axle: int = field(ge=1, doc="wheels on each of the two axles")
    gravity_mps2: float = field(gt=0, unit="m/s^2", doc="gravitational acceleration")
    motor_slope_Nms_per_rad: float = field(gt=0, unit="N m s/rad", doc="motor torque-speed slope at the wheel")
    no_load_speed_radps: float = field(gt=0, unit="rad/s", doc="no-load wheel speed")
    torque_limit_Nm: float = field(gt=0, unit="N m", doc="motor torque limit at the wheel, per wheel")
    drivetrain_efficiency: float = field(gt=0, le=1, doc="drivetrain efficiency, for electrical energy")
    speed_kp_Nms_per_rad: float = field(gt=0, unit="N m s/rad", doc="wheel-speed PI proportional gain")
    speed_ki_Nm_per_rad: float = field(ge=0, unit="N m/rad", doc="wheel-speed PI integral gain")


@dataclass(frozen=True)
class LinkConfig:
    """Inter-segment links: fixed spring-dampers or active prismatic joints (MODEL.md section 4)."""

    type: tuple[str, ...] = field(doc="'fixed' or 'prismatic', one for all links or a list with one per link")
    stiffness_N_per_m: float = field(gt=0, unit="N/m", doc="link stiffness k_c")
    damping_Ns_per_m: float = field(ge=0, unit="N s/m", doc="link damping c_c")
    rest_spacing_m: float = field(gt=0, unit="m", doc="centre-to-centre spacing of unloaded segments")
    stroke_min_m: float = field(unit="m", doc="prismatic joint fully contracted extension")
    stroke_max_m: float = field(unit="m", doc="prismatic joint fully extended extension")
    force_max_N: float = field(gt=0, unit="N", doc="prismatic joint force limit")
    rate_max_mps: float = field(gt=0, unit="m/s", doc="prismatic joint rate limit")
    force_gain_per_s: float = field(gt=0, unit="1/s", doc="bandwidth of the joint's force loop")
    joint_efficiency: float = field(gt=0, le=1, doc="prismatic actuator efficiency, mechanical work / electrical energy")

    def _check(self, path):
        for j, t in enumerate(self.type):
            if t not in ("fixed", "prismatic"):
                raise ScenarioError(f"{path}.type[{j}]: must be 'fixed' or 'prismatic', got {t!r}.{suggest(t, ('fixed', 'prismatic'))}")
        if not self.stroke_max_m > self.stroke_min_m:
            raise ScenarioError(f"{path}.stroke_max_m: must be greater than stroke_min_m ({self.stroke_min_m} m), "
                                f"got {self.stroke_max_m} m. Give the joint a positive stroke.")


@dataclass(frozen=True)
class TerrainModelConfig:
    """Terrain-model coefficients (paper Table 3, MODEL.md section 2)."""

    b_tF: float = field(gt=0, doc="Eq. 2 slip-to-tractive-force coefficient")
    b_trF: float = field(ge=0, doc="Eq. 3 terrain resistance coefficient")
    A: float = field(doc="Eq. 3 terrain coefficient exponent")
    peak_exponent_d: float = field(doc="exponent of X_t in Eq. 2's peak factor (2 default, 1 literal)")
    tau0: float = field(doc="resistance torque law constant")
    tau1: float = field(doc="resistance torque law slope in (1 - X_t)")
    slip_eps_mps: float = field(gt=0, unit="m/s", doc="slip regularisation speed")
    sign_eps_mps: float = field(gt=0, unit="m/s", doc="smooth-sign speed scale")
    torque_balance: str = field(choices=("contact", "traction"), doc="wheel torque-balance convention")


@dataclass(frozen=True)
class PatchConfig:
    """A patch of other snow on the route (``terrain.patches``), X_t = ``xt`` on ``[start_m, end_m]``."""

    start_m: float = field(unit="m", doc="position where the patch's X_t is reached")
    end_m: float = field(unit="m", doc="position where the patch's X_t ends")
    xt: float = field(gt=0, doc="terrain coefficient X_t inside the patch")
    ramp_m: float = field(0.0, ge=0, unit="m",
                          doc="length of the linear transition to the base X_t outside each edge (0: a step)")

    def _check(self, path):
        if not self.end_m > self.start_m:
            raise ScenarioError(f"{path}.end_m: must be greater than start_m ({self.start_m} m), got {self.end_m} m. "
                                "A patch covers [start_m, end_m].")


@dataclass(frozen=True)
class RandomTerrainConfig:
    """A seeded random X_t profile (``terrain.random``): Gaussian-filtered white noise, clipped."""

    mean: float = field(gt=0, doc="mean X_t")
    std: float = field(ge=0, doc="standard deviation of X_t before clipping")
    correlation_length_m: float = field(gt=0, unit="m", doc="distance at which the correlation falls to 1/e")
    seed: int = field(ge=0, doc="seed of the random generator (same seed, same profile)")
    length_m: float = field(gt=0, unit="m", doc="length of the generated stretch (X_t held beyond it)")
    start_m: float = field(0.0, unit="m", doc="position where the generated stretch starts")
    min_xt: float = field(0.05, gt=0, doc="lower clip of X_t, keeps X_t > 0")

    def _check(self, path):
        if self.length_m / (self.correlation_length_m / 8.0) > 200000:
            raise ScenarioError(f"{path}: length_m / correlation_length_m = "
                                f"{self.length_m / self.correlation_length_m:.0f} needs more than 200000 grid points; "
                                "shorten length_m or lengthen correlation_length_m.")


@dataclass(frozen=True)
class TerrainConfig:
    """Terrain coefficient along the track.

    Exactly one of: a constant ``xt`` (optionally with ``patches`` of other snow on it), a
    ``profile`` table of ``[position_m, xt]`` pairs, or a seeded ``random`` profile.  All of
    them compile to one :class:`~snoworm.terrain.TerrainProfile` (``simulate.terrain_profile``).
    """

    model: TerrainModelConfig = field(doc="terrain-model coefficients")
    xt: Optional[float] = field(None, gt=0, doc="constant terrain coefficient X_t (the base X_t with patches)")
    profile: Optional[tuple[tuple[float, ...], ...]] = field(None, doc="list of [position_m, xt] pairs")
    patches: Optional[tuple[PatchConfig, ...]] = field(None, doc="patches of other snow on the base xt")
    random: Optional[RandomTerrainConfig] = field(None, doc="seeded random X_t profile")

    def _check(self, path):
        given = [k for k in ("xt", "profile", "random") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ScenarioError(f"{path}: give exactly one of 'xt' (a constant X_t, optionally with 'patches'), "
                                f"'profile' (a list of [position_m, xt] pairs) or 'random' (a seeded random profile); "
                                f"got {' and '.join(repr(g) for g in given) if given else 'none of them'}.")
        if self.patches is not None:
            if self.xt is None:
                raise ScenarioError(f"{path}.patches: patches lie on a base X_t; give 'xt' (the X_t outside the "
                                    f"patches) instead of '{given[0]}'.")
            prev_end, prev_j = -math.inf, None
            for j, pt in enumerate(self.patches):
                lo = pt.start_m - max(pt.ramp_m, STEP_WIDTH_M)
                if lo < prev_end:
                    raise ScenarioError(f"{path}.patches[{j}]: overlaps patches[{prev_j}] (with its ramps): it starts "
                                        f"at {lo:g} m (start_m - ramp_m) before the previous one ends at {prev_end:g} m "
                                        "(end_m + ramp_m). List patches in order along the route, without overlap.")
                prev_end, prev_j = pt.end_m + max(pt.ramp_m, STEP_WIDTH_M), j
        if self.profile is not None:
            if len(self.profile) < 1:
                raise ScenarioError(f"{path}.profile: needs at least one [position_m, xt] pair.")
            prev = -math.inf
            for j, pair in enumerate(self.profile):
                if len(pair) != 2:
                    raise ScenarioError(f"{path}.profile[{j}]: expected a pair [position_m, xt], got {list(pair)}.")
                if not pair[0] > prev:
                    raise ScenarioError(f"{path}.profile[{j}]: positions must increase strictly; {pair[0]} m follows {prev} m.")
                if not pair[1] > 0:
                    raise ScenarioError(f"{path}.profile[{j}]: X_t must be greater than 0, got {pair[1]}. "
                                        "X_t = 1 is neve, lower is looser snow.")
                prev = pair[0]


@dataclass(frozen=True)
class TowConfig:
    """Towed load on the rear segment (MODEL.md section 4)."""

    force_N: float = field(unit="N", doc="constant force pulling the rear segment backward")


@dataclass(frozen=True)
class VehicleConfig:
    """The chain of segments."""

    parameter_set: str = field(choices=tuple(PARAMETER_SETS), doc="named set of physical values")
    segments: int = field(ge=1, doc="number of segments N (segment 0 leads)")
    segment: SegmentConfig = field(doc="parameters shared by every segment")
    links: LinkConfig = field(doc="inter-segment links")
    segment_overrides: dict[int, dict] = field(default_factory=dict, doc="per-segment parameter changes, by index")

    def _check(self, path):
        for k, ov in self.segment_overrides.items():
            if not 0 <= k < self.segments:
                raise ScenarioError(f"{path}.segment_overrides.{k}: segment index out of range 0..{self.segments - 1}.")
            merged = {**dump(self.segment), **(ov or {})}
            build(SegmentConfig, merged, f"{path}.segment_overrides.{k}")
        n_links = max(self.segments - 1, 0)
        if len(self.links.type) not in (1, n_links) and n_links > 0:
            raise ScenarioError(f"{path}.links.type: give one type for all links or {n_links} (one per link); "
                                f"got {len(self.links.type)}.")

    def segment_params(self):
        """Per-segment :class:`SegmentConfig` list with overrides applied."""
        if not self.segment_overrides:
            return [self.segment] * self.segments      # frozen: safe to share
        base = dump(self.segment)
        return [build(SegmentConfig, {**base, **(self.segment_overrides.get(k) or {})})
                for k in range(self.segments)]

    def link_types(self):
        n_links = max(self.segments - 1, 0)
        t = self.links.type
        return list(t) * n_links if len(t) == 1 else list(t)


@dataclass(frozen=True)
class SimulationConfig:
    """Numerical settings (no physics here)."""

    duration_s: float = field(gt=0, unit="s", doc="simulated time")
    output_dt_s: float = field(0.05, gt=0, unit="s", doc="output sampling interval")
    method: str = field("LSODA", choices=("LSODA", "BDF", "Radau", "RK45", "DOP853"), doc="solve_ivp method")
    rtol: float = field(1e-5, gt=0, lt=1, doc="relative tolerance")
    atol_scale: float = field(1.0, gt=0, doc="multiplies the per-component absolute tolerances")
    max_step_s: Optional[float] = field(None, gt=0, unit="s", doc="largest solver step (none: unlimited)")


@dataclass(frozen=True)
class Scenario:
    """A complete, validated scenario.  Build with :func:`load_scenario` or :func:`scenario_from_dict`."""

    name: str = field(doc="scenario name")
    vehicle: VehicleConfig = field(doc="the vehicle")
    terrain: TerrainConfig = field(doc="the terrain")
    tow: TowConfig = field(doc="towed load")
    mode: object = field(doc="mobility mode")
    simulation: SimulationConfig = field(doc="numerics")
    description: str = field("", doc="free text")


_TOP_KEYS = ("name", "description", "vehicle", "terrain", "tow", "mode", "simulation")


def _merge(defaults: dict, given):
    if not isinstance(given, dict):
        return given
    out = copy.deepcopy(defaults)
    out.update(given)
    return out


def read_model_file(mfile, base_dir):
    """Terrain-model coefficients from a YAML file (e.g. written by ``snoworm calibrate``).

    The file is a mapping of ``terrain.model`` keys, optionally under a ``terrain_model:`` key;
    a relative path is taken relative to the scenario file.
    """
    if not isinstance(mfile, str):
        raise ScenarioError(f"terrain.model_file: expected a file path, got {mfile!r}.")
    path = Path(mfile)
    if not path.is_absolute() and base_dir is not None:
        path = Path(base_dir) / path
    try:
        data = read_yaml(path)
    except ScenarioError as exc:
        raise ScenarioError(f"terrain.model_file: {exc}") from None
    if isinstance(data, dict) and "terrain_model" in data:
        data = data["terrain_model"]
    if not isinstance(data, dict):
        raise ScenarioError(f"terrain.model_file: {path} must hold a mapping of terrain-model coefficients "
                            "(b_tF, b_trF, A, peak_exponent_d, tau0, tau1, ...).")
    return data


def scenario_from_dict(raw: dict, source: str = "scenario", base_dir=None) -> Scenario:
    """Validate a scenario mapping (as parsed from YAML) into a :class:`Scenario`.

    Raises
    ------
    ScenarioError
        With a message naming the dotted field and the fix.
    """
    if not isinstance(raw, dict):
        raise ScenarioError(f"{source}: a scenario must be a YAML mapping with keys {', '.join(_TOP_KEYS)}; "
                            f"got {type(raw).__name__}.")
    raw = copy.deepcopy(raw)
    for key in raw:
        if key not in _TOP_KEYS:
            raise ScenarioError(f"{key}: unknown key.{suggest(key, _TOP_KEYS)} Known top-level keys: {', '.join(_TOP_KEYS)}.")
    for key in ("name", "vehicle", "terrain", "tow", "mode", "simulation"):
        if key not in raw:
            raise ScenarioError(f"{key}: is required but missing. Add a '{key}:' section to the scenario "
                                "(see scenarios/tow6_uniform.yaml for an example).")
    veh = raw["vehicle"]
    if not isinstance(veh, dict):
        raise ScenarioError(f"vehicle: expected a mapping, got {veh!r}.")
    ps_name = veh.get("parameter_set")
    if ps_name is None:
        raise ScenarioError("vehicle.parameter_set: is required but missing. Name the set of physical values "
                            f"to start from, one of: {', '.join(PARAMETER_SETS)}.")
    if ps_name not in PARAMETER_SETS:
        raise ScenarioError(f"vehicle.parameter_set: unknown set {ps_name!r}.{suggest(ps_name, PARAMETER_SETS)} "
                            f"Known sets: {', '.join(PARAMETER_SETS)}.")
    ps = parameter_set(ps_name)
    veh["segment"] = _merge(ps["segment"], veh.get("segment", {}))
    veh["links"] = _merge(ps["links"], veh.get("links", {}))
    if isinstance(raw["terrain"], dict):
        model_defaults = ps["terrain_model"]
        mfile = raw["terrain"].pop("model_file", None)
        if mfile is not None:
            model_defaults = _merge(model_defaults, read_model_file(mfile, base_dir))
        raw["terrain"]["model"] = _merge(model_defaults, raw["terrain"].get("model", {}))
    vehicle = build(VehicleConfig, veh, "vehicle")
    terrain_cfg = build(TerrainConfig, raw["terrain"], "terrain")
    tow = build(TowConfig, raw["tow"], "tow")
    sim = build(SimulationConfig, raw["simulation"], "simulation")
    mode = modes.build_config(raw["mode"], vehicle)
    sc = Scenario(name=_text(raw["name"], "name"), description=_text(raw.get("description", ""), "description"),
                  vehicle=vehicle, terrain=terrain_cfg, tow=tow, mode=mode, simulation=sim)
    check = getattr(mode, "check_scenario", None)   # checks needing terrain and tow (e.g. force control)
    if check is not None:
        check(sc, "mode")
    return sc


def _text(v, path):
    if not isinstance(v, str):
        raise ScenarioError(f"{path}: expected text, got {v!r}.")
    return v


def parse_set_option(item: str):
    """Split ``dotted.key=value`` (value parsed as YAML) into ``(key, value)``."""
    if "=" not in item:
        raise ScenarioError(f"--set {item!r}: expected KEY=VALUE with a dotted scenario key, e.g. terrain.xt=0.5.")
    key, _, text = item.partition("=")
    key = key.strip()
    if not key or any(not p for p in key.split(".")):
        raise ScenarioError(f"--set {item!r}: the key must be a dotted path such as tow.force_N.")
    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise ScenarioError(f"--set {item!r}: the value is not valid YAML ({exc.problem}).") from None
    return key, value


def apply_overrides(raw: dict, overrides) -> dict:
    """Return a copy of ``raw`` with each ``(dotted_key, value)`` set (sections created as needed)."""
    raw = copy.deepcopy(raw)
    for key, value in overrides:
        parts = key.split(".")
        node = raw
        for j, p in enumerate(parts[:-1]):
            nxt = node.get(p) if isinstance(node, dict) else None
            if nxt is None:
                nxt = {}
                node[p] = nxt
            if not isinstance(nxt, dict):
                raise ScenarioError(f"--set {key}: '{'.'.join(parts[:j + 1])}' is a value, not a section; "
                                    "cannot set a key inside it.")
            node = nxt
        leaf = parts[-1]
        if isinstance(node, dict) and leaf.isdigit() and int(leaf) in node:
            leaf = int(leaf)
        node[leaf] = value
        # a constant xt replaces a profile or random profile and vice versa (patches stay on a new xt)
        if parts[0] == "terrain" and len(parts) == 2 and parts[1] in ("xt", "profile", "random"):
            for other in ("xt", "profile", "random"):
                if other != parts[1]:
                    node.pop(other, None)
            if parts[1] != "xt":
                node.pop("patches", None)
    return raw


def read_yaml(path) -> dict:
    """Parse a YAML file, turning I/O and syntax errors into :class:`ScenarioError`."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ScenarioError(f"{path}: no such file. Check the path to the scenario.") from None
    except OSError as exc:
        raise ScenarioError(f"{path}: cannot be read ({exc.strerror}).") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise ScenarioError(f"{path}: not valid YAML{where}: {getattr(exc, 'problem', exc)}. "
                            "Fix the syntax (indentation, colons, quotes).") from None
    if data is None:
        raise ScenarioError(f"{path}: the file is empty. A scenario needs the sections {', '.join(_TOP_KEYS[:-1])}.")
    return data


def load_scenario(path, overrides=()) -> Scenario:
    """Load, override and validate a scenario file.

    Parameters
    ----------
    path : str or Path
        YAML scenario file.
    overrides : iterable of (str, object) or of "key=value" strings
        Dotted-key overrides applied before validation (the CLI's ``--set``).
    """
    raw = read_yaml(path)
    ov = [parse_set_option(o) if isinstance(o, str) else o for o in overrides]
    if ov:
        if not isinstance(raw, dict):
            raise ScenarioError(f"{path}: a scenario must be a YAML mapping.")
        raw = apply_overrides(raw, ov)
    return scenario_from_dict(raw, str(path), base_dir=Path(path).parent)


def dump_scenario(sc: Scenario) -> str:
    """The resolved scenario as YAML text, every value filled in (re-runnable)."""
    data = {"name": sc.name, "description": sc.description, "vehicle": dump(sc.vehicle),
            "terrain": dump(sc.terrain), "tow": dump(sc.tow), "mode": dump(sc.mode),
            "simulation": dump(sc.simulation)}
    t = data["terrain"]
    for key in ("xt", "profile", "patches", "random"):
        if t[key] is None:
            t.pop(key)
    if data["simulation"]["max_step_s"] is None:
        data["simulation"].pop("max_step_s")
    return yaml.safe_dump(data, sort_keys=False)


def with_overrides(sc: Scenario, overrides) -> Scenario:
    """Re-validate a scenario with dotted-key overrides applied (used by sweeps)."""
    raw = yaml.safe_load(dump_scenario(sc))
    return scenario_from_dict(apply_overrides(raw, overrides))
