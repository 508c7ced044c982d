"""Scenario files: YAML -> validated, frozen, SI configuration objects.

Data flows one way: ``load_scenario(path, overrides)`` reads YAML, applies ``--set`` overrides,
fills physical values from the named parameter set (``vehicle.parameter_set``), validates every
key (unknown keys are rejected with suggestions) and returns a frozen :class:`Scenario`.
``dump_scenario`` writes it back with every value filled in, so it re-runs identically.
"""

from __future__ import annotations

import copy
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import yaml

from . import yamlio
from .mode_registry import MODES, ModeConfig, build_mode_config
from .params import PARAMETER_SETS, parameter_entries, read_model_file, source_notes
from .routes import check_vehicle_on_grade, resolve_route
from .schema import Config, ScenarioError, build, dump, field, internal, quote, short_key, short_path, suggest
from .sections import (
    MAX_OUTPUT_SAMPLES,
    LinkConfig,
    PatchConfig,
    RandomTerrainConfig,
    SegmentConfig,
    SimulationConfig,
    TerrainConfig,
    TerrainModelConfig,
    TowConfig,
    VehicleConfig,
)

__all__ = [
    "Scenario",
    "SegmentConfig",
    "LinkConfig",
    "TerrainConfig",
    "PatchConfig",
    "RandomTerrainConfig",
    "TerrainModelConfig",
    "TowConfig",
    "VehicleConfig",
    "SimulationConfig",
    "load_scenario",
    "scenario_from_dict",
    "dump_scenario",
    "apply_overrides",
    "parse_set_option",
    "read_yaml",
    "ScenarioError",
    "ScenarioOrigin",
    "shipped_scenarios",
    "scenario_path",
    "read_scenario_yaml",
]


@dataclass(frozen=True)
class ScenarioOrigin:
    """Where a scenario came from: not a setting, but what explains and re-validates its values.

    Attributes
    ----------
    base_dir : Path or None
        The folder relative file paths of the scenario were taken from (the scenario file's
        folder; None: the working directory).
    notes : dict
        The scenario's ``sources:`` notes, ``{dotted key: note}``.
    entries : dict
        The parameter set's values with their source tags (:func:`~snoworm.config.params.parameter_entries`).
    code_root : str or None
        The folder (resolved) whose controller files the scenario may run: its file's folder, or
        the working directory; None for a scenario read back from a results folder
        (:func:`snoworm.modes.controller.code_root`, docs/controllers.md).
    """

    base_dir: Path | None
    notes: dict
    entries: dict
    code_root: str | None = None


