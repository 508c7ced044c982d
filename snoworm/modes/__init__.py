"""Mobility modes: controllers that drive the same chain physics (paper section 5).

Built-in modes, one module each: ``uniform`` (Figs 6-7), ``force_control`` (Figs 8-11),
``inchworm`` (section 5.1, Fig 5), ``supervisor`` (beyond the paper: rolls, inches where
rolling immobilises) and ``controller`` (a user's discrete-time controller, docs/controllers.md).  :class:`Mode` declares the contract; :func:`register_mode` adds a mode,
built-in or the user's own.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from . import base, command  # noqa: F401  (the registries; every run needs them)

#: The modes' public names, in one list: each name -> the module defining it.  ``__all__`` and
#: ``dir()`` derive from it; the names are imported on first use (PEP 562), so that a run imports
#: only its own mode (the registries import a mode's module when its type is looked up).
_EXPORTS = {
    "MODES": "base",
    "Interval": "base",
    "Mode": "base",
    "mode_class": "base",
    "register_mode": "base",
    "rolling_interval": "base",
    "start_times": "base",
    "COMMAND_KEYS": "command",
    "CommandState": "command",
    "Observation": "command",
    "observe": "command",
    "UniformConfig": "uniform",
    "UniformMode": "uniform",
    "ForceControlConfig": "force_control",
    "ForceControlMode": "force_control",
    "InchwormConfig": "inchworm",
    "InchwormMode": "inchworm",
    "SupervisorConfig": "supervisor",
    "SupervisorMode": "supervisor",
    "ControllerConfig": "controller",
    "ControllerError": "controller",
    "ControllerMode": "controller",
}

__all__ = list(_EXPORTS)

if TYPE_CHECKING:
    # What type checkers and editors read: they do not run __getattr__ (``X as X`` marks a re-export
    # of a py.typed package).  At run time the names come from __getattr__; tests/test_init.py
    # checks that these imports name exactly the entries of _EXPORTS.
    from .base import (
        MODES as MODES,
        Interval as Interval,
        Mode as Mode,
        mode_class as mode_class,
        register_mode as register_mode,
        rolling_interval as rolling_interval,
        start_times as start_times,
    )
    from .command import (
        COMMAND_KEYS as COMMAND_KEYS,
        CommandState as CommandState,
        Observation as Observation,
        observe as observe,
    )
    from .controller import (
        ControllerConfig as ControllerConfig,
        ControllerError as ControllerError,
        ControllerMode as ControllerMode,
    )
    from .force_control import ForceControlConfig as ForceControlConfig, ForceControlMode as ForceControlMode
    from .inchworm import InchwormConfig as InchwormConfig, InchwormMode as InchwormMode
    from .supervisor import SupervisorConfig as SupervisorConfig, SupervisorMode as SupervisorMode
    from .uniform import UniformConfig as UniformConfig, UniformMode as UniformMode


def __getattr__(name: str) -> Any:
    """Import a public name's module on first access (a built-in mode's module the first time)."""
    try:
        module = _EXPORTS[name]
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
