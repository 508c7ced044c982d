"""The simulation driver: assembled case -> ``solve_ivp`` per interval -> :class:`~snoworm.results.result.Result`.

One interval driver serves single runs (:func:`simulate`) and batched stacks
(:func:`simulate_batch`): the integration restarts at every controller start time and every
gait phase change (state events), so no switch of a controller falls inside a solver step
(docs/model.md section 6).  An interval that fails with the configured method is retried with
the implicit methods not yet tried; when every method fails, :class:`SolverError` carries the
solvers' messages.  A failed run never returns a partial result as if it were whole.
"""
from __future__ import annotations

import logging
import time
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from ..model.inputs import Controls
from ..dynamics import ChainModel
from ..modes import mode_class
from ..results.result import Result
from .vode import VodeStepper

__all__ = ["SolverError", "WORK_BASE_NFEV", "WORK_NFEV_PER_S", "work_rate", "SPEED_SANITY_FACTOR", "AssembledRun",
           "assemble", "simulate", "simulate_batch", "batch_key", "BatchMember", "solver_options", "output_grid", "ATOL",
           "solve_interval"]


class SolverError(RuntimeError):
    """The ODE solver failed; the message carries the solver's own message and where it failed."""


#: Solver fallbacks and retries are logged here (INFO).
logger = logging.getLogger("snoworm")

#: Absolute tolerance of each state field, multiplied by ``simulation.atol_scale``.
ATOL = {"x_m": 1e-6, "v_mps": 1e-6, "omega_front": 1e-5, "omega_rear": 1e-5,
        "integral_front_Nm": 1e-4, "integral_rear_Nm": 1e-4, "q_mps": 1e-6, "s_m": 1e-7}

#: Safety bound on consecutive zero-length intervals (a mode whose events re-trigger at once).
MAX_STUCK_INTERVALS = 50


@dataclass
class AssembledRun:
    """A scenario assembled for a run: its chain model and a fresh mode (built once per run)."""

    scenario: object
    model: ChainModel
    mode: object


def assemble(sc) -> AssembledRun:
    """Pair a scenario's chain model (built once per scenario) with a new instance of its mode."""
    model = sc.chain_model
    return AssembledRun(sc, model, mode_class(sc.mode)(sc.mode, sc, model))


def solver_options(model: ChainModel, sim, method=None) -> dict:
    """``solve_ivp`` keyword arguments for the model: method, tolerances, Jacobian structure."""
    method = method or sim.method
    opts = {"method": method, "rtol": sim.rtol, "atol": model.layout.per_state(ATOL) * sim.atol_scale}
    if sim.max_step_s is not None:
        opts["max_step"] = sim.max_step_s
    if method in ("LSODA", "VODE"):
        opts["lband"], opts["uband"] = model.bandwidths()
        opts["jac"] = model.jacobian_banded
    elif method in ("BDF", "Radau"):
        opts["jac"] = model.jacobian_sparse
    return opts


def output_grid(t0, t1, dt, include_start):
    """Output times of an interval: the multiples of ``dt`` inside it, its end, and its start if asked."""
    k0 = int(np.floor(t0 / dt + 1e-9)) + 1
    k1 = int(np.ceil(t1 / dt - 1e-9)) - 1
    g = np.arange(k0, k1 + 1) * dt
    pts = [t0] if include_start else []
    return np.array(pts + list(g[(g > t0) & (g < t1)]) + [t1])


def _fallbacks(method):
    """The configured method first, then the implicit methods not yet tried (VODE: LSODA first)."""
    first = [method, "LSODA"] if method == "VODE" else [method]
    return first + [m for m in ("BDF", "Radau") if m != method]


def _vode_interval(model, ctl, t, t1, y, events, t_eval, opts):
    """One interval on the run's :class:`~snoworm.simulation.vode.VodeStepper` (kept in ``opts``), restarted at ``t``.

    With ``opts["continue"]`` true (a caller that steps a run period by period, such as
    :class:`~snoworm.simulation.stepwise.Simulator`), the stepper is not restarted where the previous
    interval ended at its end time exactly at ``(t, y)``: its history carries on across the change
    of controls (the stepper restarts by itself if VODE then fails).

    Returns ``(ts, ys, t_next, y_next, which, counts)`` like :func:`_solve_interval`, plus the
    solver work of this interval.
    """
    st = opts.get("VODE stepper")
    if st is None:
        o = opts["VODE"]
        st = opts["VODE stepper"] = VodeStepper(model.rhs, model.jacobian_banded, model.n_states, rtol=o["rtol"],
                                                atol=o["atol"], lband=o["lband"], uband=o["uband"],
                                                max_step=o.get("max_step"))
    before = (st.nfev, st.njev, st.nlu)
    events = [_with_controls(ev, ctl) for ev in events or ()]
    st.ctl = ctl
    if not (opts.get("continue") and st.t == t and np.array_equal(st.y, y)):
        st.restart(t, y)            # else: carry the history across the change of controls
    try:
        ts, ys, t_next, y_next, which = st.advance(t1, events, t_eval)
    finally:
        counts = {"nfev": st.nfev - before[0], "njev": st.njev - before[1], "nlu": st.nlu - before[2]}
    return ts, ys, t_next, y_next, which, counts


