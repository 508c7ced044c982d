"""The simulation driver: assembled case -> one interval solve per mode interval -> :class:`~snoworm.results.result.Result`.

One interval loop serves single runs (:func:`simulate`) and batched stacks
(:func:`simulate_batch`): the integration restarts at every controller start time and every
gait phase change (state events), so no switch of a controller falls inside a solver step
(docs/model.md section 6).  Each interval of a single run is solved by the run's
:class:`~snoworm.simulation.interval.IntervalSolver` (method fallbacks, work limit, VODE stepper);
a batch's by the one stepper of many chains, :class:`~snoworm.simulation.stepper.ChainStepper`
(which stacks the members; the driver knows no stacking).  A failed run never returns a partial
result as if it were whole.
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..config.scenario import Scenario
from ..config.schema import quote
from ..dynamics import ChainModel
from ..model.arrays import LinkArrays, SegmentArrays
from ..model.inputs import Controls
from ..modes.base import Mode, build_mode
from ..results.result import Result
from .guard import SolverError, check_sane, guarded
from .interval import IntervalSolver, output_grid
from .stepper import WHOLE_RUNS, ChainStepper

if TYPE_CHECKING:
    from ..config.sections import SimulationConfig
    from .guard import Piece

__all__ = [
    "SolverError",
    "AssembledRun",
    "chain_model",
    "assemble",
    "check_assembly",
    "simulate",
    "simulate_batch",
    "batch_key",
    "BatchMember",
]


#: Stacked runs that fall back to one by one are logged here (INFO).
logger = logging.getLogger("snoworm")

#: Safety bound on consecutive zero-length intervals (a mode whose events re-trigger at once).
MAX_STUCK_INTERVALS = 50


@dataclass
class AssembledRun:
    """A scenario assembled for one run: its chain model and a fresh mode (built once per run).

    The mode holds what it prepared on the model (e.g. the force-control plan,
    :meth:`~snoworm.config.mode_registry.ModeConfig.prepare`)."""

    scenario: Scenario
    model: ChainModel
    mode: Mode


def _check_scenario(sc: object) -> None:
    if not isinstance(sc, Scenario):
        raise TypeError(
            f"scenario: expected a Scenario, got {quote(sc, 60)}; read one with snoworm.load_scenario(name or path)"
        )


def chain_model(sc: Scenario) -> ChainModel:
    """A new :class:`~snoworm.dynamics.ChainModel` of a scenario's chain, built from its data.

    The one place a scenario's values become the kernel's arrays (per-segment parameters with
    the overrides applied, per-link parameters, the terrain's coefficients, X_t and elevation
    along the track); a scenario holds no model (it is data), so build it once per run and
    pass it on (:func:`assemble` does).

    Raises TypeError naming ``scenario`` if ``sc`` is not a :class:`~snoworm.config.scenario.Scenario`."""
    _check_scenario(sc)
    veh, terrain = sc.vehicle, sc.terrain
    n_links = max(veh.segments - 1, 0)
    ones = np.ones(n_links)
    lc = veh.links
    link_kw = {k: getattr(lc, k) * ones for k in LinkArrays.__dataclass_fields__ if k != "prismatic"}
    prismatic = np.array([1.0 if t == "prismatic" else 0.0 for t in veh.link_types()])
    return ChainModel(
        SegmentArrays.from_list(veh.segment_params()),
        LinkArrays(prismatic=prismatic, **link_kw),
        terrain.model.params(),
        terrain.compile(),
        sc.tow.force_N,
        force_loop=sc.mode.force_loop,
        elevation=terrain.elevation_profile(),
        sled_mass_kg=sc.tow.mass_kg,
        sled_friction=sc.tow.sled_friction,
    )


def assemble(
    sc: Scenario, model: ChainModel | None = None, allow_code: Iterable[str | os.PathLike[str]] = ()
) -> AssembledRun:
    """Assemble a scenario for one run: its chain model (:func:`chain_model`, or ``model`` if the
    caller built it for this run already) and a new instance of its mode on that model (which
    prepares its plan on it, e.g. the force-control targets; :func:`snoworm.modes.base.build_mode`,
    which hands ``allow_code`` to a mode that runs the user's code).

    Raises
    ------
    ScenarioError
        If the scenario cannot run on its chain (e.g. a force-control target the chain cannot
        carry): checks that need the model are made here, not when the scenario is validated.
    TypeError
        Naming ``scenario`` if ``sc`` is not a :class:`~snoworm.config.scenario.Scenario`.
    """
    if model is None:
        model = chain_model(sc)
    else:
        _check_scenario(sc)
    return AssembledRun(sc, model, build_mode(sc.mode, sc, model, allow_code))


def check_assembly(sc: Scenario) -> None:
    """The checks of :func:`assemble` without making the mode: build the chain model and the mode
    config's plan on it (:meth:`~snoworm.config.mode_registry.ModeConfig.prepare`); no user code
    runs.  ``snoworm validate`` calls it.

    Raises
    ------
    ScenarioError
        As :func:`assemble` (e.g. a force-control target the chain cannot carry).
    """
    model = chain_model(sc)
    sc.mode.prepare(sc, model)


def _interval_solve(
    models: Sequence[ChainModel],
    modes: Sequence[Mode],
    sim: SimulationConfig,
    name: str,
    progress: Callable[[float, float], object] | None,
) -> tuple[Callable[..., tuple[Any, ...]], dict[str, Any]]:
    """``(solve, stats)``: the interval solve of a run's members, ``solve(ctl, t, t1, y, events,
    t_eval, label) -> (ts, ys, t_next, y_next, event_index)`` as
    :meth:`IntervalSolver.solve <snoworm.simulation.interval.IntervalSolver.solve>`.

    One member: its :class:`~snoworm.simulation.interval.IntervalSolver` (a mode's events end its
    intervals).  Several (a batch, whose modes have no events): the one stepper of many chains,
    :class:`~snoworm.simulation.stepper.ChainStepper` under its batched sweeps' policy
    (:data:`~snoworm.simulation.stepper.WHOLE_RUNS`: one stack of the members, the scenario's
    method, a failed stack raises :class:`SolverError`)."""
    options: dict[str, Any] = {
        "carry_history": all(getattr(md, "continue_solver", False) for md in modes),
        "progress": progress,
        "asked_steps": all(getattr(md, "steps_asked", False) for md in modes),
    }
    if len(models) == 1:
        solver = IntervalSolver(models[0], sim, name, **options)
        return solver.solve, solver.stats
    stepper = ChainStepper.of_members(models, sim, name, policy=WHOLE_RUNS, **options)

    def solve(
        ctl: Controls, t: float, t1: float, y: np.ndarray, events: object, t_eval: np.ndarray, label: str
    ) -> tuple[Any, ...]:
        ys, y_end, _, _ = stepper.solve(ctl, t, t1, y, t_eval, label)
        return np.asarray(t_eval, float), ys.reshape(len(t_eval), -1), t1, y_end.reshape(-1), None

    return solve, stepper.stats


def _integrate(
    models: Sequence[ChainModel],
    modes: Sequence[Mode],
    sim: SimulationConfig,
    name: str,
    progress: Callable[[float, float], object] | None = None,
) -> tuple[list[list[Piece]], list[dict[str, Any]], dict[str, Any]]:
    """THE interval loop: ``modes`` drive the chains ``models`` (one per member; several: a batch,
    stacked by :func:`_interval_solve`).

    ``progress(t_s, duration_s)`` is called after each interval, if given, and within long
    intervals by the solver's work meter (:class:`~snoworm.simulation.guard.WorkMeter`).

    Returns ``(pieces per member, phases, stats)``.  Raises :class:`SolverError`, or ValueError
    when the members of a batch ask for different intervals (they then run one by one).
    """
    B = len(modes)
    t, T = 0.0, sim.duration_s
    y = np.concatenate([md.initial_state() for md in modes])
    pieces: list[list[Piece]] = [[] for _ in range(B)]
    phases: list[dict[str, Any]] = []
    solve, stats = _interval_solve(models, modes, sim, name, progress)
    stuck = 0
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
        ts, ys, t_next, y_next, which = solve(ctl, t, t1, y, iv.events, t_eval, iv.label)
        if ts.size:
            ys_m = ys.reshape(ts.size, B, -1)
            for b in range(B):
                pieces[b].append((ts, ys_m[:, b, :], ivs[b].controls))
        phases.append({"t_start_s": t, "t_end_s": t_next, "label": iv.label})
        stuck = stuck + 1 if t_next - t < 1e-9 else 0
        if stuck > MAX_STUCK_INTERVALS:
            raise SolverError(
                f"mode of {name!r} keeps ending intervals at t = {t:.6g} s without progress "
                f"({iv.label}); its phase-change events re-trigger immediately."
            )
        t, y = t_next, y_next
        if which is not None:
            modes[0].on_event(t, y, which)
        if progress is not None:
            progress(t, T)
    return pieces, phases, stats


def _guarded_integrate(
    models: Sequence[ChainModel],
    modes: Sequence[Mode],
    sim: SimulationConfig,
    name: str,
    progress: Callable[[float, float], object] | None = None,
) -> tuple[list[list[Piece]], list[dict[str, Any]], dict[str, Any]]:
    """:func:`_integrate` under :func:`~snoworm.simulation.guard.guarded`, each member's results
    checked by :func:`~snoworm.simulation.guard.check_sane` against its own chain."""
    pieces, phases, stats = guarded(lambda: _integrate(models, modes, sim, name, progress), name)
    for model, piece in zip(models, pieces):
        check_sane(model, [piece], name)
    return pieces, phases, stats


def simulate(
    sc: Scenario,
    progress: Callable[[float, float], object] | None = None,
    allow_code: Iterable[str | os.PathLike[str]] = (),
) -> Result:
    """Run a scenario and return its :class:`~snoworm.results.result.Result`.

    ``progress``: optional callable ``progress(t_s, duration_s)``, called after each integration
    interval with the simulated time reached, and within long intervals every
    :data:`~snoworm.simulation.guard.PROGRESS_EVERY_S` of wall time (e.g. a
    :class:`snoworm.infra.progress.Progress`).
    ``allow_code``: paths (files or folders) whose controller code may run although they lie
    outside the scenario's folder (a controller in the scenario's folder tree runs without it;
    docs/controllers.md); handed to the controller mode, which loads the code (and restores the
    working directory a controller changed: the caller's relative paths stay theirs).

    Raises
    ------
    SolverError
        If every solver method fails on an interval (the message includes the solvers'
        messages, the time reached and the interval's label).
    """
    wall0 = time.perf_counter()
    case = assemble(sc, allow_code=allow_code)
    pieces, phases, stats = _guarded_integrate([case.model], [case.mode], sc.simulation, sc.name, progress)
    stats["wall_time_s"] = time.perf_counter() - wall0
    return Result.from_pieces(sc, case.model, case.mode, pieces[0], phases, stats)


def _assembled(run: Scenario | AssembledRun) -> AssembledRun:
    """``run`` if it is an :class:`AssembledRun`, else the scenario assembled (:func:`assemble`)."""
    return run if isinstance(run, AssembledRun) else assemble(run)


def batch_key(run: Scenario | AssembledRun) -> tuple[Any, ...] | None:
    """A hashable key shared by the runs that can run as one stacked system, or None.

    ``run``: a Scenario (its chain model is built here if its mode can run in a stack) or an
    :class:`AssembledRun` (its model is used: assemble a run once, then key and stack it).
    Members must share the mode's batch signature (:meth:`ModeConfig.batch_signature`: the same
    intervals, no events), the state layout, link types, solver settings, terrain coefficients,
    the X_t profile (or all have constant X_t) and the elevation profile (docs/model.md section 7).
    """
    sc = run.scenario if isinstance(run, AssembledRun) else run
    _check_scenario(sc)
    sig = sc.mode.batch_signature()
    if sig is None:
        return None
    model = run.model if isinstance(run, AssembledRun) else chain_model(sc)
    sim = sc.simulation
    profile = "constant" if model.profile.is_constant else model.profile
    return (
        sig,
        model.n,
        model.layout.fields,
        tuple(model.links.prismatic.tolist()),
        sim.duration_s,
        sim.output_dt_s,
        sim.rtol,
        sim.atol_scale,
        tuple(sorted(sim.atol_scale_fields.items())),
        sim.method,
        sim.max_step_s,
        model.tp,
        profile,
        model.elevation,
    )


@dataclass
class BatchMember:
    """Outcome of one member of a batched run: ``status`` ``"ok"`` with its ``result``, or
    ``"solver_failure"`` with the solver's message in ``error``."""

    scenario: Scenario
    result: Result | None
    status: str
    error: str = ""


def simulate_batch(scenarios: Iterable[Scenario | AssembledRun]) -> list[BatchMember]:
    """Run scenarios of one :func:`batch_key` as ONE stacked system through the same interval driver.

    ``scenarios``: Scenarios, or runs assembled already (:class:`AssembledRun`, e.g. to compute
    their :func:`batch_key` first); each is assembled once.

    The members are integrated together by the one stepper of many chains
    (:class:`~snoworm.simulation.stepper.ChainStepper` under its
    :data:`~snoworm.simulation.stepper.WHOLE_RUNS` policy: their models stacked with
    :meth:`ChainModel.stack`, the same kernel with one more leading axis on the parameters, in one
    stack on LSODA, whose error test is a weighted max-norm, so every member is held to the
    tolerance it has alone).  If the stacked solve fails, or a member's states leave the physics
    (:func:`~snoworm.simulation.guard.check_sane`, against its own chain), each member runs alone
    from the start, so one bad member does not fail the others.

    Returns
    -------
    list of BatchMember
        One per scenario, in order.

    Raises
    ------
    ValueError
        If the scenarios do not share a batch key.
    ScenarioError
        If a scenario cannot run on its chain (:func:`assemble`).
    """
    wall0 = time.perf_counter()
    one_key = "simulate_batch needs scenarios with one batch key (see snoworm.simulation.driver.batch_key)"
    runs = list(scenarios)
    for run in runs:  # before assembling: a mode that cannot run in a stack is not made
        sc = run.scenario if isinstance(run, AssembledRun) else run
        _check_scenario(sc)
        if sc.mode.batch_signature() is None:
            raise ValueError(one_key)
    cases = [_assembled(run) for run in runs]
    scs = [c.scenario for c in cases]
    if len({batch_key(c) for c in cases}) != 1:
        raise ValueError(one_key)
    try:
        models, modes = [c.model for c in cases], [c.mode for c in cases]
        pieces, phases, stats = _guarded_integrate(models, modes, scs[0].simulation, scs[0].name)
    except (SolverError, ValueError) as exc:
        logger.info("stacked run of %d scenarios failed (%s); running them one by one", len(scs), exc)
        return [_alone(sc) for sc in scs]
    wall = (time.perf_counter() - wall0) / len(scs)
    return [
        BatchMember(
            c.scenario,
            Result.from_pieces(
                c.scenario,
                c.model,
                c.mode,
                pieces[b],
                [dict(p) for p in phases],
                dict(stats, batch_size=len(scs), wall_time_s=wall),
            ),
            "ok",
        )
        for b, c in enumerate(cases)
    ]


def _alone(sc: Scenario) -> BatchMember:
    try:
        return BatchMember(sc, simulate(sc), "ok")
    except SolverError as exc:
        return BatchMember(sc, None, "solver_failure", str(exc))
