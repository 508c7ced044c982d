"""The guard around every solve: work limit, wall-time limit, solver breakdowns, sane states (issue 15).

Kept apart from the interval solve (:mod:`snoworm.simulation.interval`): :class:`WorkMeter` holds a
run to :data:`WORK_BASE_NFEV` + :func:`work_rate` right-hand sides per simulated second (+
:data:`WORK_NFEV_PER_INTERVAL` per step asked of a Simulator, an environment or a controller), and to
``simulation.max_wall_s``, read from the solver's own counters; :func:`guarded` turns the solver's
own breakdowns into :class:`SolverError`; :func:`check_sane` checks a run's states afterwards.
None of them changes a number of a run that stays within the limits.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, TypeVar, cast

import numpy as np

if TYPE_CHECKING:
    from numpy.typing import NDArray

    from ..config.sections import SimulationConfig
    from ..model.chain import ChainModel
    from ..model.inputs import Controls

    #: One solved stretch of a member: output times, states (one row per time), the controls held.
    Piece = tuple[NDArray[np.float64], NDArray[np.float64], Controls]

_T = TypeVar("_T")

__all__ = [
    "SolverError",
    "WORK_BASE_NFEV",
    "WORK_NFEV_PER_S",
    "WORK_NFEV_PER_INTERVAL",
    "SPEED_SANITY_FACTOR",
    "work_rate",
    "WorkMeter",
    "PROGRESS_EVERY_S",
    "guarded",
    "check_sane",
]


class SolverError(RuntimeError):
    """The ODE solver failed; the message carries the solver's own message and where it failed."""


#: Right-hand-side evaluations a run may use: this base (start-up transients) ...
WORK_BASE_NFEV = 20_000
#: ... plus this many per simulated second reached, at the default tolerances (rtol 1e-5,
#: atol_scale 1); tighter tolerances get (1e-5 / min(rtol, 1e-5 atol_scale))^(1/4) times more.
#: Shipped scenarios need under 600 per second; their rtol 1e-9 reference runs (allowed 10x)
#: under 4 000 (traverse_patch 3 765, inchworm6 2 346).
WORK_NFEV_PER_S = 5_000
#: ... plus, for steps asked (:meth:`~snoworm.simulation.stepwise.Simulator.step`, an environment's
#: step, a controller's period: ``IntervalSolver(asked_steps=True)``), this many per interval: each ends on its own time and restarts or
#: re-enters the solver, so many short steps need work that no simulated second pays for (tow6 and
#: inchworm6 with commands changing, dt 1e-6 to 1e-4 s: 1-2 evaluations per step on VODE carried
#: on, 5-7 restarted or on LSODA).  Without it, steps of 1e-4 s exhausted the limit at 0.75 s (issue
#: 30).  A mode's other intervals (gait phases, a supervisor's checks) get none: a mode whose
#: intervals shrink (events re-triggering, a tiny check interval) still meets the limit.
WORK_NFEV_PER_INTERVAL = 100
#: A run whose ground or wheel-rim speed exceeds this multiple of the fastest no-load wheel speed
#: R_w * omega_nl (plus the fastest joint rate) has left the physics: a solver failure.
SPEED_SANITY_FACTOR = 5.0


def work_rate(sim: SimulationConfig) -> float:
    """Right-hand-side evaluations allowed per simulated second for the run's tolerances."""
    tol = min(sim.rtol, 1e-5 * sim.atol_scale)
    return WORK_NFEV_PER_S * max(1.0, (1e-5 / tol) ** 0.25)


#: Within a long interval, ``progress`` hears of the simulated time reached at most this often [s].
PROGRESS_EVERY_S = 0.5


