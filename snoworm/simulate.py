"""Simulation driver: scenario -> assembled model -> ``solve_ivp`` per interval -> :class:`Result`.

The integration restarts at every controller start time and every gait phase change (state
events), so no switch of a controller falls inside a solver step (MODEL.md section 6).
A failed solve raises :class:`SolverError` with the solver's message; it never returns
a partial result as if it were whole.
"""
from __future__ import annotations

import time

import numpy as np
from scipy.integrate import solve_ivp

from . import modes
from .dynamics import ChainModel, LinkArrays, SegmentArrays
from .results import Result
from .scenario import Scenario
from .terrain import TerrainParams, TerrainProfile, patch_profile, random_profile

__all__ = ["SolverError", "build_model", "simulate", "solver_options", "terrain_profile"]


class SolverError(RuntimeError):
    """The ODE solver failed; the message carries the solver's own message and where it failed."""


#: Absolute tolerance of each state field, multiplied by ``simulation.atol_scale``.
ATOL = {"x_m": 1e-6, "v_mps": 1e-6, "omega_front": 1e-5, "omega_rear": 1e-5,
        "integral_front_Nm": 1e-4, "integral_rear_Nm": 1e-4, "q_mps": 1e-6, "s_m": 1e-7}

#: Safety bound on consecutive zero-length intervals (a mode whose events re-trigger at once).
MAX_STUCK_INTERVALS = 50


def terrain_profile(sc: Scenario) -> TerrainProfile:
    """Compile the scenario's terrain (``xt``, ``xt`` + ``patches``, ``profile`` or ``random``) to one table.

    Every form becomes a :class:`~snoworm.terrain.TerrainProfile`, the single evaluation path of
    X_t along the track (paper section 3: X_t is "location dependent").
    """
    t = sc.terrain
    if t.profile is not None:
        return TerrainProfile(tuple(p[0] for p in t.profile), tuple(p[1] for p in t.profile))
    if t.random is not None:
        r = t.random
        return random_profile(r.mean, r.std, r.correlation_length_m, r.seed, r.length_m, r.min_xt, r.start_m)
    if t.patches:
        return patch_profile(t.xt, [(p.start_m, p.end_m, p.xt, p.ramp_m) for p in t.patches])
    return TerrainProfile.constant(t.xt)


def build_model(sc: Scenario) -> ChainModel:
    """Assemble the :class:`~snoworm.dynamics.ChainModel` of a scenario (arrays built once)."""
    veh = sc.vehicle
    seg = SegmentArrays.from_list(veh.segment_params())
    n_links = max(veh.segments - 1, 0)
    lc = veh.links
    ones = np.ones(n_links)
    links = LinkArrays(
        stiffness_N_per_m=lc.stiffness_N_per_m * ones, damping_Ns_per_m=lc.damping_Ns_per_m * ones,
        rest_spacing_m=lc.rest_spacing_m * ones,
        prismatic=np.array([1.0 if t == "prismatic" else 0.0 for t in veh.link_types()]),
        stroke_min_m=lc.stroke_min_m * ones, stroke_max_m=lc.stroke_max_m * ones,
        force_max_N=lc.force_max_N * ones, rate_max_mps=lc.rate_max_mps * ones,
        force_gain_per_s=lc.force_gain_per_s * ones)
    m = sc.terrain.model
    tp = TerrainParams(b_tF=m.b_tF, b_trF=m.b_trF, A=m.A, peak_exponent_d=m.peak_exponent_d, tau0=m.tau0,
                       tau1=m.tau1, slip_eps_mps=m.slip_eps_mps, sign_eps_mps=m.sign_eps_mps,
                       torque_balance=m.torque_balance)
    force_loop = modes.mode_class(sc.mode).force_loop
    return ChainModel(seg, links, tp, terrain_profile(sc), sc.tow.force_N, force_loop=force_loop)


def _fallbacks(method):
    """The configured method first, then the implicit methods not yet tried (an interval that
    fails, e.g. in LSODA's event location, is retried before a failure is reported)."""
    return [method] + [m for m in ("BDF", "Radau") if m != method]


