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
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from ..model.inputs import Controls
from ..dynamics import ChainModel
from ..modes import mode_class
from ..modes.codeload import allow_code as allowed_code
from ..results.result import Result
from .guard import SolverError, check_sane, guarded
from .vode import VodeStepper

__all__ = ["SolverError", "AssembledRun", "assemble", "simulate", "simulate_batch", "batch_key", "BatchMember", "solver_options", "output_grid", "ATOL",
           "atol_per_field",
           "solve_interval"]


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
    opts = {"method": method, "rtol": sim.rtol, "atol": model.layout.per_state(atol_per_field(sim))}
    if sim.max_step_s is not None:
        opts["max_step"] = sim.max_step_s
    if method in ("LSODA", "VODE"):
        opts["lband"], opts["uband"] = model.bandwidths()
        opts["jac"] = model.jacobian_banded
    elif method in ("BDF", "Radau"):
        opts["jac"] = model.jacobian_sparse
    return opts


def atol_per_field(sim) -> dict:
    """Absolute tolerance of each state field: :data:`ATOL` times ``simulation.atol_scale`` and the
    field's factor in ``simulation.atol_scale_fields`` (1 where it has none)."""
    f = sim.atol_scale_fields
    return {k: v * sim.atol_scale * f.get(k, 1.0) for k, v in ATOL.items()}


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
        # B stacked members (opts["vode_stack"]): tolerances / sqrt(B), so that VODE's RMS error norm
        # over the stack <= 1 implies each member's own RMS norm <= 1 (what it has alone)
        k = 1.0 / np.sqrt(model.n_batch)
        st = opts["VODE stepper"] = VodeStepper(model.rhs, model.jacobian_banded, model.n_states, rtol=o["rtol"] * k,
                                                atol=o["atol"] * k, lband=o["lband"], uband=o["uband"],
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
        if method == "VODE" and model.n_batch > 1 and not opts.get("vode_stack"):
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
    (:func:`~snoworm.simulation.guard.work_rate`, counted from ``t``), numpy/scipy warnings captured.

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
        Cache of :func:`solver_options` per method, shared over one run.  Flags: ``"continue"``
        (VODE carries its history on from where the last interval ended), ``"vode_stack"`` (a
        stacked model may run on VODE, with its tolerances divided by sqrt(B) so that each member
        keeps the tolerance it has alone; without it a stack skips VODE for LSODA).

    Returns
    -------
    (ts, ys, t_next, y_next, event_index) : tuple
        Output times and states ``(n_t, n_states)``, where the interval ended, the state there,
        and the index of the event that ended it (None at ``t1``).
    """
    return guarded(lambda m: _solve_interval(m, ctl, t, t1, y, events, sim, t_eval, stats, label, opts),
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


def _guarded_integrate(model, modes, sim, name, progress=None):
    """:func:`_integrate` under :func:`~snoworm.simulation.guard.guarded`, its results checked by
    :func:`~snoworm.simulation.guard.check_sane`."""
    pieces, phases, stats = guarded(lambda m: _integrate(m, modes, sim, name, progress), model, sim, name,
                                    progress=progress)
    check_sane(model, pieces, name)
    return pieces, phases, stats


def simulate(sc, progress=None, allow_code=()) -> Result:
    """Run a scenario and return its :class:`~snoworm.results.result.Result`.

    ``progress``: optional callable ``progress(t_s, duration_s)``, called after each integration
    interval with the simulated time reached, and within long intervals every
    :data:`~snoworm.simulation.guard.PROGRESS_EVERY_S` of wall time (e.g. a
    :class:`snoworm.infra.progress.Progress`).
    ``allow_code``: paths (files or folders) whose controller code may run although they lie
    outside the scenario's folder (a controller in the scenario's folder tree runs without it;
    docs/controllers.md).

    Raises
    ------
    SolverError
        If every solver method fails on an interval (the message includes the solvers'
        messages, the time reached and the interval's label).
    """
    wall0 = time.perf_counter()
    with allowed_code(allow_code):
        case = assemble(sc)
        pieces, phases, stats = _guarded_integrate(case.model, [case.mode], sc.simulation, sc.name, progress)
    stats["wall_time_s"] = time.perf_counter() - wall0
    return Result.from_pieces(sc, case.model, case.mode, pieces[0], phases, stats)


def batch_key(sc):
    """A hashable key shared by the scenarios that can run as one stacked system, or None.

    Members must share the mode's batch signature (:meth:`ModeConfig.batch_signature`: the same
    intervals, no events), the state layout, link types, solver settings, terrain coefficients,
    the X_t profile (or all have constant X_t) and the elevation profile (docs/model.md section 7).
    """
    sig = sc.mode.batch_signature()
    if sig is None:
        return None
    model = sc.chain_model
    sim = sc.simulation
    profile = "constant" if model.profile.is_constant else model.profile
    return (sig, model.n, model.layout.fields, tuple(model.links.prismatic.tolist()), sim.duration_s,
            sim.output_dt_s, sim.rtol, sim.atol_scale, tuple(sorted(sim.atol_scale_fields.items())), sim.method,
            sim.max_step_s, model.tp, profile, model.elevation)


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
