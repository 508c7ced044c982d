"""snoworm: a fast reduced-order longitudinal simulator of multi-segment wheeled rovers on snow.

Public API
----------
load_scenario(path, overrides=())   -> Scenario (validated, frozen; ``Scenario.with_`` edits it)
simulate(scenario)                  -> Result
simulate_batch(scenarios)           -> list of BatchMember (one stacked solve)
Result.write(out_dir)               -> files (CSV, JSON, YAML, PNG/PDF/SVG plots)
load_result(run_dir)                -> Result read back from a run folder
Result.to_pandas(), .to_xarray()    -> tidy DataFrames / an xarray Dataset (pip install 'snoworm[data]')
Result.plot(kind, ax=None)          -> a matplotlib Figure (the backend is never changed)
run_sweep(scenario, sets, ...)      -> SweepTable (``.to_pandas()``); load_sweep(out_dir) reads one back
Mode, ModeConfig, register_mode     -> add a mobility mode of your own
Simulator(scenario)                 -> reset() / step(command, dt) -> Observation; result() -> Result
mode: {type: controller, ...}       -> your own discrete-time controller (docs/controllers.md)
snoworm.env.SnowormEnv              -> a Gymnasium environment (extra: gym)

The layers and their modules are described in docs/architecture.md.
"""
from ._version import __version__  # noqa: E402

from . import modes as modes  # noqa: E402  (registers the built-in modes)
from .driver import BatchMember, SolverError, simulate, simulate_batch  # noqa: E402
from .modes import Mode, register_mode  # noqa: E402
from .results import Result, load_result  # noqa: E402
from .scenario import Scenario, ScenarioError, load_scenario, scenario_from_dict  # noqa: E402
from .sections import ModeConfig  # noqa: E402
from .simulator import Observation, Simulator  # noqa: E402
from .sweep import SweepTable, load_sweep, run_sweep  # noqa: E402

__all__ = ["__version__", "BatchMember", "Mode", "ModeConfig", "Observation", "Result", "Scenario", "ScenarioError",
           "Simulator", "SolverError", "SweepTable", "load_result", "load_scenario", "load_sweep", "register_mode",
           "run_sweep", "scenario_from_dict", "simulate", "simulate_batch"]
