"""snoworm: a fast reduced-order longitudinal simulator of multi-segment wheeled rovers on snow.

Public API
----------
load_scenario(path, overrides=())   -> Scenario (validated, frozen; ``Scenario.with_`` edits it);
                                       a path or a shipped scenario's name (``shipped_scenarios()``)
simulate(scenario, progress=None)   -> Result
simulate_batch(scenarios)           -> list of BatchMember (one stacked solve)
Result.write(out_dir)               -> files (CSV, JSON, YAML, PNG, manifest), all or nothing;
                                       OutputError for an unusable folder
Mode, ModeConfig, register_mode     -> add a mobility mode of your own
Simulator(scenario)                 -> reset() / step(command, dt) -> Observation; result() -> Result
mode: {type: controller, ...}       -> your own discrete-time controller (docs/controllers.md)
snoworm.env.SnowormEnv              -> a Gymnasium environment (extra: gym)

The layers and their modules are described in docs/architecture.md.
"""
from ._version import __version__  # noqa: E402

from . import modes as modes  # noqa: E402  (registers the built-in modes)
from .driver import BatchMember, SolverError, simulate, simulate_batch  # noqa: E402
from .fileio import OutputError  # noqa: E402
from .modes import Mode, register_mode  # noqa: E402
from .results import Result  # noqa: E402
from .scenario import Scenario, ScenarioError, load_scenario, scenario_from_dict, shipped_scenarios  # noqa: E402
from .sections import ModeConfig  # noqa: E402
from .simulator import Observation, Simulator  # noqa: E402

__all__ = ["__version__", "BatchMember", "Mode", "ModeConfig", "OutputError", "Result", "Scenario", "ScenarioError",
           "SolverError", "load_scenario", "register_mode", "scenario_from_dict", "shipped_scenarios", "simulate",
           "simulate_batch", "Observation", "Simulator"]
