"""Performance regressions without timing anything: solver work budgets and the batched sweep path.

Budgets are ~30 % above the counts measured when they were set (benchmarks/run.py measures
the wall-clock side, docs/performance.md).  A change that makes the solver work harder fails
here; one that makes it cheaper should lower the budget.
"""
import numpy as np
import pytest

from snoworm.driver import batch_key, simulate_batch
from snoworm.sweep import BatchExecutor, run_chunk
from snoworm.scenario import apply_overrides, load_scenario, read_yaml
from snoworm import simulate
from snoworm.sweep import case_metrics, run_sweep

#: scenario -> (nfev budget, njev budget); measured 596 / 20 and 21 089 / 1 285 (LSODA, rtol 1e-5)
BUDGETS = {"tow6_uniform": (780, 30), "inchworm6": (27_500, 1_700), "frostyboy_case3": (630, 12)}


@pytest.mark.parametrize("name", sorted(BUDGETS))
def test_solver_work_budget(scenario_path, name):
    res = simulate(load_scenario(scenario_path(name)))
    nfev, njev = BUDGETS[name]
    assert res.stats["nfev"] <= nfev, res.stats
    assert res.stats["njev"] <= njev, res.stats


def assert_metrics_close(a, b, rel=1e-3):
    """Summary metrics agree within 0.1 % (with absolute floors for values near zero)."""
    floors = {"distance_m": 1e-4, "mean_speed_mps": 1e-4, "late_speed_mps": 1e-4, "mean_slip": 1e-4,
              "max_slip": 1e-4, "max_link_force_N": 1e-2, "energy_per_m_J": 1e-2}
    for k, floor in floors.items():
        if a[k] is None or b[k] is None:
            assert a[k] is b[k], k
            continue
        assert b[k] == pytest.approx(a[k], rel=rel, abs=floor), k
    fa, fb = np.array(a["final_link_forces_N"]), np.array(b["final_link_forces_N"])
    np.testing.assert_allclose(fb, fa, rtol=rel, atol=1e-2)
    assert a["immobilised"] == b["immobilised"]


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


def test_batched_sweep_matches_serial_sweep(scenario_path):
    sets = ["terrain.xt=0.6,0.9", "tow.force_N=0,150", "simulation.duration_s=3"]
    serial = run_sweep(scenario_path("tow6_uniform"), sets, plot=False)
    batched = run_sweep(scenario_path("tow6_uniform"), sets, plot=False, batch=10)
    assert len(serial) == len(batched) == 4
    for a, b in zip(serial.rows, batched.rows):
        assert a["case_id"] == b["case_id"] and b["status"] == "ok"
        b_links = [b[f"final_link_force_{j}_N"] for j in range(5)]
        a_links = [a[f"final_link_force_{j}_N"] for j in range(5)]
        assert_metrics_close({**a, "final_link_forces_N": a_links}, {**b, "final_link_forces_N": b_links})


def test_unbatchable_cases_run_one_by_one(scenario_path):
    """Event-driven modes and lone cases go through the ordinary per-case function."""
    uni = read_yaml(scenario_path("tow6_uniform"))
    inch = read_yaml(scenario_path("inchworm6"))
    tasks = [{"index": 0, "raw": apply_overrides(uni, [("simulation.duration_s", 2)])},
             {"index": 1, "raw": apply_overrides(uni, [("simulation.duration_s", 2), ("tow.force_N", 50)])},
             {"index": 2, "raw": inch},
             {"index": 3, "raw": apply_overrides(uni, [("simulation.duration_s", 3)])}]   # its own group of one
    seen = []

    def one(task):
        seen.append(task["index"])
        return {"index": task["index"], "status": "stub"}
    rows = {r["index"]: r for r in run_chunk(tasks, fn=one, metrics=case_metrics)}
    assert sorted(seen) == [2, 3]
    assert rows[0]["status"] == rows[1]["status"] == "ok"
    with pytest.raises(ValueError):
        BatchExecutor(0)
