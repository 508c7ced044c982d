"""snoworm: a fast reduced-order longitudinal simulator of multi-segment wheeled rovers on snow.

Public API
----------
load_scenario(path, overrides=())   -> Scenario
simulate(scenario)                  -> Result
Result.write(out_dir)               -> files (CSV, JSON, YAML, PNG)
"""
__version__ = "0.1.0"

from .scenario import Scenario, ScenarioError, load_scenario, scenario_from_dict  # noqa: E402
from .simulate import SolverError, simulate  # noqa: E402

__all__ = ["__version__", "Scenario", "ScenarioError", "SolverError", "load_scenario",
           "scenario_from_dict", "simulate"]