@dataclass(frozen=True)
class Scenario(Config):
    """A complete, validated scenario.

    Build with :func:`load_scenario` (a YAML file), :func:`scenario_from_dict` (a mapping) or the
    constructor (config objects); edit with :meth:`with_` or :func:`dataclasses.replace`, which
    validate the result too.  Every physical value is filled in from the parameter set.

    A scenario is data: validating it builds no chain model and runs no root finding.  The
    chain model and the mode's plan are assembled when a run starts
    (:func:`snoworm.simulation.driver.assemble`), so a scenario pickles to the size of its data.
    """

    _section = ""
    name: str = field(doc="scenario name")
    vehicle: VehicleConfig = field(doc="the vehicle")
    terrain: TerrainConfig = field(doc="the terrain")
    tow: TowConfig = field(doc="towed load")
    mode: ModeConfig = field(doc="mobility mode (a ModeConfig, or a mapping with its type)", convert=build_mode_config)
    simulation: SimulationConfig = field(doc="numerics")
    description: str = field("", doc="free text")
    #: where the scenario was read from (set by :func:`scenario_from_dict`; None if made directly)
    origin: ScenarioOrigin | None = internal()

    def _check(self, path: str) -> None:
        mode = self.mode
        sim = self.simulation
        n_out = (sim.duration_s / sim.output_dt_s + 1) * self.vehicle.segments
        if n_out > MAX_OUTPUT_SAMPLES:
            raise ScenarioError(
                f"simulation.output_dt_s: {sim.duration_s:g} s sampled every {sim.output_dt_s:g} s "
                f"for {self.vehicle.segments} segments gives {n_out:.0f} output samples (times x segments), over "
                f"the {MAX_OUTPUT_SAMPLES} allowed (memory). Raise output_dt_s or shorten duration_s."
            )
        mode.check_vehicle(self.vehicle, "mode")
        check_vehicle_on_grade(self.vehicle, self.terrain.elevation_profile())
        mode.check_scenario(self, "mode")  # checks needing terrain and tow (data only: no chain model)

    @property
    def sources(self) -> dict:
        """The source tag of every physical value, ``{dotted key: tag}`` (e.g. ``"vehicle.segment.mass_kg":
        "[Lines] incl. wheels"``): the parameter set's tag, the scenario's ``sources:`` note, or
        ``[user] scenario`` for a value the scenario changed."""
        origin = self.origin
        entries = origin.entries if origin is not None else parameter_entries(self.vehicle.parameter_set)[0]
        notes = origin.notes if origin is not None else {}
        values = {
            "segment": dump(self.vehicle.segment),
            "links": dump(self.vehicle.links),
            "terrain_model": dump(self.terrain.model),
        }
        out = {}
        for sec, prefix in _SECTIONS.items():
            for k, (v, tag) in entries[sec].items():
                key = f"{prefix}.{k}"
                out[key] = notes.get(key) or (tag if values[sec].get(k) == v else "[user] scenario")
        for j, ov in sorted(self.vehicle.segment_overrides.items()):
            for k in ov or {}:
                key = f"vehicle.segment_overrides.{j}.{k}"
                out[key] = notes.get(key, "[user] scenario")
        return out

    def to_dict(self) -> dict:
        """Plain data of the resolved scenario, every value filled in (what ``scenario.yaml`` holds)."""
        data = {
            "name": self.name,
            "description": self.description,
            "vehicle": dump(self.vehicle),
            "terrain": dump(self.terrain),
            "tow": dump(self.tow),
            "mode": dump(self.mode),
            "simulation": dump(self.simulation),
        }
        t = data["terrain"]
        for key in ("xt", "profile", "patches", "random", "grade_deg", "grade_patches", "elevation", "route"):
            if t[key] is None:
                t.pop(key)
        for key in ("max_step_s", "max_wall_s"):
            if data["simulation"][key] is None:
                data["simulation"].pop(key)
        if self.origin is not None and self.origin.notes:
            data["sources"] = dict(self.origin.notes)
        return data

    def data_files(self) -> dict:
        """The files this scenario reads, ``{dotted key: path}``: the route file (``terrain.route``)
        and a parameter-set file (``vehicle.parameter_set``).  A results folder holds copies of them
        (:mod:`snoworm.results.copies`).  A ``terrain.model_file`` is not among them (its values are
        written into the scenario), nor is a controller's code (docs/controllers.md)."""
        out = {}
        if self.vehicle.parameter_set not in PARAMETER_SETS:
            out["vehicle.parameter_set"] = self.vehicle.parameter_set
        if self.terrain.route is not None:
            out["terrain.route"] = self.terrain.route
        return out

    def with_(self, changes: Mapping[str, Any] | None = None, **kw: Any) -> Scenario:
        """A new, validated scenario with dotted-key changes applied.

        ``sc.with_({"tow.force_N": 150, "terrain.xt": 0.7})``; keyword arguments set top-level
        keys (``sc.with_(name="other")``).  Raises :class:`ScenarioError` like a scenario file.
        """
        items = list((changes or {}).items()) + list(kw.items())
        o = self.origin
        return scenario_from_dict(
            apply_overrides(self.to_dict(), items),
            self.name,
            base_dir=o.base_dir if o is not None else None,
            trust_folder=o is None or o.code_root is not None,
        )


