"""A sweep's plan: its cases, each validated up front, and what its files record.

:func:`plan_sweep` parses the axes, builds the cases (:mod:`.cases`) and validates every case's
scenario (an invalid case is recorded, not run; a controller that may not run refuses the whole
sweep); :class:`SweepPlan` holds the result, with the resume key of ``sweep.json``
(:func:`_definition`: the scenario, the axes, the version and the contents of the files they name).
:mod:`.run` executes the plan.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field as dc_field

from ..._version import __version__
from ...config.scenario import Scenario, apply_overrides, read_scenario_yaml, scenario_from_dict
from ...config.schema import ScenarioError, short_key
from ...infra.csvwriter import canonical_json
from ...modes.codeload import allowed_paths
from ...modes.controller import trust_problem_of
from .cases import build_cases
from .inputs import input_hashes
from .metrics import one_line
from .spec import as_axes
from .summary import summary_columns

__all__ = ["SweepPlan", "KEEP_VALIDATED_MAX", "plan_sweep"]


def _base(scenario):
    """(raw mapping, source name, base_dir) of a path or a Scenario object."""
    if isinstance(scenario, Scenario):
        bd = scenario.origin.base_dir if scenario.origin is not None else None
        return scenario.to_dict(), scenario.name, (str(bd) if bd is not None else None)
    if isinstance(scenario, dict):
        return scenario, "scenario", None
    raw, path = read_scenario_yaml(scenario)
    return raw, str(path), str(path.resolve().parent)


def _definition(raw, axes, zip_, base_dir=None):
    """The resume key: the scenario mapping, the axes, the snoworm version and the contents of
    every file they name (:mod:`snoworm.studies.sweep.inputs`)."""
    return json.loads(
        json.dumps(
            {
                "scenario_sha256": hashlib.sha256(canonical_json(raw).encode()).hexdigest(),
                "axes": [{"key": a.key, "values": list(a.values)} for a in axes],
                "zip": bool(zip_),
                "snoworm_version": __version__,
                "inputs": input_hashes(raw, axes, base_dir),
            },
            default=str,
        )
    )


@dataclass
class SweepPlan:
    """A sweep's cases, validated, and what its files record."""

    axes: list
    raw: dict
    source: str
    base_dir: str | None
    cases: list
    invalid: dict  # case index -> one-line error of the cases whose scenario is rejected
    n_links: int
    columns: list
    definition: dict
    #: case index -> its validated Scenario, kept for local executors (see _plan)
    scenarios: dict = dc_field(default_factory=dict)
    #: resolved paths whose controller code may run (run_sweep's allow_code), handed to every task
    allow_code: list = dc_field(default_factory=list)

    @property
    def keys(self):
        return [a.key for a in self.axes]


#: Most validated scenarios a sweep keeps for its local executor (about 5 KiB each; a worker
#: process receives them pickled, ~0.05 ms against ~0.6 ms to validate again), so that a case is
#: not validated twice; larger sweeps validate again in the executor to bound memory.
KEEP_VALIDATED_MAX = 20_000


def plan_sweep(scenario, sets, zip_, save_cases, out_dir, jobs, keep=False, allow_code=()) -> SweepPlan:
    """Parse the axes, build the cases and validate each one (about 2 ms a case).

    ``keep``: the cases run in this process or its own worker pool; keep their validated
    scenarios (up to :data:`KEEP_VALIDATED_MAX` cases) for the tasks.  ``allow_code``: see
    ``run_sweep`` (a controller that may not run refuses the whole sweep here)."""
    allow = list(allowed_paths(allow_code))  # ScenarioError for an empty path
    plan = _plan_cases(scenario, sets, zip_, save_cases, out_dir, jobs, keep, allow)
    plan.allow_code = allow
    return plan


def _plan_cases(scenario, sets, zip_, save_cases, out_dir, jobs, keep, allow_code) -> SweepPlan:
    axes = as_axes(sets)
    raw, source, base_dir = _base(scenario)
    if not isinstance(raw, dict):
        raise ScenarioError(f"{source}: a scenario must be a YAML mapping.")
    cases = build_cases(axes, zip_)
    if save_cases and out_dir is None:
        raise ScenarioError("--save-cases needs --out: the time series are written under DIR/cases/.")
    if int(jobs) < 1:
        raise ScenarioError(f"-j/--jobs must be at least 1, got {jobs}.")
    invalid, n_links, kept = {}, 0, {}
    keep = keep and len(cases) <= KEEP_VALIDATED_MAX
    for c in cases:
        try:
            sc = scenario_from_dict(apply_overrides(raw, c.overrides(axes)), source, base_dir=base_dir)
        except ScenarioError as exc:
            invalid[c.index] = one_line(exc)
            continue
        why = trust_problem_of(sc, allow_code=allow_code) if sc.mode.type == "controller" else None
        if why is not None:  # refused for the whole sweep, before anything runs
            raise ScenarioError(f"case {c.case_id}: {why}")
        n_links = max(n_links, sc.vehicle.segments - 1)
        if keep:
            kept[c.index] = sc
    if len(invalid) == len(cases):
        first = invalid[cases[0].index]
        raise ScenarioError(
            f"every case of the sweep is invalid, e.g. case {cases[0].case_id} "
            f"({', '.join(f'{short_key(a.key)}={short_key(v)}' for a, v in zip(axes, cases[0].values))}): {first}"
        )
    return SweepPlan(
        axes,
        raw,
        source,
        base_dir,
        cases,
        invalid,
        n_links,
        summary_columns(axes, n_links),
        _definition(raw, axes, zip_, base_dir),
        kept,
    )
