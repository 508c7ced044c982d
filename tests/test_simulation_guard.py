"""The guard around every solve (snoworm.simulation.guard, issue 15): work limit, wall-time limit,
solver breakdowns and runaway states end a run with SolverError; shipped runs stay far inside."""

import pytest

from snoworm import SolverError, load_scenario, simulate
from snoworm.dynamics import ChainModel
from snoworm.simulation import guard
from snoworm.simulation.driver import assemble
from snoworm.simulation.guard import WORK_BASE_NFEV, WORK_NFEV_PER_S, work_rate
from snoworm.simulation.interval import IntervalSolver, output_grid


def test_work_limit_ends_a_too_stiff_run(monkeypatch, scenario_path):
    """A max_step_s of 1e-7 s needs 1e7 steps per second: the work limit stops it early."""
    sc = load_scenario(scenario_path("tow6_uniform"), [("simulation.max_step_s", 1e-7)])
    monkeypatch.setattr(guard, "WORK_BASE_NFEV", 2_000)
    calls = []
    real = ChainModel.rhs  # the run assembles its own model: count the calls of every model's rhs
    monkeypatch.setattr(ChainModel, "rhs", lambda self, *a: calls.append(1) or real(self, *a))
    with pytest.raises(SolverError, match=r"work limit: \d+ right-hand-side evaluations by t = .* too stiff"):
        simulate(sc)
    assert 0 < len(calls) <= 2_000 + guard.work_rate(sc.simulation) * 1e-3  # stopped within the budget


def test_work_limit_leaves_shipped_runs_alone(scenario_path):
    """The budget is far above what a shipped scenario needs (nfev per simulated second)."""
    sc = load_scenario(scenario_path("inchworm2"))
    res = simulate(sc)
    assert res.stats["nfev"] < 0.1 * (WORK_BASE_NFEV + work_rate(sc.simulation) * 20)


def test_work_rate_grows_with_tighter_tolerances(scenario_path):
    sc = load_scenario(scenario_path("tow6_uniform"))
    assert work_rate(sc.simulation) == WORK_NFEV_PER_S  # rtol 1e-5, atol_scale 1
    tight = sc.with_({"simulation.rtol": 1e-9, "simulation.atol_scale": 1e-3})
    assert work_rate(tight.simulation) == pytest.approx(10 * WORK_NFEV_PER_S)  # (1e-5 / 1e-9)^(1/4)


def test_max_wall_s_ends_the_run(scenario_path):
    sc = load_scenario(scenario_path("inchworm2"), [("simulation.max_wall_s", 1e-6)])
    with pytest.raises(SolverError, match=r"simulation\.max_wall_s: .* \(limit 1e-06 s\)"):
        simulate(sc)


def test_runaway_chain_is_a_solver_failure(scenario_path):
    """A 1 MN tow drags the chain backward at ~2 km/s: beyond 5 x the no-load speed, not a result."""
    sc = load_scenario(scenario_path("tow6_uniform"), [("tow.force_N", 1e6), ("simulation.duration_s", 3)])
    with pytest.raises(SolverError, match=r"speed .* m/s .* beyond 24\.8 m/s .* run away"):
        simulate(sc)


def test_singular_matrix_is_a_solver_failure(scenario_path):
    """A wheel of (almost) no inertia makes the Newton matrix singular: SolverError, not a crash."""
    sc = load_scenario(
        scenario_path("tow6_uniform"), [("vehicle.segment.wheel_inertia_kgm2", 1e-300), ("simulation.duration_s", 3)]
    )
    with pytest.raises(SolverError):
        simulate(sc)


@pytest.mark.parametrize("method", ["LSODA", "VODE"])
def test_interval_solver_is_under_the_work_limit_too(scenario_path, method, monkeypatch):
    """The interval solve of snoworm.Simulator steps counts its budget from its first interval's
    start, from the solver's own counter (VODE) or the calls it counts (solve_ivp)."""
    sc = load_scenario(scenario_path("tow6_uniform"), [("simulation.max_step_s", 1e-7), ("simulation.method", method)])
    monkeypatch.setattr(guard, "WORK_BASE_NFEV", 3_000)
    case = assemble(sc)
    y0 = case.mode.initial_state()
    ctl = case.mode.interval(0.0, y0).controls
    solver = IntervalSolver(case.model, sc.simulation, "step")
    with pytest.raises(SolverError, match="work limit: .* by t = 100"):
        solver.solve(ctl, 100.0, 101.0, y0, (), output_grid(100.0, 101.0, 0.05, True))
    # stopped within a step's worth of calls of the limit at the time reached (1e-7 s steps: ~3 000)
    assert 3_000 <= solver.stats["nfev"] <= 3_000 + work_rate(sc.simulation) * 1e-3 + 20