_TOP_KEYS = ("name", "description", "vehicle", "terrain", "tow", "mode", "simulation", "sources", "uncertainty")


def _merge(defaults: dict, given: Any) -> Any:
    if not isinstance(given, dict):
        return given
    out = _copy_tree(defaults)
    out.update(given)
    return out


_ATOMS = (str, int, float, bool, type(None))


def _copy_tree(data: Any) -> Any:
    """A copy of YAML-like data (nested dicts and lists of plain scalars, copied level by level;
    anything else by :func:`copy.deepcopy`), several times faster than ``copy.deepcopy`` of it."""
    if type(data) is dict:
        return {k: _copy_tree(v) for k, v in data.items()}
    if type(data) is list:
        return [_copy_tree(v) for v in data]
    if isinstance(data, _ATOMS):
        return data
    return copy.deepcopy(data)


def scenario_from_dict(
    raw: dict, source: str = "scenario", base_dir: str | os.PathLike[str] | None = None, *, trust_folder: bool = True
) -> Scenario:
    """Validate a scenario mapping (as parsed from YAML) into a :class:`Scenario`.

    Relative file paths are taken from ``base_dir`` (default: the working directory), which is
    also the folder whose controller files the scenario may run (``Scenario.origin.code_root``),
    unless ``trust_folder`` is False (a scenario read back from a results folder trusts none).

    Raises
    ------
    ScenarioError
        With a message naming the dotted field and the fix.
    """
    if not isinstance(raw, dict):
        raise ScenarioError(
            f"{source}: a scenario must be a YAML mapping with keys {', '.join(_TOP_KEYS)}; got {type(raw).__name__}."
        )
    raw = _copy_tree(raw)
    for key in raw:
        if key not in _TOP_KEYS:
            raise ScenarioError(
                f"{short_key(key)}: unknown key.{suggest(key, _TOP_KEYS)} Known top-level keys: {', '.join(_TOP_KEYS)}."
            )
    for key in ("name", "vehicle", "terrain", "tow", "mode", "simulation"):
        if key not in raw:
            raise ScenarioError(
                f"{key}: is required but missing. Add a '{key}:' section to the scenario "
                "(see scenarios/tow6_uniform.yaml for an example)."
            )
    veh = raw["vehicle"]
    if not isinstance(veh, dict):
        raise ScenarioError(f"vehicle: expected a mapping, got {quote(veh)}.")
    entries, veh["parameter_set"] = parameter_entries(veh.get("parameter_set"), base_dir)
    ps = {sec: {k: v for k, (v, _) in items.items()} for sec, items in entries.items()}
    notes = source_notes(raw.pop("sources", None) or {})
    raw.pop("uncertainty", None)  # read (and checked) by `snoworm odds` only: a run uses the nominal values
    veh["segment"] = _merge(ps["segment"], veh.get("segment", {}))
    veh["links"] = _merge(ps["links"], veh.get("links", {}))
    if isinstance(raw["terrain"], dict):
        model_defaults = ps["terrain_model"]
        mfile = raw["terrain"].pop("model_file", None)
        if mfile is not None:
            from_file = read_model_file(mfile, base_dir)
            model_defaults = _merge(model_defaults, from_file)
            if isinstance(from_file, dict):
                for k in from_file:
                    notes.setdefault(f"terrain.model.{k}", f"[user] terrain.model_file {mfile}")
        raw["terrain"]["model"] = _merge(model_defaults, raw["terrain"].get("model", {}))
    raw["name"] = _text(raw["name"], "name")
    raw["description"] = _text(raw.get("description", ""), "description")
    base = Path.cwd() if base_dir is None else Path(base_dir)
    if isinstance(raw["terrain"], dict):
        raw["terrain"] = resolve_route(raw["terrain"], base)
    raw["mode"] = _resolve_mode_paths(raw["mode"], base)
    origin = ScenarioOrigin(
        None if base_dir is None else Path(base_dir), notes, entries, os.path.realpath(base) if trust_folder else None
    )
    return build(Scenario, raw, "", internal_values={"origin": origin})


