"""Scenario files: YAML -> validated, frozen, SI configuration objects.

Data flows one way: ``load_scenario(path, overrides)`` reads YAML, applies ``--set`` overrides,
fills physical values from the named parameter set (``vehicle.parameter_set``), validates every
key (unknown keys are rejected with suggestions) and returns a frozen :class:`Scenario`.
``dump_scenario`` writes it back with every value filled in, so it re-runs identically.
"""
from __future__ import annotations

import contextvars
import copy
import functools
from dataclasses import dataclass
from pathlib import Path

import yaml

from . import yamlio
from .dynamics import ChainModel
from .params import PARAMETER_SETS, parameter_set
from .schema import Config, ScenarioError, build, dump, field, quote, short_key, suggest
from .sections import (MAX_OUTPUT_SAMPLES, LinkConfig, ModeConfig, PatchConfig, RandomTerrainConfig, SegmentConfig,
                       SimulationConfig, TerrainConfig, TerrainModelConfig, TowConfig, VehicleConfig)

__all__ = [
    "Scenario", "SegmentConfig", "LinkConfig", "TerrainConfig", "PatchConfig", "RandomTerrainConfig",
    "TerrainModelConfig", "TowConfig", "VehicleConfig", "SimulationConfig", "ModeConfig", "MODE_CONFIGS",
    "register_mode_config", "load_scenario", "scenario_from_dict", "dump_scenario", "apply_overrides",
    "parse_set_option", "read_model_file", "read_yaml", "ScenarioError", "base_dir",
]

#: The scenario's ``mode.type`` -> its :class:`~snoworm.sections.ModeConfig` subclass.  Filled by
#: :func:`snoworm.modes.register_mode` (the built-in modes register when :mod:`snoworm` is imported).
MODE_CONFIGS: dict = {}


def register_mode_config(name: str, cls) -> None:
    """Make ``mode: {type: name, ...}`` validate against the config class ``cls``."""
    if not (isinstance(cls, type) and issubclass(cls, ModeConfig)):
        raise TypeError(f"a mode config must subclass snoworm.sections.ModeConfig, got {cls!r}")
    MODE_CONFIGS[name] = cls


def build_mode_config(raw, path="mode") -> ModeConfig:
    """Validate a ``mode`` mapping against the config class registered for its ``type``."""
    reg = MODE_CONFIGS
    if not isinstance(raw, dict):
        raise ScenarioError(f"{path}: expected a mapping with a 'type' key ({', '.join(reg)}), got {quote(raw)}.")
    kind = raw.get("type")
    if kind is None:
        raise ScenarioError(f"{path}.type: is required but missing. Choose one of: {', '.join(reg)}.")
    if not isinstance(kind, str):
        raise ScenarioError(f"{path}.type: expected the name of a mode ({', '.join(reg)}), got "
                            f"{type(kind).__name__} {quote(kind)}.")
    if kind not in reg:
        raise ScenarioError(f"{path}.type: unknown mode {quote(kind)}.{suggest(kind, reg)} Known modes: {', '.join(reg)}.")
    return build(reg[kind], raw, path)


