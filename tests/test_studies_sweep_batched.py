"""The batched sweep path (snoworm.studies.sweep.executors.BatchExecutor, run_chunk): batched sweeps equal serial ones.

The solver work budgets and the batched-vs-one-by-one driver test are in test_simulation_driver.py.
"""

import numpy as np
import pytest

from snoworm.config.scenario import apply_overrides, read_yaml
from snoworm.studies.sweep import BatchExecutor, SweepTask, case_metrics, run_chunk, run_sweep
from tests.conftest import assert_metrics_close


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


def test_batched_sweep_stacks_its_groups_in_the_one_stepper(scenario_path, monkeypatch):
    """--batch B: each group of up to B cases is one stack of ChainStepper (the stepper of the
    Simulator and the environments, issue 31), under the batched sweeps' policy; the rows equal
    the serial sweep's (the cases run alone, no stepper) within the batched path's 0.1 %."""
    from snoworm.simulation import stepper as stepper_mod

    stacks = set()
    real = stepper_mod.ChainStepper.solve

    def spy(self, *a, **k):
        stacks.add((self.policy, tuple((m.stop - m.start, model.n_batch) for m, model in self.stacks)))
        return real(self, *a, **k)

    monkeypatch.setattr(stepper_mod.ChainStepper, "solve", spy)
    sets = ["tow.force_N=0,100,200,300,400", "simulation.duration_s=2"]
    serial = run_sweep(scenario_path("tow6_uniform"), sets, plot=False)
    assert stacks == set()
    batched = run_sweep(scenario_path("tow6_uniform"), sets, plot=False, batch=3)
    assert stacks == {(stepper_mod.WHOLE_RUNS, ((3, 3),)), (stepper_mod.WHOLE_RUNS, ((2, 2),))}
    for a, b in zip(serial.rows, batched.rows):
        assert a["case_id"] == b["case_id"] and b["status"] == "ok"
        a, b = ({**r, "final_link_forces_N": [r[f"final_link_force_{j}_N"] for j in range(5)]} for r in (a, b))
        assert_metrics_close(a, b)


def test_unbatchable_cases_run_one_by_one(scenario_path):
    """Event-driven modes and lone cases go through the ordinary per-case function."""
    uni = read_yaml(scenario_path("tow6_uniform"))
    inch = read_yaml(scenario_path("inchworm6"))
    tasks = [
        SweepTask(0, raw=apply_overrides(uni, [("simulation.duration_s", 2)])),
        SweepTask(1, raw=apply_overrides(uni, [("simulation.duration_s", 2), ("tow.force_N", 50)])),
        SweepTask(2, raw=inch),
        SweepTask(3, raw=apply_overrides(uni, [("simulation.duration_s", 3)])),
    ]  # its own group of one
    seen = []

    def one(task):
        seen.append(task.index)
        return {"index": task.index, "status": "stub"}

    rows = {r["index"]: r for r in run_chunk(tasks, fn=one, metrics=case_metrics)}
    assert sorted(seen) == [2, 3]
    assert rows[0]["status"] == rows[1]["status"] == "ok"
    with pytest.raises(ValueError):
        BatchExecutor(0)


@pytest.mark.parametrize("batch", [0, 10])
def test_in_process_sweep_validates_each_case_once(scenario_path, monkeypatch, batch):
    """A sweep run in this process hands the scenarios it validated while planning to the executor."""
    import snoworm.studies.sweep.metrics as metrics
    import snoworm.studies.sweep.run as plan_mod

    calls = []

    def counting(original):
        def wrapped(*args, **kwargs):
            calls.append(1)
            return original(*args, **kwargs)

        return wrapped

    monkeypatch.setattr(plan_mod, "scenario_from_dict", counting(plan_mod.scenario_from_dict))
    monkeypatch.setattr(metrics, "scenario_from_dict", counting(metrics.scenario_from_dict))  # SweepTask.validated
    table = run_sweep(
        scenario_path("tow6_uniform"), ["tow.force_N=0,100,200", "simulation.duration_s=1"], plot=False, batch=batch
    )
    assert [r["status"] for r in table.rows] == ["ok"] * 3
    assert len(calls) == 3


def test_local_pool_tasks_carry_the_validated_scenarios(scenario_path):
    """For a local executor (this process or its own pool) the tasks carry the scenarios validated
    while planning, and no mapping to validate again; each equals a fresh validation of its case."""
    from snoworm.config.scenario import load_scenario
    from snoworm.studies.sweep.run import _tasks, plan_sweep as _plan

    sets = ["tow.force_N=0,100", "simulation.duration_s=1"]
    plan = _plan(scenario_path("tow6_uniform"), sets, False, False, None, 2, keep=True)
    tasks = list(_tasks(plan, plan.cases, None, False))
    assert [t.index for t in tasks] == [0, 1] and all(t.raw is None for t in tasks)
    for t, f in zip(tasks, (0.0, 100.0)):
        assert t.scenario == load_scenario(
            scenario_path("tow6_uniform"), [("tow.force_N", f), ("simulation.duration_s", 1)]
        )
    plan = _plan(scenario_path("tow6_uniform"), sets, False, False, None, 2, keep=False)
    assert all(
        t.scenario is None and t.raw["tow"]["force_N"] in (0, 100) for t in _tasks(plan, plan.cases, None, False)
    )


def test_grade_sweep_batches_only_equal_elevations():
    """Members on different grades get different batch keys (stacked chains share one elevation
    profile); members on the same grade share one, and the stacked run equals the runs alone."""
    from snoworm import load_scenario, simulate
    from snoworm.simulation.driver import batch_key, simulate_batch

    base = load_scenario("tow6_uniform", ["simulation.duration_s=3"])
    a, b = base.with_({"terrain.grade_deg": 4.0}), base.with_({"terrain.grade_deg": 8.0})
    assert batch_key(a) != batch_key(b)
    c = base.with_({"terrain.grade_deg": 4.0, "tow.force_N": 100.0})
    assert batch_key(a) == batch_key(c)
    for m, sc in zip(simulate_batch([a, c]), [a, c]):
        alone = simulate(sc)
        np.testing.assert_allclose(m.result.segments["v_mps"][-1], alone.segments["v_mps"][-1], rtol=1e-4)


def test_batched_sweep_assembles_each_case_once_and_records_a_refused_one(scenario_path, monkeypatch):
    """A batchable case is assembled once (its key and its stack read the same model); a case whose
    run cannot be assembled (a tow beyond the whole chain's drawbar: a check that needs the chain
    model, so not made while planning) is recorded invalid with the message, the others stacked."""
    from snoworm.simulation import driver

    built = []
    real = driver.chain_model
    monkeypatch.setattr(driver, "chain_model", lambda sc: built.append(sc.tow.force_N) or real(sc))
    sets = ["tow.force_N=100,200,1100", "simulation.duration_s=2"]
    table = run_sweep(scenario_path("pi3_equal"), sets, plot=False, batch=10)
    rows = {r["tow.force_N"]: r for r in table.rows}
    assert rows[100.0]["status"] == rows[200.0]["status"] == "ok"
    assert rows[1100.0]["status"] == "invalid" and "whole chain" in rows[1100.0]["error"]
    # once per case; the refused case once more, run alone to report it
    assert sorted(built) == [100.0, 200.0, 1100.0, 1100.0]