def _resolve_mode_paths(mode: Any, base: Path) -> Any:
    """The ``mode`` mapping with its file paths taken from ``base`` (:meth:`ModeConfig.resolve_paths`
    of its registered type; anything else is left for validation to report)."""
    if isinstance(mode, dict) and isinstance(mode.get("type"), str) and mode["type"] in MODES:
        return MODES.config_class(mode["type"]).resolve_paths(mode, base)
    return mode


#: Sections of a parameter set and their dotted prefixes in a scenario.
_SECTIONS = {"segment": "vehicle.segment", "links": "vehicle.links", "terrain_model": "terrain.model"}


def _text(v: object, path: str) -> str:
    if not isinstance(v, str):
        raise ScenarioError(f"{path}: expected text, got {quote(v)}.")
    return v


def parse_set_option(item: str) -> tuple[str, Any]:
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
        raise ScenarioError(f"--set {quote(item)}: the value is not valid YAML ({exc}).") from None
    return key, value


def apply_overrides(raw: dict, overrides: Iterable[tuple[str, Any]]) -> dict:
    """Return a copy of ``raw`` with each ``(dotted_key, value)`` set (sections created as needed)."""
    raw = _copy_tree(raw)
    for key, value in overrides:
        parts = key.split(".")
        node = raw
        for j, p in enumerate(parts[:-1]):
            nxt = node.get(p) if isinstance(node, dict) else None
            if nxt is None:
                nxt = {}
                node[p] = nxt
            if not isinstance(nxt, dict):
                raise ScenarioError(
                    f"--set {key}: '{'.'.join(parts[: j + 1])}' is a value, not a section; cannot set a key inside it."
                )
            node = nxt
        leaf: str | int = parts[-1]
        if isinstance(node, dict) and parts[-1].isdigit() and int(parts[-1]) in node:
            leaf = int(parts[-1])
        node[leaf] = value
        if isinstance(raw.get("sources"), dict) and parts[0] != "sources":
            raw["sources"].pop(key, None)  # a changed value's note no longer applies
        # a constant xt replaces a profile or random profile and vice versa (patches stay on a new xt)
        if parts[0] == "terrain" and len(parts) == 2 and parts[1] in ("xt", "profile", "random"):
            for other in ("xt", "profile", "random"):
                if other != parts[1]:
                    node.pop(other, None)
            if parts[1] != "xt":
                node.pop("patches", None)
    return raw


def read_yaml(path: str | os.PathLike[str]) -> dict:
    """Parse a YAML file with the hardened reader (:func:`snoworm.config.yamlio.read_yaml`).

    Syntax errors, non-UTF-8 files, duplicate keys, alias bombs, deep nesting, missing or empty
    files become :class:`ScenarioError` naming the file.
    """
    return yamlio.read_yaml(path)


def _shipped_dir() -> Path:
    return Path(str(resources.files("snoworm") / "scenarios"))


def shipped_scenarios() -> dict:
    """The scenarios shipped with snoworm: ``{name: (path, one-line description)}``, sorted by name."""
    out = {}
    for p in sorted(_shipped_dir().glob("*.yaml")):
        try:
            raw = read_yaml(p)
        except ScenarioError:  # pragma: no cover - the shipped files are tested
            continue
        desc = raw.get("description", "") if isinstance(raw, dict) else ""
        first = " ".join(str(desc).split())
        out[p.stem] = (p, first.split(". ")[0].rstrip(".") + "." if first else "")
    return out


