"""The ``controller`` mode: a user's discrete-time controller drives the chain (docs/controllers.md).

``mode: {type: controller, controller: "controllers/my.py:MyController", period_s: 0.02,
params: {...}}``.  A scenario with a controller is a program.  Validation checks the reference
statically and runs nothing (:mod:`snoworm.modes.codeload`: the file or module exists, parses
and defines the class); the code is imported, and the class constructed as
``MyController(params, scenario)``, only when a simulation starts, and only if the file lies in
the scenario's folder tree or a folder the user allowed (``--allow-code``).  The run is one
integration interval per period: at its start ``t`` the controller is called with the
:class:`~snoworm.modes.command.Observation` of the state at ``t`` and returns a command (a
mapping, :data:`~snoworm.modes.command.COMMAND_KEYS`), held until ``t + period_s`` (zero-order
hold), the paper's controllers running as ROS nodes at a fixed rate.

A controller that raises, or returns a bad command, stops the run with :class:`ControllerError`
(CLI exit status 1) whose message holds the time and the user's own traceback frames.
"""

from __future__ import annotations

import math
import os
import time
import traceback
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from ..config.mode_registry import ModeConfig
from ..config.schema import ScenarioError, field, quote
from ..config.sections import MAX_OUTPUT_SAMPLES
from .base import Interval, Mode, register_mode
from .codeload import (
    check_reference,
    code_files,
    import_class,
    resolve_spec,
    trust_problem,
)
from .command import CommandState, observe
from .watchdog import WallLimit, wall_limit

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from ..config.scenario import Scenario
    from ..model.chain import ChainModel

__all__ = [
    "ControllerConfig",
    "ControllerMode",
    "ControllerError",
    "load_controller",
    "construct",
    "user_traceback",
    "code_root",
    "trust_problem_of",
    "code_notice",
]

_PKG_DIR = Path(__file__).resolve().parents[1]


class ControllerError(RuntimeError):
    """A user's controller raised, or returned a bad command, during a run (CLI exit status 1)."""


#: Shortest control period [s], as :data:`snoworm.simulation.stepwise.DT_MIN_S` for a step.
PERIOD_MIN_S = 1e-6


@dataclass(frozen=True)
class ControllerConfig(ModeConfig):
    """``mode: {type: controller, controller: ..., period_s: ..., params: {...}}``."""

    type: str = field(choices=("controller",), doc="mode name")
    controller: str = field(
        doc="the controller class: 'file.py:ClassName' (relative to the scenario file) or 'package.module:ClassName'"
    )
    period_s: float = field(ge=PERIOD_MIN_S, le=1e5, unit="s", doc="control period: the command is held this long")
    params: dict[str, Any] = field(default_factory=dict, doc="parameters handed to the controller's constructor")

    @classmethod
    def resolve_paths(cls, raw: dict, base_dir: Path) -> dict:
        """A relative controller file made absolute from ``base_dir`` (the scenario file's folder),
        before validation, so that sweeps and the written ``scenario.yaml`` find it."""
        spec = raw.get("controller")
        if isinstance(spec, str):
            return {**raw, "controller": resolve_spec(spec, "mode.controller", Path(base_dir))}
        return raw  # not text: validation reports it

    def _check(self, path: str) -> None:
        check_reference(self.controller, f"{path}.controller")  # static: nothing imported, nothing run

    def check_scenario(self, scenario: Scenario, path: str) -> None:
        """Each control period is an interval that ends on an output sample: the periods of the run
        times the segments stay within :data:`~snoworm.config.sections.MAX_OUTPUT_SAMPLES` (memory;
        and the work limit allows each period its own share, so their number must be bounded)."""
        periods = math.ceil(scenario.simulation.duration_s / self.period_s - 1e-9)
        n = periods * scenario.vehicle.segments
        if n > MAX_OUTPUT_SAMPLES:
            raise ScenarioError(
                f"{path}.period_s: {scenario.simulation.duration_s:g} s in periods of {self.period_s:g} s are "
                f"{periods} control periods, each ending on an output sample: {n} samples (periods x "
                f"segments), over the {MAX_OUTPUT_SAMPLES} allowed (memory). Raise period_s or shorten "
                "simulation.duration_s."
            )


def code_root(scenario: Scenario) -> str | None:
    """The folder whose controller files ``scenario`` may run: ``scenario.origin.code_root`` (the
    scenario file's folder, resolved; None for a scenario read back from a results folder), or the
    working directory for a scenario made in Python."""
    origin = scenario.origin
    return origin.code_root if origin is not None else os.path.realpath(os.getcwd())


def trust_problem_of(
    scenario: Scenario, path: str = "mode.controller", allow_code: Iterable[str | os.PathLike[str]] = ()
) -> str | None:
    """Why ``scenario``'s controller may not run here, with the paths ``allow_code`` allowed (see
    :func:`snoworm.modes.codeload.trust_problem`)."""
    spec = cast(ControllerConfig, scenario.mode).controller
    return trust_problem(spec, code_root(scenario), path, allow_code)


def code_notice(scenario: Scenario, allow_code: Iterable[str | os.PathLike[str]] = ()) -> str:
    """``controller code <spec> (<files>)`` for the CLI's notice; ScenarioError if ``scenario``'s
    controller may not run (with ``allow_code`` allowed too)."""
    why = trust_problem_of(scenario, allow_code=allow_code)
    if why is not None:
        raise ScenarioError(why)
    spec = cast(ControllerConfig, scenario.mode).controller
    return f"controller code {spec} ({', '.join(str(f) for f in code_files(spec))})"


