"""Step-by-step simulation: advance a scenario's chain by commands held for ``dt`` (docs/controllers.md).

::

    sim = snoworm.Simulator(scenario)
    obs = sim.reset()                                   # Observation at t = 0
    obs = sim.step({"wheel_speed_mps": [1.8] * 6}, 0.02)  # command held for 20 ms
    res = sim.result()                                  # a Result, as simulate() returns

The chain, its initial state, the solver, its tolerances and the output grid are those of
:func:`snoworm.simulate` for the same scenario (the scenario's ``mode`` only gives the initial
state; the commands replace its control).  Each step is one period of the one stepper of one
chain or many (:class:`snoworm.simulation.stepper.ChainStepper`, with one member; one per reset:
the driver's interval solve, :meth:`snoworm.simulation.interval.IntervalSolver.solve`); the ``controller`` mode
(:mod:`snoworm.modes.controller`) runs the same intervals with the same observations and
commands (:mod:`snoworm.modes.command`), so a controller gives the same result either way.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from ..config.schema import quote
from ..config.sections import MAX_OUTPUT_SAMPLES
from ..modes import Mode
from ..modes.command import COMMAND_KEYS, CommandState, Observation, observe
from ..results.result import Result
from .driver import assemble
from .guard import SolverError
from .interval import output_grid
from .stepper import ChainStepper

if TYPE_CHECKING:
    from numpy.typing import ArrayLike, NDArray

    from ..config.scenario import Scenario
    from ..model.inputs import Controls

__all__ = ["Simulator", "Observation", "COMMAND_KEYS", "DT_MIN_S"]

#: Shortest step [s]: well below any control period, far above the solver's resolution at t ~ 1e3 s.
DT_MIN_S = 1e-6


class Simulator:
    """A scenario's chain advanced step by step with held commands.

    Parameters
    ----------
    scenario : Scenario
        The validated scenario (vehicle, terrain, tow, solver settings; its mode's initial state).
        ``simulation.duration_s`` does not limit stepping.
    record : bool
        Keep every step's output samples for :meth:`result` (default).  The record is bounded like
        a scenario's output (:data:`~snoworm.config.sections.MAX_OUTPUT_SAMPLES` times x segments): a step
        past it raises ValueError (call :meth:`reset`).  ``False``: memory stays flat however long
        you step (only :attr:`last_step` is kept, its samples then always starting at the step's
        start; :meth:`result` is unavailable), e.g. for reinforcement learning.

    Attributes
    ----------
    t_s : float
        Time reached [s].
    last_step : tuple or None
        ``(ts, ys, controls)`` of the last step: its output times, flat states and controls.
    """

    def __init__(self, scenario: Scenario, record: bool = True) -> None:
        self.scenario, self.record = scenario, bool(record)
        case = assemble(scenario)
        self.model = case.model
        self._y0 = np.array(case.mode.initial_state(), float)
        self.reset()

    def reset(self) -> Observation:
        """Back to t = 0 at the initial state, motors off and joints holding; the first observation."""
        self.t_s = 0.0
        self._y = self._y0.copy()
        self.commands = CommandState(self.model)
        self._pieces: list[tuple[NDArray[np.float64], NDArray[np.float64], Controls]] = []
        self._phases: list[dict[str, Any]] = []
        self._samples = 0
        # the one stepper of one chain or many (simulation.stepper); VODE (simulation.method) carries
        # its history across steps
        self._stepper = ChainStepper(self.model, self.scenario.simulation, 1, "step")
        self._stepper.carry_history = True
        self._wall_s = 0.0
        self.last_step: tuple[NDArray[np.float64], NDArray[np.float64], Controls] | None = None
        return self.observation()

    @property
    def state(self) -> NDArray[np.float64]:
        """The flat state at :attr:`t_s` (a copy)."""
        return self._y.copy()

    def observation(self) -> Observation:
        """The :class:`Observation` at the time reached (under the command held up to it)."""
        return observe(self.model, self._y, self.commands.controls, self.t_s)

    def step(self, command: Mapping[str, ArrayLike] | None, dt: float, restart: bool = False) -> Observation:
        """Hold ``command`` for ``dt`` seconds and return the observation at the end.

        Parameters
        ----------
        command : mapping or None
            Keys of :data:`~snoworm.modes.command.COMMAND_KEYS`; keys left out keep their value.
        dt : float
            Step length [s], > 0.  The solver chooses its own steps inside it with the
            scenario's tolerances, whatever ``dt`` is.
        restart : bool
            Restart VODE's history at this step (the ``solve_ivp`` methods restart at every
            step anyway).  By default VODE carries it on across the change of command, which
            pays while commands change little; after a large jump a restart costs fewer
            evaluations (measured on tow6, dt 0.1 s: 104 against 124 per step with random
            wheel-speed set-points; 4 against 10 with a held command).

        Raises
        ------
        ValueError
            Unknown command key, wrong length, non-finite value, or a bad ``dt`` (nothing changes).
        SolverError
            If every solver method fails (the simulator stays at the start of the step).
        """
        dt = self._check_dt(dt)
        wall0 = time.perf_counter()
        saved = self.commands.snapshot()
        ctl = self.commands.apply(command)
        t, t1 = self.t_s, self.t_s + float(dt)
        sim = self.scenario.simulation
        t_eval = output_grid(t, t1, sim.output_dt_s, include_start=not (self._phases and self.record))
        self._stepper.carry_history = not restart
        try:
            ys, y_end, failed, errors = self._stepper.solve(ctl, t, t1, self._y[None, :], t_eval)
            if failed[0]:
                raise SolverError(errors[0])
        except Exception:
            self.commands.restore(saved)
            raise
        ts, ys, t_next, y_next = np.asarray(t_eval, float), ys[:, 0, :], t1, y_end[0]
        if self.record:
            self._pieces.append((ts, ys, ctl))
            self._samples += len(ts)
        self.last_step = (ts, ys, ctl)
        self._phases.append({"t_start_s": t, "t_end_s": t_next, "label": "step"})
        if not self.record:
            self._phases = self._phases[-1:]  # only "a step was made" matters: memory stays flat
        self.t_s, self._y = t_next, y_next
        self._wall_s += time.perf_counter() - wall0
        return self.observation()

    def _check_dt(self, dt: Any) -> float:
        """``dt`` as a float within [:data:`DT_MIN_S`, the output cap] (ValueError naming it otherwise)."""
        ok = not isinstance(dt, bool) and isinstance(dt, (int, float, np.floating, np.integer))
        try:
            value = float(dt) if ok else math.nan
        except OverflowError:
            value = math.inf
        sim = self.scenario.simulation
        n = self.model.n
        dt_max = sim.output_dt_s * MAX_OUTPUT_SAMPLES / n
        if not math.isfinite(value) or not DT_MIN_S <= value <= dt_max:
            raise ValueError(
                f"dt: the step length must be a number of seconds from {DT_MIN_S:g} to {dt_max:g} "
                f"(at most {MAX_OUTPUT_SAMPLES} output samples x segments a step), got {quote(dt, 60)}"
            )
        if self.record and (self._samples + value / sim.output_dt_s + 2) * n > MAX_OUTPUT_SAMPLES:
            raise ValueError(
                f"Simulator: the recorded history would pass {MAX_OUTPUT_SAMPLES} output samples x "
                f"segments (memory) at t = {self.t_s:.6g} s. Call reset(), or use "
                "Simulator(scenario, record=False) to step without recording."
            )
        return value

    def result(self) -> Result:
        """A :class:`~snoworm.results.result.Result` of everything stepped since the last reset."""
        if not self.record:
            raise ValueError("Simulator.result: this Simulator was made with record=False and keeps no history")
        if not self._pieces:
            raise ValueError("Simulator.result: nothing simulated yet; call step() first")
        sc = self.scenario
        return Result.from_pieces(
            sc,
            self.model,
            Mode(sc.mode, sc, self.model),
            self._pieces,
            [dict(p) for p in self._phases],
            self.stats,
        )

    @property
    def stats(self) -> dict:
        """Solver counters since the last :meth:`reset` (``nfev``, ``njev``, ``nlu``, ``intervals``)
        and the wall-clock time spent stepping, ``wall_time_s``."""
        s = self._stepper.stats
        return {**{k: s[k] for k in ("nfev", "njev", "nlu", "intervals")}, "wall_time_s": self._wall_s}