def _terminal(ev):
    """A mode's event ``ev(t, y)`` as a terminal solve_ivp event (which also receives ``args``)."""
    def f(t, y, _ctl):
        return ev(t, y)
    f.terminal = True
    f.direction = getattr(ev, "direction", 0)
    f.mode_event = ev
    return f


def _with_controls(ev, ctl):
    """A solve_ivp event ``ev(t, y, ctl)`` as ``ev(t, y)`` with the same direction (for the stepper);
    the mode's own event where ``ev`` wraps one (:func:`_terminal`)."""
    if hasattr(ev, "mode_event"):
        return ev.mode_event
    def f(t, y):
        return ev(t, y, ctl)
    f.direction = getattr(ev, "direction", 0)
    return f


def _solve_interval(model, ctl, t, t1, y, events, sim, t_eval, stats, label, opts):
    """Integrate one interval with method fallbacks; ``(ts, ys, t_next, y_next, event_index)``.

    ``opts`` caches :func:`solver_options` per method for the run (built when first needed).
    """
    sol, failures = None, []
    for method in _fallbacks(sim.method):
        if method == "VODE" and model.n_batch > 1:
            continue                # stacked members: LSODA's max-norm error test (see simulate_batch)
        if method not in opts:
            opts[method] = solver_options(model, sim, method)
        if method == "VODE":
            try:
                ts, ys, t_next, y_next, which, counts = _vode_interval(model, ctl, t, t1, y, events, t_eval, opts)
            except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
                failures.append(f"VODE: {exc}")
                continue
            for k in ("nfev", "njev", "nlu"):
                stats[k] += counts[k]
            if np.all(np.isfinite(ys)):
                _count_interval(stats, failures)
                return ts, ys, t_next, y_next.copy(), which
            failures.append(f"VODE: non-finite state (near t = {t_next:.6g} s)")
            continue
        try:
            sol = solve_ivp(model.rhs, (t, t1), y, t_eval=t_eval, events=events or None, args=(ctl,),
                            **opts[method])
        except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
            failures.append(f"{method}: {exc}")
            sol = None
            continue
        for k in ("nfev", "njev", "nlu"):
            stats[k] += int(getattr(sol, k))
        if sol.status >= 0 and all(np.all(np.isfinite(a)) for a in (sol.y, *(sol.y_events or ()))):
            break
        reached = sol.t[-1] if np.size(sol.t) else t
        failures.append(f"{method}: {sol.message} (near t = {reached:.6g} s)")
        sol = None
    if failures:
        logger.info("interval '%s' from t = %.6g s: %s%s", label, t, "; ".join(failures),
                    "" if sol is None else f"; retried with {method}, which succeeded")
    if sol is None:
        raise SolverError(f"every method failed at t = {t:.6g} s in interval '{label}': "
                          + "; ".join(failures) + ". Try a smaller simulation.rtol or max_step_s.")
    _count_interval(stats, failures)
    ts = np.asarray(sol.t, float)
    ys = np.asarray(sol.y, float).T if ts.size else np.empty((0, y.size))
    if sol.status != 1:
        return ts, ys, t1, sol.y[:, -1].copy(), None
    t_hit, which = min((te[0], j) for j, te in enumerate(sol.t_events) if len(te))
    y_hit = sol.y_events[which][0]
    keep = ts < t_hit
    return np.append(ts[keep], t_hit), np.vstack([ys[keep], y_hit]), float(t_hit), y_hit.copy(), which


def _count_interval(stats, failures):
    if failures:                    # the interval succeeded after this many failed methods
        stats["retries"] = stats.get("retries", 0) + len(failures)
    stats["intervals"] += 1