def solver_options(model: ChainModel, sim, method=None) -> dict:
    """``solve_ivp`` keyword arguments for the model: method, tolerances, Jacobian structure."""
    method = method or sim.method
    atol = np.tile([ATOL[f] for f in model.fields], model.n_states // model.n_s) * sim.atol_scale
    opts = {"method": method, "rtol": sim.rtol, "atol": atol}
    if sim.max_step_s is not None:
        opts["max_step"] = sim.max_step_s
    if method == "LSODA":
        lband, uband = model.bandwidths()
        opts["lband"], opts["uband"] = lband, uband
        opts["jac"] = model.jacobian_banded
    elif method in ("BDF", "Radau"):
        opts["jac"] = model.jacobian_sparse
    return opts


def _grid(t0, t1, dt, include_start):
    k0 = int(np.floor(t0 / dt + 1e-9)) + 1
    k1 = int(np.ceil(t1 / dt - 1e-9)) - 1
    g = np.arange(k0, k1 + 1) * dt
    pts = [t0] if include_start else []
    return np.array(pts + list(g[(g > t0) & (g < t1)]) + [t1])


def simulate(sc: Scenario) -> Result:
    """Run a scenario and return its :class:`~snoworm.results.Result`.

    Raises
    ------
    SolverError
        If ``solve_ivp`` fails (the message includes the solver's message, the time reached
        and the interval's label).
    """
    wall0 = time.perf_counter()
    model = build_model(sc)
    mode = modes.mode_class(sc.mode)(sc.mode, sc, model)
    sim = sc.simulation
    opts = solver_options(model, sim)
    t, y = 0.0, mode.initial_state()
    T = sim.duration_s
    pieces, phases = [], []
    stats = {"nfev": 0, "njev": 0, "nlu": 0, "intervals": 0}
    stuck = 0
    while t < T - 1e-12:
        iv = mode.interval(t, y)
        t1 = float(min(iv.t_end, T))
        if t1 <= t:
            raise SolverError(f"mode {sc.mode.type!r} asked for an empty interval at t = {t:.6g} s ({iv.label}).")
        t_eval = _grid(t, t1, sim.output_dt_s, include_start=not pieces)
        events = [_wrap_event(ev) for ev in iv.events]
        sol, failures = None, []
        for method in _fallbacks(sim.method):
            o = opts if method == sim.method else solver_options(model, sim, method)
            try:
                sol = solve_ivp(model.rhs, (t, t1), y, t_eval=t_eval, events=events or None,
                                args=(iv.controls,), **o)
            except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
                failures.append(f"{method}: {exc}")
                sol = None
                continue
            stats["nfev"] += int(sol.nfev)
            stats["njev"] += int(sol.njev)
            stats["nlu"] += int(sol.nlu)
            if sol.status >= 0 and all(np.all(np.isfinite(a)) for a in (sol.y, *(sol.y_events or ()))):
                break
            reached = sol.t[-1] if np.size(sol.t) else t
            failures.append(f"{method}: {sol.message} (near t = {reached:.6g} s)")
            sol = None
        if sol is None:
            raise SolverError(f"every method failed at t = {t:.6g} s in interval '{iv.label}': "
                              + "; ".join(failures) + ". Try a smaller simulation.rtol or max_step_s.")
        if failures:                    # the interval succeeded after this many failed methods
            stats["retries"] = stats.get("retries", 0) + len(failures)
        stats["intervals"] += 1
        ts = np.asarray(sol.t, float)
        ys = np.asarray(sol.y, float).T if ts.size else np.empty((0, y.size))
        if sol.status == 1:
            hits = [(te[0], j) for j, te in enumerate(sol.t_events) if len(te)]
            t_hit, which = min(hits)
            y_hit = sol.y_events[which][0]
            keep = ts < t_hit
            ts = np.append(ts[keep], t_hit)
            ys = np.vstack([ys[keep], y_hit])
            t_next, y_next = float(t_hit), y_hit.copy()
        else:
            t_next, y_next, which = t1, sol.y[:, -1].copy(), None
        if ts.size:
            pieces.append((ts, ys, iv.controls))
        phases.append({"t_start_s": t, "t_end_s": t_next, "label": iv.label})
        stuck = stuck + 1 if t_next - t < 1e-9 else 0
        if stuck > MAX_STUCK_INTERVALS:
            raise SolverError(f"mode {sc.mode.type!r} keeps ending intervals at t = {t:.6g} s without progress "
                              f"({iv.label}); its phase-change events re-trigger immediately.")
        t, y = t_next, y_next
        if which is not None:
            mode.on_event(t, y, which)
    stats["wall_time_s"] = time.perf_counter() - wall0
    return Result.from_pieces(sc, model, mode, pieces, phases, stats)


def _wrap_event(ev):
    """A mode's event ``ev(t, y)`` as a terminal solve_ivp event (which also receives ``args``)."""
    def f(t, y, _ctl):
        return ev(t, y)
    f.terminal = True
    f.direction = getattr(ev, "direction", 0)
    return f
