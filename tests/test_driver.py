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


def test_progress_reports_simulated_time_and_changes_nothing(scenario_path):
    sc = load_scenario(scenario_path("inchworm2")).with_({"simulation.duration_s": 4.0})
    seen = []
    res = simulate(sc, progress=lambda t, total: seen.append((t, total)))
    ref = simulate(sc)
    assert len(seen) == res.stats["intervals"] > 1
    assert [t for t, _ in seen] == sorted(t for t, _ in seen) and seen[-1] == (4.0, 4.0)
    assert {tot for _, tot in seen} == {4.0}
    assert res.stats["nfev"] == ref.stats["nfev"]
    np.testing.assert_array_equal(res.segments["x_m"], ref.segments["x_m"])


def test_solver_fallbacks_are_logged(monkeypatch, scenario_path, caplog):
    import logging
    from snoworm import driver
    real, calls = driver.solve_ivp, []

    def flaky(*a, **kw):
        calls.append(kw["method"])
        if len(calls) == 1:
            raise ValueError("injected")
        return real(*a, **kw)
    monkeypatch.setattr(driver, "solve_ivp", flaky)
    sc = load_scenario(scenario_path("frostyboy_case1")).with_({"simulation.duration_s": 1.0})
    with caplog.at_level(logging.INFO, logger="snoworm"):
        res = simulate(sc)
    assert res.stats["retries"] == 1 and calls[:2] == ["LSODA", "BDF"]
    msgs = [r.getMessage() for r in caplog.records if r.name == "snoworm"]
    assert len(msgs) == 1 and "LSODA: injected" in msgs[0] and "retried with BDF" in msgs[0]