def solve_interval(model, ctl, t, t1, y, events, sim, t_eval, stats, label, opts):
    """Integrate ``model`` under controls ``ctl`` from ``(t, y)`` to ``t1`` (or a terminal event).

    The one solver step of every run (:func:`simulate`, batched stacks and
    :class:`snoworm.simulation.stepwise.Simulator`): ``solve_ivp`` with the scenario's method, tolerances and
    Jacobian, retried with the implicit methods before :class:`SolverError`; under the work limit
    (:func:`work_rate`, counted from ``t``), numpy/scipy warnings captured.

    Parameters
    ----------
    model, ctl : ChainModel, Controls
    t, t1 : float
        Start and end of the interval [s].
    y : ndarray
        Flat state at ``t``.
    events : list of callable
        Terminal events ``f(t, y, ctl)`` (empty: none).
    sim : SimulationConfig
        Solver settings.
    t_eval : ndarray
        Output times (:func:`output_grid`).
    stats : dict
        Solver counters (``nfev``, ``njev``, ``nlu``, ``intervals``), updated in place.
    label : str
        The interval's name for error messages.
    opts : dict
        Cache of :func:`solver_options` per method, shared over one run.

    Returns
    -------
    (ts, ys, t_next, y_next, event_index) : tuple
        Output times and states ``(n_t, n_states)``, where the interval ended, the state there,
        and the index of the event that ended it (None at ``t1``).
    """
    return _guarded(lambda m: _solve_interval(m, ctl, t, t1, y, events, sim, t_eval, stats, label, opts),
                    model, sim, label, t)


def _integrate(model, modes, sim, name, progress=None):
    """THE interval loop: ``modes`` (one per member) drive ``model`` (stacked if several members).

    ``progress(t_s, duration_s)`` is called after each interval, if given.

    Returns ``(pieces per member, phases, stats)``.  Raises :class:`SolverError`, or ValueError
    when the members of a stack ask for different intervals (they then run one by one).
    """
    B = len(modes)
    t, T = 0.0, sim.duration_s
    y = np.concatenate([md.initial_state() for md in modes])
    pieces, phases = [[] for _ in range(B)], []
    stats = {"nfev": 0, "njev": 0, "nlu": 0, "intervals": 0}
    stuck, opts = 0, {"continue": all(getattr(md, "continue_solver", False) for md in modes)}
    while t < T - 1e-12:
        ys_b = y.reshape(B, -1)
        ivs = [md.interval(t, ys_b[b]) for b, md in enumerate(modes)]
        iv = ivs[0]
        t1 = float(min(iv.t_end, T))
        if B > 1 and (any(v.events for v in ivs) or any(float(min(v.t_end, T)) != t1 for v in ivs)):
            raise ValueError("the members of a batch ask for different intervals")
        if t1 <= t:
            raise SolverError(f"mode of {name!r} asked for an empty interval at t = {t:.6g} s ({iv.label}).")
        ctl = iv.controls if B == 1 else Controls.stack([v.controls for v in ivs])
        t_eval = output_grid(t, t1, sim.output_dt_s, include_start=not phases)
        ts, ys, t_next, y_next, which = _solve_interval(
            model, ctl, t, t1, y, [_terminal(ev) for ev in iv.events], sim, t_eval, stats, iv.label, opts)
        if ts.size:
            ys_m = ys.reshape(ts.size, B, -1)
            for b in range(B):
                pieces[b].append((ts, ys_m[:, b, :], ivs[b].controls))
        phases.append({"t_start_s": t, "t_end_s": t_next, "label": iv.label})
        stuck = stuck + 1 if t_next - t < 1e-9 else 0
        if stuck > MAX_STUCK_INTERVALS:
            raise SolverError(f"mode of {name!r} keeps ending intervals at t = {t:.6g} s without progress "
                              f"({iv.label}); its phase-change events re-trigger immediately.")
        t, y = t_next, y_next
        if which is not None:
            modes[0].on_event(t, y, which)
        if progress is not None:
            progress(t, T)
    return pieces, phases, stats


# ---------------------------------------------------------------- work limit and sanity (issue 15)
# Kept apart from the interval driver: a counting proxy of the model handed to it, and checks of
# its output.  Neither changes a number of a run that stays within the limits.

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


class _Metered:
    """The model as the solver sees it: ``rhs`` counts its calls against the work limit
    (:data:`WORK_BASE_NFEV` + :data:`WORK_NFEV_PER_S` per simulated second reached) and checks
    ``simulation.max_wall_s``; every other attribute is the model's own."""

    def __init__(self, model, sim, name, t0=0.0):
        self._model, self._sim, self._name, self._t0 = model, sim, name, float(t0)
        self._n, self._t_max, self._wall0 = 0, float(t0), time.perf_counter()
        self._rate = work_rate(sim)

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
        return self._model.rhs(t, y, *args)


def _check_sane(model, pieces, name):
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


