"""Mobility modes: controllers that drive the same chain physics (paper section 5).

Built-in modes, one module each: ``uniform`` (Figs 6-7), ``force_control`` (Figs 8-11),
``inchworm`` (section 5.1, Fig 5), ``supervisor`` (beyond the paper: rolls, inches where
rolling immobilises) and ``controller`` (a user's discrete-time controller, docs/controllers.md).  :class:`Mode` declares the contract; :func:`register_mode` adds a mode,
built-in or the user's own.
"""
from __future__ import annotations

from .base import MODES, Interval, Mode, mode_class, register_mode, rolling_interval, start_times
from .command import COMMAND_KEYS, CommandState, Observation, observe
from .controller import ControllerConfig, ControllerError, ControllerMode
from .force_control import ForceControlConfig, ForceControlMode
from .inchworm import InchwormConfig, InchwormMode
from .supervisor import SupervisorConfig, SupervisorMode
from .uniform import UniformConfig, UniformMode

__all__ = ["MODES", "Interval", "Mode", "mode_class", "register_mode", "rolling_interval", "start_times",
           "UniformConfig", "UniformMode", "ForceControlConfig", "ForceControlMode", "InchwormConfig",
           "InchwormMode", "SupervisorConfig", "SupervisorMode", "COMMAND_KEYS", "CommandState", "Observation",
           "observe", "ControllerConfig", "ControllerError", "ControllerMode"]