def scenario_path(name_or_path: str | os.PathLike[str]) -> Path:
    """The file of a scenario given as a path or as the name of a shipped scenario.

    A path that exists wins; otherwise a name such as ``inchworm6`` (or ``inchworm6.yaml``)
    of :func:`shipped_scenarios` gives the shipped file; otherwise the path is returned as given
    (reading it then reports the missing file, with the shipped names).
    """
    path = Path(name_or_path)
    try:
        if path.exists():
            return path
    except (OSError, ValueError) as exc:  # a name too long, a NUL byte
        raise ScenarioError(
            f"{short_path(path)}: cannot be used as a scenario path ({getattr(exc, 'strerror', None) or exc}). "
            "Give a scenario file or a shipped scenario's name."
        ) from None
    text = str(name_or_path)
    name = text[:-5] if text.endswith(".yaml") else text
    if "/" not in text and "\\" not in text:
        shipped = _shipped_dir() / f"{name}.yaml"
        if shipped.is_file():
            return shipped
    return path


def read_scenario_yaml(name_or_path: str | os.PathLike[str]) -> tuple[dict, Path]:
    """(parsed YAML, the file) of a scenario path or shipped name (:func:`scenario_path`)."""
    path = scenario_path(name_or_path)
    try:
        return read_yaml(path), path
    except ScenarioError as exc:
        if os.path.lexists(path):
            raise
        names = ", ".join(shipped_scenarios())
        raise ScenarioError(
            f"{exc} A shipped scenario is named without a path, one of: {names} (`snoworm scenarios` lists them)."
        ) from None


def load_scenario(
    path: str | os.PathLike[str], overrides: Iterable[tuple[str, Any] | str] = (), *, trust_folder: bool = True
) -> Scenario:
    """Load, override and validate a scenario file.

    Parameters
    ----------
    path : str or Path
        YAML scenario file, or the name of a shipped scenario (``"inchworm6"``, see
        :func:`shipped_scenarios`); an existing path wins over a name.
    overrides : iterable of (str, object) or of "key=value" strings
        Dotted-key overrides applied before validation (the CLI's ``--set``; on a shipped
        scenario a relative controller file in them is taken from the working directory).
    trust_folder : bool
        Whether the scenario may run controller files from its folder (False for a scenario read
        back from a results folder; see :func:`scenario_from_dict`).
    """
    raw, path = read_scenario_yaml(path)
    ov = [parse_set_option(o) if isinstance(o, str) else o for o in overrides]
    if ov:
        if not isinstance(raw, dict):
            raise ScenarioError(f"{path}: a scenario must be a YAML mapping.")
        shipped = Path(path).resolve().parent == _shipped_dir().resolve()  # --set paths are the user's, not ours
        raw = apply_overrides(raw, yamlio.controller_paths_from_cwd(ov) if shipped else ov)
    return scenario_from_dict(raw, str(path), base_dir=Path(path).parent, trust_folder=trust_folder)


def dump_scenario(sc: Scenario, paths: dict | None = None) -> str:
    """The resolved scenario as YAML text, every value filled in (re-runnable), followed by the
    source of every physical value as comments (:attr:`Scenario.sources`).

    ``paths``: ``{dotted key: path}`` written instead of the scenario's own file paths (a results
    folder names its copies of :meth:`Scenario.data_files` relative to itself, e.g.
    ``{"terrain.route": "inputs/route.csv"}``; they are read relative to the scenario file)."""
    data = sc.to_dict()
    for key, value in (paths or {}).items():
        *sections, leaf = key.split(".")
        node = data
        for part in sections:
            node = node[part]
        node[leaf] = value
    lines = [
        "",
        "# Sources of the physical values (parameter set "
        f"{data['vehicle']['parameter_set']}; [user] scenario: changed by the scenario):",
    ]
    lines += [f"#   {k}: {v}" for k, v in sc.sources.items()]
    return yaml.safe_dump(data, sort_keys=False) + "\n".join(lines) + "\n"
