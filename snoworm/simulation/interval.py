"""The interval solve: one object per run that integrates the chain from one control change to the next.

:class:`IntervalSolver` is built once per run from the model and the simulation settings and owns
what lasts across intervals: the solver counters (:attr:`IntervalSolver.stats`), the options of
each method (tolerances, Jacobian), the run's :class:`~snoworm.simulation.vode.VodeStepper` and
the work meter (:class:`~snoworm.simulation.guard.WorkMeter`).  The driver
(:mod:`snoworm.simulation.driver`: single runs) and the one stepper of one chain or many
(:class:`~snoworm.simulation.stepper.ChainStepper`, one per stack: a batch's, the step-by-step
:class:`~snoworm.simulation.stepwise.Simulator`'s, the environments') call
:meth:`IntervalSolver.solve`, so every run integrates the same way.  An interval that fails with the configured method is retried with the
implicit methods not yet tried; when every method fails, :class:`SolverError` carries the
solvers' messages.
"""

from __future__ import annotations

import logging
import math

import numpy as np
from scipy.integrate import solve_ivp

from .guard import WORK_NFEV_PER_INTERVAL, SolverError, WorkMeter, guarded
from .vode import VodeStepper

__all__ = ["ATOL", "IntervalSolver", "atol_per_field", "output_grid", "solver_options"]

#: Solver fallbacks and retries are logged here (INFO).
logger = logging.getLogger("snoworm")

#: Absolute tolerance of each state field, multiplied by ``simulation.atol_scale`` and the
#: field's factor in ``simulation.atol_scale_fields``.
ATOL = {
    "x_m": 1e-6,
    "v_mps": 1e-6,
    "omega_front": 1e-5,
    "omega_rear": 1e-5,
    "integral_front_Nm": 1e-4,
    "integral_rear_Nm": 1e-4,
    "q_mps": 1e-6,
    "s_m": 1e-7,
    "j_front_m": 1e-7,
    "j_rear_m": 1e-7,
    "z_front_m": 1e-7,
    "z_rear_m": 1e-7,
}


def atol_per_field(sim) -> dict:
    """Absolute tolerance of each state field: :data:`ATOL` times ``simulation.atol_scale`` and the
    field's factor in ``simulation.atol_scale_fields`` (1 where it has none)."""
    f = sim.atol_scale_fields
    return {k: v * sim.atol_scale * f.get(k, 1.0) for k, v in ATOL.items()}


def solver_options(model, sim, method=None) -> dict:
    """``solve_ivp`` keyword arguments for the model: method, tolerances, Jacobian structure."""
    method = method or sim.method
    opts = {"method": method, "rtol": sim.rtol, "atol": model.layout.per_state(atol_per_field(sim))}
    if sim.max_step_s is not None:
        opts["max_step"] = sim.max_step_s
    if method in ("LSODA", "VODE"):
        opts["lband"], opts["uband"] = model.bandwidths()
        opts["jac"] = model.jacobian_banded
    elif method in ("BDF", "Radau"):
        opts["jac"] = model.jacobian_sparse
    return opts


def output_grid(t0, t1, dt, include_start) -> list:
    """Output times of an interval: the multiples of ``dt`` inside it, its end, and its start if asked."""
    k0 = math.floor(t0 / dt + 1e-9) + 1
    k1 = math.ceil(t1 / dt - 1e-9) - 1
    inner = [t for t in (k * dt for k in range(k0, k1 + 1)) if t0 < t < t1]
    return ([t0] if include_start else []) + inner + [t1]


def _fallbacks(method):
    """The configured method first, then the implicit methods not yet tried (VODE: LSODA first)."""
    first = [method, "LSODA"] if method == "VODE" else [method]
    return first + [m for m in ("BDF", "Radau") if m != method]


def _terminal(ev):
    """A mode's event ``ev(t, y)`` as a terminal solve_ivp event (which also receives ``args``)."""

    def f(t, y, _ctl):
        return ev(t, y)

    f.terminal = True
    f.direction = getattr(ev, "direction", 0)
    return f


