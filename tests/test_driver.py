"""The simulation driver (snoworm.driver): solver failures, solver work budgets, batched runs.

Budgets are ~30 % above the counts measured when they were set (benchmarks/run.py measures
the wall-clock side, docs/performance.md).  A change that makes the solver work harder fails
here; one that makes it cheaper should lower the budget.  The Figs 6-7 steady state is in
test_uniform.py, the energy balance in test_energy.py.
"""
import numpy as np
import pytest

from snoworm import SolverError, load_scenario, simulate
from snoworm.driver import batch_key, simulate_batch
from snoworm.sweep import case_metrics
from tests.conftest import assert_metrics_close


def test_solver_failure_raises(monkeypatch, scenario_path):
    import importlib
    S = importlib.import_module("snoworm.driver")

    class Bad:
        status, message, nfev, njev, nlu = -1, "Required step size is less than spacing between numbers.", 1, 0, 0
        t = np.array([0.0])
        y = np.zeros((36, 1))
        t_events = None
    monkeypatch.setattr(S, "solve_ivp", lambda *a, **k: Bad())
    with pytest.raises(SolverError, match="step size"):
        S.simulate(load_scenario(scenario_path("tow6_uniform")))


#: scenario -> (nfev budget, njev budget); measured 596 / 20 and 21 089 / 1 285 (LSODA, rtol 1e-5)
BUDGETS = {"tow6_uniform": (780, 30), "inchworm6": (27_500, 1_700), "frostyboy_case3": (630, 12)}


@pytest.mark.parametrize("name", sorted(BUDGETS))
def test_solver_work_budget(scenario_path, name):
    res = simulate(load_scenario(scenario_path(name)))
    nfev, njev = BUDGETS[name]
    assert res.stats["nfev"] <= nfev, res.stats
    assert res.stats["njev"] <= njev, res.stats


CASES = [(0.6, 0.0, 1.8), (0.75, 100.0, 1.5), (0.9, 200.0, 1.8), (1.0, 300.0, 2.0), (0.5, 0.0, 1.0)]


def test_batched_runs_match_one_by_one(scenario_path):
    scs = [load_scenario(scenario_path("tow6_uniform"),
                         [("terrain.xt", xt), ("tow.force_N", f), ("mode.speed_mps", v), ("simulation.duration_s", 4)])
           for xt, f, v in CASES]
    assert len({batch_key(sc) for sc in scs}) == 1
    batched = simulate_batch(scs)
    for sc, mb in zip(scs, batched):
        assert mb.status == "ok", mb.error
        assert_metrics_close(case_metrics(simulate(sc)), case_metrics(mb.result))
        assert mb.result.stats["batch_size"] == len(scs)


# ------------------------------------------------------------------ work limit and sanity (issue 15)

def test_work_limit_ends_a_too_stiff_run(monkeypatch, scenario_path):
    """A max_step_s of 1e-7 s needs 1e7 steps per second: the work limit stops it early."""
    import snoworm.driver as D
    sc = load_scenario(scenario_path("tow6_uniform"), [("simulation.max_step_s", 1e-7)])
    monkeypatch.setattr(D, "WORK_BASE_NFEV", 2_000)
    calls = []
    real = sc.chain_model.rhs
    monkeypatch.setattr(sc.chain_model, "rhs", lambda *a: calls.append(1) or real(*a))
    with pytest.raises(SolverError, match=r"work limit: \d+ right-hand-side evaluations by t = .* too stiff"):
        simulate(sc)
    assert len(calls) <= 2_000 + D.work_rate(sc.simulation) * 1e-3     # stopped within the budget


def test_work_limit_leaves_shipped_runs_alone(scenario_path):
    """The budget is far above what a shipped scenario needs (nfev per simulated second)."""
    from snoworm.driver import WORK_BASE_NFEV, work_rate
    sc = load_scenario(scenario_path("inchworm2"))
    res = simulate(sc)
    assert res.stats["nfev"] < 0.1 * (WORK_BASE_NFEV + work_rate(sc.simulation) * 20)


def test_work_rate_grows_with_tighter_tolerances(scenario_path):
    from snoworm.driver import WORK_NFEV_PER_S, work_rate
    sc = load_scenario(scenario_path("tow6_uniform"))
    assert work_rate(sc.simulation) == WORK_NFEV_PER_S                       # rtol 1e-5, atol_scale 1
    tight = sc.with_({"simulation.rtol": 1e-9, "simulation.atol_scale": 1e-3})
    assert work_rate(tight.simulation) == pytest.approx(10 * WORK_NFEV_PER_S)  # (1e-5 / 1e-9)^(1/4)


def test_max_wall_s_ends_the_run(monkeypatch, scenario_path):
    import snoworm.driver as D
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
    sc = load_scenario(scenario_path("tow6_uniform"), [("vehicle.segment.wheel_inertia_kgm2", 1e-300),
                                                       ("simulation.duration_s", 3)])
    with pytest.raises(SolverError):
        simulate(sc)


def test_solve_interval_is_under_the_work_limit_too(scenario_path):
    """The public interval solve (snoworm.Simulator steps) counts its own budget from its start."""
    from snoworm.driver import assemble, output_grid, solve_interval
    sc = load_scenario(scenario_path("tow6_uniform"), [("simulation.max_step_s", 1e-7)])
    case = assemble(sc)
    y0 = case.mode.initial_state()
    ctl = case.mode.interval(0.0, y0).controls
    stats = {"nfev": 0, "njev": 0, "nlu": 0, "intervals": 0}
    with pytest.raises(SolverError, match="work limit"):
        solve_interval(case.model, ctl, 100.0, 101.0, y0, [], sc.simulation, output_grid(100.0, 101.0, 0.05, True),
                       stats, "step", {})