def _guarded(fn, model, sim, name, t0=0.0):
    """``fn(metered model)`` under the work limit from ``t0``, with numpy/scipy warnings kept quiet
    and the solver's own breakdowns (singular matrices, ...) as :class:`SolverError`."""
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return fn(_Metered(model, sim, name, t0))
        except (RuntimeError, ArithmeticError, np.linalg.LinAlgError) as exc:
            if type(exc) not in (RuntimeError, ArithmeticError, ZeroDivisionError, OverflowError,
                                 np.linalg.LinAlgError):
                raise           # SolverError, a mode's own error (e.g. ControllerError): as they are
            raise SolverError(f"the solver broke down in {name!r} ({type(exc).__name__}: {str(exc)[:200]}). "
                              "The scenario is too stiff or has extreme values; check its gains, stiffnesses "
                              "and forces, or try a smaller simulation.rtol.") from None


def _guarded_integrate(model, modes, sim, name, progress=None):
    """:func:`_integrate` under :func:`_guarded`, its results checked by :func:`_check_sane`."""
    pieces, phases, stats = _guarded(lambda m: _integrate(m, modes, sim, name, progress), model, sim, name)
    _check_sane(model, pieces, name)
    return pieces, phases, stats


def simulate(sc, progress=None) -> Result:
    """Run a scenario and return its :class:`~snoworm.results.result.Result`.

    ``progress``: optional callable ``progress(t_s, duration_s)``, called after each integration
    interval with the simulated time reached (e.g. a :class:`snoworm.infra.progress.Progress`).

    Raises
    ------
    SolverError
        If every solver method fails on an interval (the message includes the solvers'
        messages, the time reached and the interval's label).
    """
    wall0 = time.perf_counter()
    case = assemble(sc)
    pieces, phases, stats = _guarded_integrate(case.model, [case.mode], sc.simulation, sc.name, progress)
    stats["wall_time_s"] = time.perf_counter() - wall0
    return Result.from_pieces(sc, case.model, case.mode, pieces[0], phases, stats)


def batch_key(sc):
    """A hashable key shared by the scenarios that can run as one stacked system, or None.

    Members must share the mode's batch signature (:meth:`ModeConfig.batch_signature`: the same
    intervals, no events), the state layout, link types, solver settings, terrain coefficients
    and the X_t profile (or all have constant X_t).
    """
    sig = sc.mode.batch_signature()
    if sig is None:
        return None
    model = sc.chain_model
    sim = sc.simulation
    profile = "constant" if model.profile.is_constant else model.profile
    return (sig, model.n, model.layout.fields, tuple(model.links.prismatic.tolist()), sim.duration_s,
            sim.output_dt_s, sim.rtol, sim.atol_scale, sim.method, sim.max_step_s, model.tp, profile)


@dataclass
class BatchMember:
    """Outcome of one member of a batched run: ``status`` ``"ok"`` with its ``result``, or
    ``"solver_failure"`` with the solver's message in ``error``."""

    scenario: object
    result: Result | None
    status: str
    error: str = ""


def simulate_batch(scenarios) -> list:
    """Run scenarios of one :func:`batch_key` as ONE stacked system through the same interval driver.

    The members' models are stacked (:meth:`ChainModel.stack`: the same kernel with one more
    leading axis on the parameters) and integrated together; LSODA's error test is a weighted
    max-norm, so every member is held to the tolerance it has alone.  If the stacked solve fails,
    each member runs alone, so one bad member does not fail the others.

    Returns
    -------
    list of BatchMember
        One per scenario, in order.

    Raises
    ------
    ValueError
        If the scenarios do not share a batch key.
    """
    wall0 = time.perf_counter()
    scs = list(scenarios)
    keys = {batch_key(sc) for sc in scs}
    if None in keys or len(keys) != 1:
        raise ValueError("simulate_batch needs scenarios with one batch key (see snoworm.simulation.driver.batch_key)")
    cases = [assemble(sc) for sc in scs]
    try:
        big = ChainModel.stack([c.model for c in cases]) if len(cases) > 1 else cases[0].model
        pieces, phases, stats = _guarded_integrate(big, [c.mode for c in cases], scs[0].simulation, scs[0].name)
    except (SolverError, ValueError) as exc:
        logger.info("stacked run of %d scenarios failed (%s); running them one by one", len(scs), exc)
        return [_alone(sc) for sc in scs]
    wall = (time.perf_counter() - wall0) / len(scs)
    return [BatchMember(c.scenario, Result.from_pieces(c.scenario, c.model, c.mode, pieces[b], [dict(p) for p in phases],
                                                       dict(stats, batch_size=len(scs), wall_time_s=wall)), "ok")
            for b, c in enumerate(cases)]


def _alone(sc) -> BatchMember:
    try:
        return BatchMember(sc, simulate(sc), "ok")
    except SolverError as exc:
        return BatchMember(sc, None, "solver_failure", str(exc))
