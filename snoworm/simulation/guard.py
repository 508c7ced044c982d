"""The guard around every solve: work limit, wall-time limit, solver breakdowns, sane states (issue 15).

Kept apart from the interval driver (:mod:`snoworm.simulation.driver`): :func:`guarded` hands the
driver a counting proxy of the model (:data:`WORK_BASE_NFEV` + :func:`work_rate` right-hand sides
per simulated second, ``simulation.max_wall_s``) and turns the solver's own breakdowns into
:class:`SolverError`; :func:`check_sane` checks a run's states afterwards.  Neither changes a
number of a run that stays within the limits.
"""
from __future__ import annotations

import time
import warnings

import numpy as np

__all__ = ["SolverError", "WORK_BASE_NFEV", "WORK_NFEV_PER_S", "SPEED_SANITY_FACTOR", "work_rate", "guarded",
           "check_sane"]


class SolverError(RuntimeError):
    """The ODE solver failed; the message carries the solver's own message and where it failed."""


#: Right-hand-side evaluations a run may use: this base (start-up transients) ...
WORK_BASE_NFEV = 20_000
#: ... plus this many per simulated second reached, at the default tolerances (rtol 1e-5,
#: atol_scale 1); tighter tolerances get (1e-5 / min(rtol, 1e-5 atol_scale))^(1/4) times more.
#: Shipped scenarios need under 600 per second; their rtol 1e-9 reference runs (allowed 10x)
#: under 4 000 (traverse_patch 3 765, inchworm6 2 346).
WORK_NFEV_PER_S = 5_000
#: A run whose ground or wheel-rim speed exceeds this multiple of the fastest no-load wheel speed
#: R_w * omega_nl (plus the fastest joint rate) has left the physics: a solver failure.
SPEED_SANITY_FACTOR = 5.0


def work_rate(sim) -> float:
    """Right-hand-side evaluations allowed per simulated second for the run's tolerances."""
    tol = min(sim.rtol, 1e-5 * sim.atol_scale)
    return WORK_NFEV_PER_S * max(1.0, (1e-5 / tol) ** 0.25)


#: Within a long interval, ``progress`` hears of the simulated time reached at most this often [s].
PROGRESS_EVERY_S = 0.5


class _Metered:
    """The model as the solver sees it: ``rhs`` counts its calls against the work limit
    (:data:`WORK_BASE_NFEV` + :data:`WORK_NFEV_PER_S` per simulated second reached), checks
    ``simulation.max_wall_s`` and reports the time reached to ``progress`` within long intervals
    (every :data:`PROGRESS_EVERY_S` of wall time); every other attribute is the model's own."""

    def __init__(self, model, sim, name, t0=0.0, progress=None):
        self._model, self._sim, self._name, self._t0 = model, sim, name, float(t0)
        self._n, self._t_max, self._wall0 = 0, float(t0), time.perf_counter()
        self._rate = work_rate(sim)
        self._progress, self._shown = progress, self._wall0

    def __getattr__(self, attr):
        return getattr(self._model, attr)

    def rhs(self, t, y, *args):
        """The model's right-hand side, counted."""
        self._n += 1
        self._t_max = max(self._t_max, float(t))
        if self._n > WORK_BASE_NFEV + self._rate * (self._t_max - self._t0):
            raise SolverError(
                f"work limit: {self._n} right-hand-side evaluations by t = {self._t_max:.6g} s of {self._name!r} "
                f"(limit {WORK_BASE_NFEV} + {self._rate:.0f} per simulated second). The system is too stiff or "
                "too fast to integrate: lower the large gains, stiffnesses, forces or speeds of the scenario, or "
                "raise simulation.max_step_s / atol_scale if they are tiny.")
        if self._sim.max_wall_s is not None and self._n % 256 == 0:
            wall = time.perf_counter() - self._wall0
            if wall > self._sim.max_wall_s:
                raise SolverError(f"simulation.max_wall_s: {wall:.1f} s of wall time spent by t = {self._t_max:.6g} s "
                                  f"of {self._name!r} (limit {self._sim.max_wall_s:g} s). Shorten the run, relax "
                                  "simulation.rtol or raise max_wall_s.")
        if self._progress is not None and self._n % 64 == 0 and time.perf_counter() - self._shown >= PROGRESS_EVERY_S:
            self._shown = time.perf_counter()
            self._progress(min(self._t_max, self._sim.duration_s), self._sim.duration_s)
        return self._model.rhs(t, y, *args)


def check_sane(model, pieces, name):
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
                raise SolverError(f"non-finite state in {name!r} near t = {ts[0]:.6g} s; the run is meaningless. "
                                  "Check the scenario's extreme values.")
            v = max(float(np.max(np.abs(Y[..., lay.v]), initial=0.0)),
                    float(np.max(np.abs(Y[..., lay.omega]), initial=0.0)) * R)
            if v > limit:
                k = int(np.argmax(np.max(np.abs(Y[..., lay.v]), axis=1)))
                raise SolverError(f"speed {v:.3g} m/s in {name!r} near t = {ts[k]:.6g} s, beyond {limit:.3g} m/s "
                                  f"({SPEED_SANITY_FACTOR:g} x the no-load wheel speed R_w*omega_nl = {vnl:.3g} m/s): "
                                  "the chain has run away. Check forces, gains and speeds for extreme values.")


def guarded(fn, model, sim, name, t0=0.0, progress=None):
    """``fn(metered model)`` under the work limit from ``t0``, with numpy/scipy warnings kept quiet
    and the solver's own breakdowns (singular matrices, ...) as :class:`SolverError`; ``progress`` hears of
    the time reached within long intervals."""
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return fn(_Metered(model, sim, name, t0, progress))
        except (RuntimeError, ArithmeticError, np.linalg.LinAlgError) as exc:
            if type(exc) not in (RuntimeError, ArithmeticError, ZeroDivisionError, OverflowError,
                                 np.linalg.LinAlgError):
                raise           # SolverError, a mode's own error (e.g. ControllerError): as they are
            raise SolverError(f"the solver broke down in {name!r} ({type(exc).__name__}: {str(exc)[:200]}). "
                              "The scenario is too stiff or has extreme values; check its gains, stiffnesses "
                              "and forces, or try a smaller simulation.rtol.") from None
