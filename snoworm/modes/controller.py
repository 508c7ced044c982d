"""The ``controller`` mode: a user's discrete-time controller drives the chain (docs/controllers.md).

``mode: {type: controller, controller: "controllers/my.py:MyController", period_s: 0.02,
params: {...}}``.  The class is loaded and constructed once at validation (a missing file or
class, or a constructor that raises, is bad input: :class:`~snoworm.config.schema.ScenarioError`), and
constructed afresh for every run as ``MyController(params, scenario)``.  The run is one
integration interval per period: at its start ``t`` the controller is called with the
:class:`~snoworm.modes.command.Observation` of the state at ``t`` and returns a command (a
mapping, :data:`~snoworm.modes.command.COMMAND_KEYS`), held until ``t + period_s`` (zero-order
hold), the paper's controllers running as ROS nodes at a fixed rate.

A controller that raises, or returns a bad command, stops the run with :class:`ControllerError`
(CLI exit status 1) whose message holds the time and the user's own traceback frames.
"""
from __future__ import annotations

import hashlib
import importlib
import importlib.util
import sys
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..config.schema import ScenarioError, field, quote
from ..config.scenario import base_dir
from ..config.mode_registry import ModeConfig
from .base import Interval, Mode, register_mode
from .command import CommandState, observe

__all__ = ["ControllerConfig", "ControllerMode", "ControllerError", "load_controller", "construct", "user_traceback"]

_PKG_DIR = Path(__file__).resolve().parents[1]


class ControllerError(RuntimeError):
    """A user's controller raised, or returned a bad command, during a run (CLI exit status 1)."""


@dataclass(frozen=True)
class ControllerConfig(ModeConfig):
    """``mode: {type: controller, controller: ..., period_s: ..., params: {...}}``."""

    type: str = field(choices=("controller",), doc="mode name")
    controller: str = field(doc="the controller class: 'file.py:ClassName' (relative to the scenario file) "
                                "or 'package.module:ClassName'")
    period_s: float = field(gt=0, le=1e5, unit="s", doc="control period: the command is held this long")
    params: dict[str, Any] = field(default_factory=dict, doc="parameters handed to the controller's constructor")

    def _check(self, path):
        spec = _resolve(self.controller, f"{path}.controller")
        object.__setattr__(self, "controller", spec)    # file paths made absolute (scenario.yaml records them)
        load_controller(spec, f"{path}.controller")

    def check_scenario(self, scenario, path):
        construct(self, scenario, f"{path}.controller")


def _is_file_spec(target: str) -> bool:
    return target.endswith(".py") or "/" in target or "\\" in target


def _split(spec, path):
    target, sep, name = str(spec).rpartition(":")
    if not sep or not target or not name.isidentifier():
        raise ScenarioError(f"{path}: expected 'file.py:ClassName' or 'package.module:ClassName', got {quote(spec)}. "
                            "Name the class after a colon.")
    return target, name


def _resolve(spec, path):
    """``spec`` with a relative file path made absolute (from the scenario file's folder)."""
    target, name = _split(spec, path)
    if _is_file_spec(target) and not Path(target).is_absolute():
        target = str((base_dir() / target).resolve())
    return f"{target}:{name}"


#: loaded controller files: absolute path -> (modification time, module)
_FILES: dict = {}


def _load_file(target, path):
    p = Path(target)
    if not p.is_file():
        raise ScenarioError(f"{path}: controller file {p} does not exist (a relative path is taken from the "
                            "scenario file's folder). Fix the path.")
    mtime = p.stat().st_mtime_ns
    cached = _FILES.get(str(p))
    if cached and cached[0] == mtime:
        return cached[1]
    modname = "snoworm_controller_" + hashlib.sha1(str(p).encode()).hexdigest()[:12]
    spec = importlib.util.spec_from_file_location(modname, p)
    module = importlib.util.module_from_spec(spec)
    sys.modules[modname] = module
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # noqa: BLE001 - any error in the user's file is bad input
        sys.modules.pop(modname, None)
        raise ScenarioError(f"{path}: importing controller file {p} failed: {type(exc).__name__}: {exc}") from None
    _FILES[str(p)] = (mtime, module)
    return module


def load_controller(spec: str, path: str = "mode.controller"):
    """The controller class named by ``spec`` ('file.py:Name' or 'package.module:Name').

    Raises
    ------
    ScenarioError
        If the file or module cannot be found or imported, or does not define ``Name``.
    """
    target, name = _split(spec, path)
    if _is_file_spec(target):
        module, where = _load_file(target, path), f"controller file {target}"
    else:
        try:
            module = importlib.import_module(target)
        except Exception as exc:  # noqa: BLE001 - a missing or broken module is bad input
            raise ScenarioError(f"{path}: cannot import module {target!r} ({type(exc).__name__}: {exc}). "
                                "Give an importable module or a file path ending in .py.") from None
        where = f"module {target}"
    cls = getattr(module, name, None)
    if cls is None or not callable(cls):
        found = sorted(k for k, v in vars(module).items() if isinstance(v, type) and not k.startswith("_"))
        raise ScenarioError(f"{path}: {where} has no class {name!r}"
                            + (f" (it defines: {', '.join(found)})." if found else "."))
    return cls


def construct(cfg, scenario, path="mode.controller"):
    """A new controller instance, ``cls(params, scenario)`` (ScenarioError if the constructor fails)."""
    cls = load_controller(cfg.controller, path)
    try:
        return cls(dict(cfg.params), scenario)
    except Exception as exc:  # noqa: BLE001 - a failing constructor is bad input
        raise ScenarioError(f"{path}: constructing {cfg.controller} with params {dict(cfg.params)!r} failed: "
                            f"{type(exc).__name__}: {exc}\n{user_traceback(exc)}".rstrip()) from None


def user_traceback(exc) -> str:
    """The traceback of ``exc`` keeping only the frames outside the snoworm package (the user's)."""
    frames = [f for f in traceback.extract_tb(exc.__traceback__)
              if not Path(f.filename).resolve().is_relative_to(_PKG_DIR)]
    return "".join(traceback.format_list(frames) + traceback.format_exception_only(type(exc), exc))


@register_mode
class ControllerMode(Mode):
    """One interval per control period, with the command the controller returned at its start."""

    name = "controller"
    config_class = ControllerConfig
    continue_solver = True          # short periods: VODE keeps its history across them

    def __init__(self, cfg, scenario, model):
        super().__init__(cfg, scenario, model)
        self.controller = construct(cfg, scenario)
        self.commands = CommandState(model)
        self.calls = 0

    def interval(self, t, y):
        """Call the controller with the observation at ``t``; hold its command until ``t + period_s``.

        Raises
        ------
        ControllerError
            If the controller raises (its own traceback frames in the message) or returns a bad
            command (the key and the time in the message).
        """
        obs = observe(self.model, y, self.commands.controls, t)
        try:
            command = self.controller(obs)
        except Exception as exc:  # noqa: BLE001 - the user's code: report it with their frames
            raise ControllerError(f"controller raised at t = {t:.6g} s:\n{user_traceback(exc)}".rstrip()) from None
        self.calls += 1
        try:
            ctl = self.commands.apply(command)
        except ValueError as exc:
            raise ControllerError(f"controller returned a bad command at t = {t:.6g} s: {exc}") from None
        return Interval(t + self.cfg.period_s, ctl, [], "controller")

    def summary(self, result) -> dict:
        """The controller (as resolved) and how many times it was called."""
        return {"controller": self.cfg.controller, "controller_calls": self.calls}