def test_progress_within_a_long_interval(monkeypatch):
    """A uniform run is one long interval after its start: progress still hears of the simulated
    time reached while it is integrated (here at every check, PROGRESS_EVERY_S = 0), increasing,
    and ends at the duration."""
    from snoworm import load_scenario, simulate
    from snoworm.simulation import guard
    from tests.conftest import SCENARIOS

    monkeypatch.setattr(guard, "PROGRESS_EVERY_S", 0.0)
    calls = []
    res = simulate(
        load_scenario(SCENARIOS / "tow6_uniform.yaml", ["simulation.duration_s=20"]),
        progress=lambda t, T: calls.append((t, T)),
    )
    within = [t for t, _ in calls if 0.0 < t < 20.0]
    assert res.stats["intervals"] <= 3 and len(within) >= 5
    assert all(T == 20.0 for _, T in calls) and calls[-1][0] == 20.0
    assert all(b >= a for a, b in zip(within, within[1:]))


@pytest.mark.parametrize("method", ["LSODA", "VODE"])
def test_many_short_steps_are_not_a_stiff_run(scenario_path, method, monkeypatch):
    """Issue 30: Simulator.step with dt 1e-4 s failed with "too stiff" at 0.75 s: every step costs a
    few evaluations that no simulated second pays for, and they exhausted the base of the limit.  The
    limit allows WORK_NFEV_PER_INTERVAL per step asked; with a base 10 x smaller (which 0.3 s of such
    steps exhaust, as 0.75 s exhausted the real one) 3 000 steps of 1e-4 s must still go through."""
    from snoworm.simulation.stepwise import Simulator

    monkeypatch.setattr(guard, "WORK_BASE_NFEV", WORK_BASE_NFEV // 10)
    sc = load_scenario(scenario_path("tow6_uniform"), [("simulation.method", method)])
    sim = Simulator(sc, record=False)
    for k in range(3_000):
        sim.step({"wheel_speed_mps": [1.8 if (k // 100) % 2 else 1.0] * 6}, 1e-4)
    assert sim.t_s == pytest.approx(0.3, abs=1e-9)
    nfev = sim.stats["nfev"]
    assert nfev > WORK_BASE_NFEV // 10 + work_rate(sc.simulation) * 0.3  # past the old limit
    assert nfev < 0.2 * 3_000 * guard.WORK_NFEV_PER_INTERVAL  # the allowance per step is ample
    assert sim.observation().x_m[0] > 0.0


def test_a_stiff_run_of_many_steps_is_still_stopped(scenario_path, monkeypatch):
    """The allowance per interval does not hide a stiff system: steps of 1e-3 s that each need ~1e4
    evaluations (max_step_s 1e-7 s) end within the first few steps."""
    from snoworm.simulation.stepwise import Simulator

    monkeypatch.setattr(guard, "WORK_BASE_NFEV", 2_000)
    sc = load_scenario(scenario_path("tow6_uniform"), [("simulation.max_step_s", 1e-7)])
    sim = Simulator(sc, record=False)
    with pytest.raises(SolverError, match=r"work limit: .* \+ 100 per step, 1 steps\)"):
        for _ in range(10):
            sim.step({"wheel_speed_mps": [1.8] * 6}, 1e-3)
    assert sim.t_s == 0.0


def test_a_run_s_own_intervals_get_no_allowance(scenario_path, monkeypatch):
    """A mode's intervals are not steps asked: a supervisor re-checking every 1e-4 s still meets the
    work limit as before (with an allowance per interval, such a run went on for minutes)."""
    monkeypatch.setattr(guard, "WORK_BASE_NFEV", 2_000)
    sc = load_scenario(
        scenario_path("traverse_patch"),
        [("mode.check_interval_s", 1e-4), ("mode.stuck_window_s", 1.0), ("mode.start_time_s", 0.0)],
    )
    with pytest.raises(SolverError, match=r"work limit: .* per simulated second\)\. The system is too stiff"):
        simulate(sc)
