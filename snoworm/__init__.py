"""snoworm: a fast reduced-order longitudinal simulator of multi-segment wheeled rovers on snow.

Public API
----------
load_scenario(path, overrides=())   -> Scenario (validated, frozen; ``Scenario.with_`` edits it);
                                       a path or a shipped scenario's name (``shipped_scenarios()``)
simulate(scenario, progress=None)   -> Result
simulate_batch(scenarios)           -> list of BatchMember (one stacked solve)
Result.write(out_dir)               -> files (CSV, JSON, YAML, PNG/PDF/SVG plots, manifest), all or
                                       nothing; OutputError for an unusable folder
load_result(run_dir)                -> Result read back from a run folder
Result.to_pandas(), .to_xarray()    -> tidy DataFrames / an xarray Dataset (pip install 'snoworm[data]')
Result.plot(kind, ax=None)          -> a matplotlib Figure (the backend is never changed)
run_sweep(scenario, sets, ...)      -> SweepTable (``.to_pandas()``); load_sweep(out_dir) reads one back
odds(scenario, vary=..., ...)       -> OddsResult: P(go) per strategy with its interval, samples, Sobol indices
Mode, ModeConfig, register_mode     -> add a mobility mode of your own
Simulator(scenario)                 -> reset() / step(command, dt) -> Observation; result() -> Result
mode: {type: controller, ...}       -> your own discrete-time controller (docs/controllers.md)
import snoworm.env                  -> registers the Gymnasium env "snoworm/Snoworm-v0" and its vector
                                       env (extra: gym); ``import snoworm`` registers it too when
                                       gymnasium is already imported (it never imports gymnasium)

The layers and their modules are described in docs/architecture.md.
"""

from __future__ import annotations

import importlib
import sys
from typing import TYPE_CHECKING, Any

from ._version import __version__

#: The public API, in one list: each public name -> the module defining it (docs/architecture.md,
#: "The public surface").  ``__all__`` and ``dir(snoworm)`` derive from it; the names are imported
#: on first use (PEP 562), so that ``import snoworm`` and the command line start without NumPy,
#: SciPy, the sweeps or matplotlib; a command pays only for the modules it uses (``snoworm --help``
#: imports none of them).
_EXPORTS = {
    "BatchMember": "simulation.driver",
    "SolverError": "simulation.guard",
    "simulate": "simulation.driver",
    "simulate_batch": "simulation.driver",
    "OutputError": "infra.folders",
    "Mode": "modes",
    "register_mode": "modes",
    "Result": "results.result",
    "ResultFileError": "results.result",
    "load_result": "results.result",
    "Scenario": "config.scenario",
    "ScenarioError": "config.scenario",
    "load_scenario": "config.scenario",
    "scenario_from_dict": "config.scenario",
    "shipped_scenarios": "config.scenario",
    "ModeConfig": "config.mode_registry",
    "Observation": "simulation.stepwise",
    "Simulator": "simulation.stepwise",
    "SweepTable": "studies.sweep",
    "load_sweep": "studies.sweep",
    "run_sweep": "studies.sweep",
    "odds": "studies.odds",
    "OddsResult": "studies.odds",
}

__all__ = ["__version__", *sorted(_EXPORTS)]

if TYPE_CHECKING:
    # What type checkers and editors read: they do not run __getattr__ (``X as X`` marks a re-export
    # of a py.typed package).  At run time the names come from __getattr__; tests/test_init.py
    # checks that these imports name exactly the entries of _EXPORTS.
    from . import modes as modes
    from .config.mode_registry import ModeConfig as ModeConfig
    from .config.scenario import (
        Scenario as Scenario,
        ScenarioError as ScenarioError,
        load_scenario as load_scenario,
        scenario_from_dict as scenario_from_dict,
        shipped_scenarios as shipped_scenarios,
    )
    from .infra.folders import OutputError as OutputError
    from .modes import Mode as Mode, register_mode as register_mode
    from .results.result import Result as Result, ResultFileError as ResultFileError, load_result as load_result
    from .simulation.driver import BatchMember as BatchMember, simulate as simulate, simulate_batch as simulate_batch
    from .simulation.guard import SolverError as SolverError
    from .simulation.stepwise import Observation as Observation, Simulator as Simulator
    from .studies.odds import OddsResult as OddsResult, odds as odds
    from .studies.sweep import SweepTable as SweepTable, load_sweep as load_sweep, run_sweep as run_sweep


def __getattr__(name: str) -> Any:
    """Import a public name's module on first access (``snoworm.simulate``, ``from snoworm import
    Result``) and keep the name, so later lookups are plain attribute reads."""
    if name == "modes":  # the modes package (its registries import a built-in mode when looked up)
        return importlib.import_module(".modes", __name__)
    try:
        module = _EXPORTS[name]
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__) | {"modes"})


if "gymnasium" in sys.modules:  # an RL script imported gymnasium first: register the env id now
    importlib.import_module(".env", __name__)  # (never imported otherwise: the CLI stays light)