@dataclass(frozen=True)
class Scenario(Config):
    """A complete, validated scenario.

    Build with :func:`load_scenario` (a YAML file), :func:`scenario_from_dict` (a mapping) or the
    constructor (config objects); edit with :meth:`with_` or :func:`dataclasses.replace`, which
    validate the result too.  Every physical value is filled in from the parameter set.
    """

    _section = ""
    name: str = field(doc="scenario name")
    vehicle: VehicleConfig = field(doc="the vehicle")
    terrain: TerrainConfig = field(doc="the terrain")
    tow: TowConfig = field(doc="towed load")
    mode: object = field(doc="mobility mode (a ModeConfig, or a mapping with its type)")
    simulation: SimulationConfig = field(doc="numerics")
    description: str = field("", doc="free text")

    def _check(self, path):
        mode = self.mode
        if not isinstance(mode, ModeConfig):
            mode = build_mode_config(mode)
            object.__setattr__(self, "mode", mode)
        sim = self.simulation
        n_out = (sim.duration_s / sim.output_dt_s + 1) * self.vehicle.segments
        if n_out > MAX_OUTPUT_SAMPLES:
            raise ScenarioError(f"simulation.output_dt_s: {sim.duration_s:g} s sampled every {sim.output_dt_s:g} s "
                                f"for {self.vehicle.segments} segments gives {n_out:.0f} output samples (times x segments), over "
                                f"the {MAX_OUTPUT_SAMPLES} allowed (memory). Raise output_dt_s or shorten duration_s.")
        mode.check_vehicle(self.vehicle, "mode")
        mode.check_scenario(self, "mode")      # checks needing terrain and tow (e.g. force control)

    @functools.cached_property
    def chain_model(self) -> ChainModel:
        """The assembled :class:`~snoworm.dynamics.ChainModel` (built once per scenario)."""
        veh = self.vehicle
        return ChainModel(veh.segment_arrays(), veh.link_arrays(), self.terrain.model.params(),
                          self.terrain.compile(), self.tow.force_N, force_loop=self.mode.force_loop)

    @functools.cached_property
    def mode_plan(self):
        """The mode's plan (:meth:`ModeConfig.prepare`), computed once per scenario."""
        return self.mode.prepare(self)

    def to_dict(self) -> dict:
        """Plain data of the resolved scenario, every value filled in (what ``scenario.yaml`` holds)."""
        data = {"name": self.name, "description": self.description, "vehicle": dump(self.vehicle),
                "terrain": dump(self.terrain), "tow": dump(self.tow), "mode": dump(self.mode),
                "simulation": dump(self.simulation)}
        t = data["terrain"]
        for key in ("xt", "profile", "patches", "random"):
            if t[key] is None:
                t.pop(key)
        for key in ("max_step_s", "max_wall_s"):
            if data["simulation"][key] is None:
                data["simulation"].pop(key)
        return data

    def with_(self, changes=None, **kw) -> "Scenario":
        """A new, validated scenario with dotted-key changes applied.

        ``sc.with_({"tow.force_N": 150, "terrain.xt": 0.7})``; keyword arguments set top-level
        keys (``sc.with_(name="other")``).  Raises :class:`ScenarioError` like a scenario file.
        """
        items = list((changes or {}).items()) + list(kw.items())
        return scenario_from_dict(apply_overrides(self.to_dict(), items), self.name)


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
        raise ScenarioError(f"terrain.model_file: expected a file path, got {quote(mfile)}.")
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
            raise ScenarioError(f"{short_key(key)}: unknown key.{suggest(key, _TOP_KEYS)} Known top-level keys: {', '.join(_TOP_KEYS)}.")
    for key in ("name", "vehicle", "terrain", "tow", "mode", "simulation"):
        if key not in raw:
            raise ScenarioError(f"{key}: is required but missing. Add a '{key}:' section to the scenario "
                                "(see scenarios/tow6_uniform.yaml for an example).")
    veh = raw["vehicle"]
    if not isinstance(veh, dict):
        raise ScenarioError(f"vehicle: expected a mapping, got {quote(veh)}.")
    ps_name = veh.get("parameter_set")
    if ps_name is None:
        raise ScenarioError("vehicle.parameter_set: is required but missing. Name the set of physical values "
                            f"to start from, one of: {', '.join(PARAMETER_SETS)}.")
    if not isinstance(ps_name, str):
        raise ScenarioError(f"vehicle.parameter_set: expected the name of a set ({', '.join(PARAMETER_SETS)}), got "
                            f"{type(ps_name).__name__} {quote(ps_name)}.")
    if ps_name not in PARAMETER_SETS:
        raise ScenarioError(f"vehicle.parameter_set: unknown set {quote(ps_name)}.{suggest(ps_name, PARAMETER_SETS)} "
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
    raw["name"] = _text(raw["name"], "name")
    raw["description"] = _text(raw.get("description", ""), "description")
    token = _BASE_DIR.set(None if base_dir is None else Path(base_dir))
    try:
        return build(Scenario, raw, "")
    finally:
        _BASE_DIR.reset(token)


#: folder of the scenario file being validated (None: the working directory); see :func:`base_dir`
_BASE_DIR = contextvars.ContextVar("snoworm_scenario_dir", default=None)


def base_dir() -> Path:
    """The folder that relative file paths in the scenario being validated are taken from.

    The scenario file's folder while :func:`load_scenario` validates it, else the working
    directory.  A config section resolving a file path (e.g. ``mode.controller``) calls it.
    """
    d = _BASE_DIR.get()
    return Path.cwd() if d is None else d


def _text(v, path):
    if not isinstance(v, str):
        raise ScenarioError(f"{path}: expected text, got {quote(v)}.")
    return v


def parse_set_option(item: str):
    """Split ``dotted.key=value`` (value parsed as YAML) into ``(key, value)``."""
    if "=" not in item:
        raise ScenarioError(f"--set {quote(item)}: expected KEY=VALUE with a dotted scenario key, e.g. terrain.xt=0.5.")
    key, _, text = item.partition("=")
    key = key.strip()
    if not key or any(not p for p in key.split(".")):
        raise ScenarioError(f"--set {quote(item)}: the key must be a dotted path such as tow.force_N.")
    try:
        value = yamlio.load_yaml_text(text, f"--set {key}")
    except ScenarioError as exc:
        raise ScenarioError(f"--set {yamlio.quote(item)}: the value is not valid YAML ({exc}).") from None
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
    """Parse a YAML file with the hardened reader (:func:`snoworm.yamlio.read_yaml`).

    Syntax errors, non-UTF-8 files, duplicate keys, alias bombs, deep nesting, missing or empty
    files become :class:`ScenarioError` naming the file.
    """
    return yamlio.read_yaml(path)


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
    return yaml.safe_dump(sc.to_dict(), sort_keys=False)
