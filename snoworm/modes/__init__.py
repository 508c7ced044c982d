"""Mobility modes: controllers that drive the same chain physics (paper section 5).

Built-in modes, one module each: ``uniform`` (Figs 6-7), ``force_control`` (Figs 8-11),
``inchworm`` (section 5.1, Fig 5), ``supervisor`` (beyond the paper: rolls, inches where
rolling immobilises) and ``controller`` (a user's discrete-time controller, docs/controllers.md).  :class:`Mode` declares the contract; :func:`register_mode` adds a mode,
built-in or the user's own.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from .base import MODES, Interval, Mode, mode_class, register_mode, rolling_interval, start_times
from .command import COMMAND_KEYS, CommandState, Observation, observe

#: Names of the built-in modes' modules, imported on first use (PEP 562) so that a run imports
#: only its own mode (the registries import a mode's module when its type is looked up).
_LAZY = {
    "ControllerConfig": "controller",
    "ControllerError": "controller",
    "ControllerMode": "controller",
    "ForceControlConfig": "force_control",
    "ForceControlMode": "force_control",
    "InchwormConfig": "inchworm",
    "InchwormMode": "inchworm",
    "SupervisorConfig": "supervisor",
    "SupervisorMode": "supervisor",
    "UniformConfig": "uniform",
    "UniformMode": "uniform",
}

__all__ = [
    "MODES",
    "Interval",
    "Mode",
    "mode_class",
    "register_mode",
    "rolling_interval",
    "start_times",
    "UniformConfig",
    "UniformMode",
    "ForceControlConfig",
    "ForceControlMode",
    "InchwormConfig",
    "InchwormMode",
    "SupervisorConfig",
    "SupervisorMode",
    "COMMAND_KEYS",
    "CommandState",
    "Observation",
    "observe",
    "ControllerConfig",
    "ControllerError",
    "ControllerMode",
]

if TYPE_CHECKING:  # for type checkers and editors; at run time the names come from __getattr__
    from .controller import ControllerConfig, ControllerError, ControllerMode
    from .force_control import ForceControlConfig, ForceControlMode
    from .inchworm import InchwormConfig, InchwormMode
    from .supervisor import SupervisorConfig, SupervisorMode
    from .uniform import UniformConfig, UniformMode


def __getattr__(name: str):
    """Import a built-in mode's module on first access to one of its names."""
    try:
        module = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