def load_controller(
    spec: str, path: str = "mode.controller", root: str | None = None, allow_code: Iterable[str | os.PathLike[str]] = ()
) -> type:
    """Import the controller class named by ``spec`` ('file.py:Name' or 'package.module:Name'):
    this RUNS the file's or module's code.  A file must lie under ``root`` or a path of
    ``allow_code``.

    Raises
    ------
    ScenarioError
        If the file or module cannot be found or imported, does not define class ``Name``, or
        may not run.
    """
    return import_class(spec, root, path, allow_code)


def construct(
    cfg: ControllerConfig,
    scenario: Scenario,
    path: str = "mode.controller",
    allow_code: Iterable[str | os.PathLike[str]] = (),
) -> Any:
    """A new controller instance, ``cls(params, scenario)`` (ScenarioError if the constructor fails);
    its code may run from the scenario's folder or a path of ``allow_code``."""
    cls = import_class(cfg.controller, code_root(scenario), path, allow_code)
    try:
        return cls(dict(cfg.params), scenario)
    except Exception as exc:  # noqa: BLE001 - a failing constructor is bad input
        raise ScenarioError(
            f"{path}: constructing {quote(cfg.controller)} with params {quote(dict(cfg.params))} "
            f"failed: {type(exc).__name__}: {quote(str(exc))}\n{user_traceback(exc)}".rstrip()
        ) from None


def user_traceback(exc: BaseException, limit: int = 2000) -> str:
    """The traceback of ``exc`` keeping only the frames outside the snoworm package (the user's),
    cut to about ``limit`` characters (a 1 MB message prints its head and tail)."""
    frames = [
        f for f in traceback.extract_tb(exc.__traceback__) if not Path(f.filename).resolve().is_relative_to(_PKG_DIR)
    ]
    text = "".join(traceback.format_list(frames) + traceback.format_exception_only(type(exc), exc))
    if len(text) > limit:
        text = text[: limit // 2] + f"\n... [{len(text) - limit} characters cut] ...\n" + text[-limit // 2 :]
    return text


def _working_directory() -> str | None:
    try:
        return os.getcwd()
    except OSError:  # the working directory was removed
        return None


@contextmanager
def _guard(deadline: float | None, when: str, limit: float | None) -> Iterator[None]:
    """Run a user's code: past ``deadline`` (``simulation.max_wall_s``, :mod:`snoworm.modes.watchdog`)
    or on ``sys.exit`` it stops with ControllerError; the process never ends on the user's word.
    A working directory the code changed (``os.chdir``) is restored: the caller's relative paths
    (``res.write("out")`` after the run) stay theirs."""
    cwd = _working_directory()
    try:
        with wall_limit(deadline):
            yield
    except WallLimit:
        raise ControllerError(
            f"simulation.max_wall_s: the controller was still running {when} when the "
            f"wall-clock limit of {limit:g} s passed (an endless loop?). Fix the controller or "
            "raise max_wall_s."
        ) from None
    except SystemExit as exc:
        raise ControllerError(
            f"controller called sys.exit({quote(exc.code, 40)}) {when}; a controller never ends "
            "the process. Raise an exception to stop the run."
        ) from None
    finally:
        if cwd is not None and _working_directory() != cwd:
            try:
                os.chdir(cwd)
            except OSError:
                pass


@register_mode
class ControllerMode(Mode):
    """One interval per control period, with the command the controller returned at its start."""

    name = "controller"
    config_class = ControllerConfig
    continue_solver = True  # short periods: VODE keeps its history across them
    steps_asked = True  # fixed periods, at most MAX_OUTPUT_SAMPLES / segments of them (check_scenario)

    runs_code = True  # takes the user's allow-list (Mode.runs_code)
    cfg: ControllerConfig

    def __init__(
        self,
        cfg: ControllerConfig,
        scenario: Scenario,
        model: ChainModel,
        allow_code: Iterable[str | os.PathLike[str]] = (),
    ) -> None:
        super().__init__(cfg, scenario, model)
        limit = scenario.simulation.max_wall_s
        self.deadline = time.perf_counter() + limit if limit is not None else None  # user code counts too
        with _guard(self.deadline, "while importing and constructing it", limit):
            self.controller = construct(cfg, scenario, allow_code=allow_code)
        self.commands = CommandState(model)
        self.calls = 0

    def interval(self, t: float, y: NDArray[np.float64]) -> Interval:
        """Call the controller with the observation at ``t``; hold its command until ``t + period_s``.

        Raises
        ------
        ControllerError
            If the controller raises (its own traceback frames in the message) or returns a bad
            command (the key and the time in the message).
        """
        obs = observe(self.model, y, self.commands.controls, t)
        with _guard(self.deadline, f"at t = {t:.6g} s", self.scenario.simulation.max_wall_s):
            try:
                command = self.controller(obs)
            except Exception as exc:  # noqa: BLE001 - the user's code: report it with their frames
                # formatted under the guard: the exception's __str__ is the user's code too
                raise ControllerError(f"controller raised at t = {t:.6g} s:\n{user_traceback(exc)}".rstrip()) from None
        self.calls += 1
        try:
            ctl = self.commands.apply(command)
        except ValueError as exc:
            raise ControllerError(f"controller returned a bad command at t = {t:.6g} s: {exc}") from None
        return Interval(t + self.cfg.period_s, ctl, [], "controller")

    def summary(self, result: Any) -> dict:
        """The controller (as resolved) and how many times it was called."""
        return {"controller": self.cfg.controller, "controller_calls": self.calls}