class IntervalSolver:
    """The interval solve of one run (single chain, or a stack of batch members).

    Parameters
    ----------
    model : ChainModel
    sim : SimulationConfig
        Method, tolerances, step limit, wall-time limit.
    name : str
        The run's name for messages.
    carry_history : bool
        With VODE, do not restart the stepper where the previous interval ended (at its end time
        and state exactly): its history carries on across the change of controls (the
        :class:`~snoworm.simulation.stepwise.Simulator`'s short steps; the stepper restarts by
        itself if VODE then fails).  May be changed between calls.
    progress : callable, optional
        ``progress(t_s, duration_s)`` within long intervals (:class:`~snoworm.simulation.guard.WorkMeter`).
    vode_stack : bool
        A stacked model (B members) may run on VODE, with its tolerances divided by sqrt(B) so that
        VODE's RMS error norm over the stack <= 1 implies each member's own <= 1 (what it has alone);
        without it a stack skips VODE for LSODA (max norm).
    stats : dict, optional
        The counters to update (default: a new dict), e.g. a caller's own with more keys.
    asked_steps : bool
        Each call of :meth:`solve` is a step asked (a Simulator's, an environment's, a controller's period):
        the work limit allows it :data:`~snoworm.simulation.guard.WORK_NFEV_PER_INTERVAL` more.

    Attributes
    ----------
    stats : dict
        Solver work of the run so far: ``nfev``, ``njev``, ``nlu``, ``intervals`` (and ``retries``
        once an interval needed another method).
    meter : WorkMeter
        The run's work and wall-time limits, counted from the first interval's start.
    """

    def __init__(
        self,
        model,
        sim,
        name="",
        carry_history=False,
        progress=None,
        vode_stack=False,
        stats=None,
        asked_steps=False,
    ):
        self.model, self.sim, self.name = model, sim, name
        self.carry_history, self.vode_stack = bool(carry_history), bool(vode_stack)
        self.stats = {"nfev": 0, "njev": 0, "nlu": 0, "intervals": 0} if stats is None else stats
        self.meter = WorkMeter(sim, name, progress, WORK_NFEV_PER_INTERVAL if asked_steps else 0)
        self._options = {}
        self._stepper = None

    def options(self, method) -> dict:
        """:func:`solver_options` of ``method`` for this run (computed once)."""
        o = self._options.get(method)
        if o is None:
            o = self._options[method] = solver_options(self.model, self.sim, method)
        return o

    def solve(self, controls, t0, t1, y, events=(), t_eval=None, label="interval"):
        """Integrate from ``(t0, y)`` to ``t1`` (or the first terminal event) under ``controls``.

        Parameters
        ----------
        controls : Controls
        t0, t1 : float
            Start and end of the interval [s].
        y : ndarray
            Flat state at ``t0``.
        events : sequence of callable
            The mode's terminal events ``ev(t, y)`` (``direction`` attribute as in ``solve_ivp``).
        t_eval : sequence of float
            Output times (:func:`output_grid`).
        label : str
            The interval's name for error messages.

        Returns
        -------
        (ts, ys, t_next, y_next, event_index) : tuple
            Output times and states ``(n_t, n_states)``, where the interval ended, the state there,
            and the index of the event that ended it (None at ``t1``).
        """
        self.meter.start(t0)
        return guarded(lambda: self._solve(controls, t0, t1, y, list(events or ()), t_eval, label), self.name)

    def _solve(self, ctl, t, t1, y, events, t_eval, label):
        failures, model = [], self.model
        for method in _fallbacks(self.sim.method):
            if method == "VODE" and model.n_batch > 1 and not self.vode_stack:
                continue  # stacked members: LSODA's max-norm error test (see simulate_batch)
            try:
                out = (self._vode if method == "VODE" else self._solve_ivp)(method, ctl, t, t1, y, events, t_eval)
            except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
                failures.append(f"{method}: {exc}")
                continue
            if isinstance(out, str):
                failures.append(f"{method}: {out}")
                continue
            if failures:
                logger.info(
                    "interval '%s' from t = %.6g s: %s; retried with %s, which succeeded",
                    label,
                    t,
                    "; ".join(failures),
                    method,
                )
                self.stats["retries"] = self.stats.get("retries", 0) + len(failures)
            self.stats["intervals"] += 1
            return out
        logger.info("interval '%s' from t = %.6g s: %s", label, t, "; ".join(failures))
        raise SolverError(
            f"every method failed at t = {t:.6g} s in interval '{label}': "
            + "; ".join(failures)
            + ". Try a smaller simulation.rtol or max_step_s."
        )

    def _vode(self, method, ctl, t, t1, y, events, t_eval):
        """One interval on the run's VODE stepper (restarted at ``t`` unless it carries its history)."""
        st = self._stepper
        if st is None:
            o = self.options("VODE")
            k = 1.0 / np.sqrt(self.model.n_batch)  # 1 for one chain; 1/sqrt(B) for a stack (vode_stack)
            st = self._stepper = VodeStepper(
                self.model.rhs,
                self.model.jacobian_banded,
                self.model.n_states,
                rtol=o["rtol"] * k,
                atol=o["atol"] * k,
                lband=o["lband"],
                uband=o["uband"],
                max_step=o.get("max_step"),
            )
        before = (st.nfev, st.njev, st.nlu)
        st.ctl = ctl
        if not (self.carry_history and st.t == t and np.array_equal(st.y, y)):
            st.restart(t, y)
        base = self.stats["nfev"] - before[0]  # the run's count = base + the stepper's own
        check = self.meter.check
        try:
            ts, ys, t_next, y_next, which = st.advance(t1, events, t_eval, lambda tt, n: check(base + n, tt))
        finally:
            for k, b in zip(("nfev", "njev", "nlu"), before):
                self.stats[k] += getattr(st, k) - b
        if not np.isfinite(ys.sum()):
            return f"non-finite state (near t = {t_next:.6g} s)"
        return ts, ys, t_next, y_next.copy(), which

    def _solve_ivp(self, method, ctl, t, t1, y, events, t_eval):
        """One interval with ``solve_ivp`` (a fresh start), its calls counted against the work limit."""
        fun = self.meter.counted(self.model.rhs, self.stats["nfev"])
        try:
            sol = solve_ivp(
                fun,
                (t, t1),
                y,
                t_eval=t_eval,
                events=[_terminal(ev) for ev in events] or None,
                args=(ctl,),
                **self.options(method),
            )
        except BaseException:
            self.stats["nfev"] = fun.calls[0]  # the work done before the failure (or the work limit)
            raise
        for k in ("nfev", "njev", "nlu"):
            self.stats[k] += int(getattr(sol, k))
        if sol.status < 0 or not all(np.all(np.isfinite(a)) for a in (sol.y, *(sol.y_events or ()))):
            reached = sol.t[-1] if np.size(sol.t) else t
            return f"{sol.message} (near t = {reached:.6g} s)"
        ts = np.asarray(sol.t, float)
        ys = np.asarray(sol.y, float).T if ts.size else np.empty((0, y.size))
        if sol.status != 1:
            return ts, ys, t1, sol.y[:, -1].copy(), None
        t_hit, which = min((te[0], j) for j, te in enumerate(sol.t_events) if len(te))
        y_hit = sol.y_events[which][0]
        keep = ts < t_hit
        return np.append(ts[keep], t_hit), np.vstack([ys[keep], y_hit]), float(t_hit), y_hit.copy(), which