class WorkMeter:
    """The work and wall-time limits of one run, read from the solver's own counters.

    :class:`~snoworm.simulation.interval.IntervalSolver` calls :meth:`start` at every interval and
    :meth:`check` after every VODE step with VODE's own count of right-hand sides, and counts the
    calls of the ``solve_ivp`` methods in the one function it hands them (:meth:`counted`).  The
    limit is :data:`WORK_BASE_NFEV` + :func:`work_rate` per simulated second from the time of the
    first interval, + ``per_interval`` per interval started (:meth:`limit`), and
    ``simulation.max_wall_s`` of wall time from the meter's creation.  ``progress(t_s, duration_s)``
    hears of the time reached within long intervals, every :data:`PROGRESS_EVERY_S` of wall time.
    """

    def __init__(
        self,
        sim: SimulationConfig,
        name: str,
        progress: Callable[[float, float], object] | None = None,
        per_interval: int = 0,
    ) -> None:
        self.name, self.rate, self.max_wall_s = name, work_rate(sim), sim.max_wall_s
        #: right-hand sides allowed per interval started (:data:`WORK_NFEV_PER_INTERVAL` for steps asked)
        self.per_interval = per_interval
        self.duration_s = sim.duration_s
        self.t0: float | None = None
        #: intervals started (:meth:`start`)
        self.intervals = 0
        self.wall0 = self._shown = time.perf_counter()
        self.progress = progress

    def start(self, t: float) -> None:
        """An interval starts at ``t``: counted; simulated time counts from the first one's start."""
        if self.t0 is None:
            self.t0 = float(t)
        self.intervals += 1

    def limit(self, t: float) -> float:
        """Right-hand sides allowed by time ``t`` (in the current interval)."""
        return WORK_BASE_NFEV + self.rate * (t - cast(float, self.t0)) + self.per_interval * self.intervals

    def check(self, nfev: int, t: float) -> None:
        """Raise :class:`SolverError` if ``nfev`` right-hand sides by time ``t`` exceed the limits."""
        if nfev > self.limit(t):
            raise SolverError(
                f"work limit: {nfev} right-hand-side evaluations by t = {t:.6g} s of {self.name!r} "
                f"(limit {WORK_BASE_NFEV} + {self.rate:.0f} per simulated second"
                + (f" + {self.per_interval} per step, {self.intervals} steps" if self.per_interval else "")
                + "). The system is too stiff or too fast to integrate: "
                "lower the large gains, stiffnesses, forces or speeds of the scenario, or raise "
                "simulation.max_step_s / atol_scale if they are tiny."
            )
        if self.max_wall_s is not None:
            wall = time.perf_counter() - self.wall0
            if wall > self.max_wall_s:
                raise SolverError(
                    f"simulation.max_wall_s: {wall:.1f} s of wall time spent by t = {t:.6g} s "
                    f"of {self.name!r} (limit {self.max_wall_s:g} s). Shorten the run, relax "
                    "simulation.rtol or raise max_wall_s."
                )
        if self.progress is not None and time.perf_counter() - self._shown >= PROGRESS_EVERY_S:
            self._shown = time.perf_counter()
            self.progress(min(t, self.duration_s), self.duration_s)

    def counted(self, fun: Callable[..., _T], nfev0: int) -> Callable[..., _T]:
        """``fun(t, y, *args)`` counting its calls from ``nfev0`` against the limits (for ``solve_ivp``);
        the count so far is the returned function's ``calls[0]``."""
        check, rate, t0 = self.check, self.rate, cast(float, self.t0)
        calls, t_max = [nfev0], [t0]
        wall = self.max_wall_s is not None or self.progress is not None
        base = WORK_BASE_NFEV + self.per_interval * self.intervals

        def f(t: float, y: NDArray[np.float64], *args: Any) -> _T:
            n = calls[0] = calls[0] + 1
            if t > t_max[0]:
                t_max[0] = t
            if n > base + rate * (t_max[0] - t0) or (wall and n & 63 == 0):
                check(n, t_max[0])
            return fun(t, y, *args)

        f.calls = calls  # type: ignore[attr-defined]  # a counter the interval solver reads
        return f


def check_sane(model: ChainModel, pieces: Sequence[Sequence[Piece]], name: str) -> None:
    """Raise SolverError if a member's states are non-finite or its speeds far beyond the no-load speed."""
    lay = model.layout
    vnl = float(np.max(np.asarray(model.seg.wheel_radius_m) * np.asarray(model.seg.no_load_speed_radps)))
    rate = float(np.max(model.links.rate_max_mps, initial=0.0))
    limit = SPEED_SANITY_FACTOR * vnl + rate
    R = np.max(np.asarray(model.seg.wheel_radius_m))
    for piece in pieces:
        for ts, ys, _ in piece:
            Y = ys.reshape(ts.size, lay.n, lay.n_s)
            if not np.all(np.isfinite(Y)):
                raise SolverError(
                    f"non-finite state in {name!r} near t = {ts[0]:.6g} s; the run is meaningless. "
                    "Check the scenario's extreme values."
                )
            v = max(
                float(np.max(np.abs(Y[..., lay.v]), initial=0.0)),
                float(np.max(np.abs(Y[..., lay.omega]), initial=0.0)) * R,
            )
            if v > limit:
                k = int(np.argmax(np.max(np.abs(Y[..., lay.v]), axis=1)))
                raise SolverError(
                    f"speed {v:.3g} m/s in {name!r} near t = {ts[k]:.6g} s, beyond {limit:.3g} m/s "
                    f"({SPEED_SANITY_FACTOR:g} x the no-load wheel speed R_w*omega_nl = {vnl:.3g} m/s): "
                    "the chain has run away. Check forces, gains and speeds for extreme values."
                )


def guarded(fn: Callable[[], _T], name: str) -> _T:
    """``fn()`` with numpy/scipy warnings kept quiet and the solver's own breakdowns (singular
    matrices, ...) as :class:`SolverError`."""
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return fn()
        except (RuntimeError, ArithmeticError, np.linalg.LinAlgError) as exc:
            if type(exc) not in (
                RuntimeError,
                ArithmeticError,
                ZeroDivisionError,
                OverflowError,
                np.linalg.LinAlgError,
            ):
                raise  # SolverError, a mode's own error (e.g. ControllerError): as they are
            raise SolverError(
                f"the solver broke down in {name!r} ({type(exc).__name__}: {str(exc)[:200]}). "
                "The scenario is too stiff or has extreme values; check its gains, stiffnesses "
                "and forces, or try a smaller simulation.rtol."
            ) from None
