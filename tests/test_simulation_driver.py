"""The simulation driver (snoworm.simulation.driver): solver failures, solver work budgets, batched runs.

Budgets are ~15 % above the counts measured when they were set (benchmarks/run.py measures
the wall-clock side, docs/performance.md).  A change that makes the solver work harder fails
here; one that makes it cheaper should lower the budget.  The Figs 6-7 steady state is in
test_modes_uniform.py, the energy balance in test_results_energy.py.
"""

import numpy as np
import pytest

from snoworm import SolverError, load_scenario, simulate
from snoworm.simulation.driver import batch_key, simulate_batch
from snoworm.simulation.vode import VodeError, VodeStepper
from snoworm.studies.sweep import case_metrics
from tests.conftest import assert_metrics_close, shipped_result


def test_solver_failure_raises(monkeypatch, scenario_path):
    import importlib

    S = importlib.import_module("snoworm.simulation.driver")
    interval = importlib.import_module("snoworm.simulation.interval")

    class Bad:
        status, message, nfev, njev, nlu = -1, "Required step size is less than spacing between numbers.", 1, 0, 0
        t = np.array([0.0])
        y = np.zeros((36, 1))
        t_events = None

    monkeypatch.setattr(interval, "solve_ivp", lambda *a, **k: Bad())
    with pytest.raises(SolverError, match="step size"):
        S.simulate(load_scenario(scenario_path("tow6_uniform")))


#: scenario -> (nfev budget, njev budget), ~15 % above the counts measured: tow6_uniform 596 / 20,
#: frostyboy_case3 482 / 8 (LSODA); inchworm6 8 906 / 263, inchworm2 5 106 / 165 and traverse_patch
#: 43 473 / 1 150 (VODE, rtol 1e-5, atol_scale 3, wheel speeds' atol 10x more; before that
#: 10 424 / 290, 6 033 / 210 and 47 792 / 1 191; traverse_patch was 58 961 / 6 271 on LSODA)
BUDGETS = {
    "tow6_uniform": (690, 23),
    "frostyboy_case3": (555, 10),
    "inchworm6": (10_250, 305),
    "inchworm2": (5_900, 190),
    "traverse_patch": (50_000, 1_325),
}


@pytest.mark.parametrize(
    "name", [pytest.param(n, marks=pytest.mark.slow) if n == "traverse_patch" else n for n in sorted(BUDGETS)]
)
def test_solver_work_budget(name):
    res = shipped_result(name)
    nfev, njev = BUDGETS[name]
    assert res.stats["nfev"] <= nfev, res.stats
    assert res.stats["njev"] <= njev, res.stats


CASES = [(0.6, 0.0, 1.8), (0.75, 100.0, 1.5), (0.9, 200.0, 1.8), (1.0, 300.0, 2.0), (0.5, 0.0, 1.0)]


def test_batched_runs_match_one_by_one(scenario_path):
    scs = [
        load_scenario(
            scenario_path("tow6_uniform"),
            [("terrain.xt", xt), ("tow.force_N", f), ("mode.speed_mps", v), ("simulation.duration_s", 4)],
        )
        for xt, f, v in CASES
    ]
    assert len({batch_key(sc) for sc in scs}) == 1
    batched = simulate_batch(scs)
    for sc, mb in zip(scs, batched):
        assert mb.status == "ok", mb.error
        assert_metrics_close(case_metrics(simulate(sc)), case_metrics(mb.result))
        assert mb.result.stats["batch_size"] == len(scs)


def _short_inchworm(scenario_path, method):
    return simulate(
        load_scenario(scenario_path("inchworm2"), [("simulation.duration_s", 6), ("simulation.method", method)])
    )


def test_vode_matches_lsoda_within_tolerance(scenario_path):
    vode, lsoda = _short_inchworm(scenario_path, "VODE"), _short_inchworm(scenario_path, "LSODA")
    assert [p["label"] for p in vode.phases] == [p["label"] for p in lsoda.phases]
    np.testing.assert_allclose(
        [p["t_end_s"] for p in vode.phases], [p["t_end_s"] for p in lsoda.phases], rtol=0, atol=2e-3
    )
    np.testing.assert_allclose(vode.segments["x_m"][-1], lsoda.segments["x_m"][-1], rtol=0, atol=1e-4)
    assert vode.stats.get("retries", 0) == 0
    assert vode.stats["njev"] < lsoda.stats["njev"]


def test_vode_failure_falls_back_per_interval(monkeypatch, scenario_path):
    calls = []

    def fail_every_other(self, t1, events=(), t_eval=None, on_step=None):
        calls.append(self.t)
        if len(calls) % 2:
            raise VodeError(f"VODE failed near t = {self.t:.6g} s (istate -4)")
        return real(self, t1, events, t_eval, on_step)

    real = VodeStepper.advance
    monkeypatch.setattr(VodeStepper, "advance", fail_every_other)
    res = _short_inchworm(scenario_path, "VODE")
    ref = _short_inchworm(scenario_path, "LSODA")
    assert res.stats["retries"] == (len(calls) + 1) // 2  # each failed interval ran on LSODA
    np.testing.assert_allclose(res.segments["x_m"][-1], ref.segments["x_m"][-1], rtol=0, atol=1e-4)


def test_vode_every_method_failing_raises(monkeypatch, scenario_path):
    import importlib

    interval = importlib.import_module("snoworm.simulation.interval")

    def boom(*a, **k):
        raise ValueError("no luck")

    monkeypatch.setattr(VodeStepper, "advance", lambda self, *a, **k: boom())
    monkeypatch.setattr(interval, "solve_ivp", boom)
    with pytest.raises(SolverError, match="VODE: no luck; LSODA: no luck; BDF: no luck; Radau: no luck"):
        _short_inchworm(scenario_path, "VODE")


def test_batched_members_on_vode_are_stacked_on_lsoda(scenario_path):
    """A stack keeps LSODA (max-norm error test per member) when the members ask for VODE."""
    scs = [
        load_scenario(
            scenario_path("tow6_uniform"),
            [("terrain.xt", xt), ("simulation.duration_s", 3), ("simulation.method", "VODE")],
        )
        for xt in (0.6, 0.9)
    ]
    batched = simulate_batch(scs)
    for sc, mb in zip(scs, batched):
        assert mb.status == "ok" and mb.result.stats["batch_size"] == 2
        assert_metrics_close(case_metrics(simulate(sc)), case_metrics(mb.result))


def test_vode_carries_its_history_across_simulator_steps(scenario_path):
    """Simulator (its stepper carries VODE's history) on VODE: no restart per 10 ms step, same states, far less work."""
    from snoworm.simulation.stepwise import Simulator

    sc = load_scenario(scenario_path("tow6_uniform"), [("simulation.method", "VODE"), ("simulation.duration_s", 3)])
    runs = {}
    for cont in (True, False):
        sim = Simulator(sc)
        sim.reset()
        sim._stepper.carry_history = cont
        for k in range(300):
            sim.step({"wheel_speed_mps": [1.8] * 6} if k == 50 else None, 0.01, restart=not cont)
        runs[cont] = sim.result()
    assert runs[True].stats["nfev"] < runs[False].stats["nfev"] / 3
    assert runs[True].stats.get("retries", 0) == 0
    np.testing.assert_allclose(runs[True].links["force_N"][-1], runs[False].links["force_N"][-1], rtol=0, atol=0.05)
    np.testing.assert_allclose(runs[True].segments["v_mps"][-1], runs[False].segments["v_mps"][-1], rtol=0, atol=1e-4)


def test_only_the_controller_mode_continues_the_solver():
    from snoworm.modes import MODES

    assert {name for name, cls in MODES.items() if cls.continue_solver} == {"controller"}


def test_progress_reports_simulated_time_and_changes_nothing(scenario_path, monkeypatch):
    # one report per interval: the reports within an interval (every PROGRESS_EVERY_S of wall time)
    # are switched off, as on a loaded machine an interval can outlast it (a wall-clock count)
    from snoworm.simulation import guard

    monkeypatch.setattr(guard, "PROGRESS_EVERY_S", float("inf"))
    sc = load_scenario(scenario_path("inchworm2")).with_({"simulation.duration_s": 4.0})
    seen = []
    res = simulate(sc, progress=lambda t, total: seen.append((t, total)))
    ref = simulate(sc)
    assert len(seen) == res.stats["intervals"] > 1
    assert [t for t, _ in seen] == sorted(t for t, _ in seen) and seen[-1] == (4.0, 4.0)
    assert {tot for _, tot in seen} == {4.0}
    # the same scenario through the same code path twice in one process: the callback only reads,
    # so the two runs are identical operation for operation (exact equality is safe here)
    assert res.stats["nfev"] == ref.stats["nfev"]
    np.testing.assert_array_equal(res.segments["x_m"], ref.segments["x_m"])


def test_solver_fallbacks_are_logged(monkeypatch, scenario_path, caplog):
    import logging

    from snoworm.simulation import interval

    real, calls = interval.solve_ivp, []

    def flaky(*a, **kw):
        calls.append(kw["method"])
        if len(calls) == 1:
            raise ValueError("injected")
        return real(*a, **kw)

    monkeypatch.setattr(interval, "solve_ivp", flaky)
    sc = load_scenario(scenario_path("frostyboy_case1")).with_({"simulation.duration_s": 1.0})
    with caplog.at_level(logging.INFO, logger="snoworm"):
        res = simulate(sc)
    assert res.stats["retries"] == 1 and calls[:2] == ["LSODA", "BDF"]
    msgs = [r.getMessage() for r in caplog.records if r.name == "snoworm"]
    assert len(msgs) == 1 and "LSODA: injected" in msgs[0] and "retried with BDF" in msgs[0]


FC_CASES = [(0.9, 200.0, 1.8), (0.75, 150.0, 1.6), (1.0, 250.0, 2.0), (0.85, 100.0, 1.7)]


def test_batched_force_control_matches_one_by_one(scenario_path):
    """Force control has no state events: a stack of it equals its members run one by one."""
    scs = [
        load_scenario(
            scenario_path("pi3_equal"),
            [("terrain.xt", xt), ("tow.force_N", f), ("mode.speed_mps", v), ("simulation.duration_s", 6)],
        )
        for xt, f, v in FC_CASES
    ]
    assert len({batch_key(sc) for sc in scs}) == 1
    other = load_scenario(scenario_path("pi3_equal"), [("mode.start_time_s", 0.5)])
    assert batch_key(other) != batch_key(scs[0])  # other intervals: another stack
    batched = simulate_batch(scs)
    for sc, mb in zip(scs, batched):
        assert mb.status == "ok", mb.error
        assert mb.result.stats["batch_size"] == len(scs)
        alone = simulate(sc)
        assert_metrics_close(case_metrics(alone), case_metrics(mb.result))
        fa, fb = (r.mode_summary["force_control"] for r in (alone, mb.result))
        np.testing.assert_allclose(fb["final_setpoints_mps"], fa["final_setpoints_mps"], rtol=0, atol=1e-3)
        np.testing.assert_allclose(fb["final_link_force_errors_N"], fa["final_link_force_errors_N"], rtol=0, atol=0.1)


@pytest.mark.parametrize("given", ["tow6_uniform", None, {"name": "x"}])
def test_simulate_and_the_simulator_name_the_scenario_when_given_something_else(given):
    """A scenario name, None or a raw mapping is refused with one TypeError that says how to read one."""
    from snoworm import Simulator

    for make in (simulate, Simulator):
        with pytest.raises(TypeError, match=r"^scenario: expected a Scenario, got .*snoworm\.load_scenario"):
            make(given)


def _tow6_members(scenario_path, cases, duration_s=3):
    return [
        load_scenario(
            scenario_path("tow6_uniform"),
            [("terrain.xt", xt), ("tow.force_N", f), ("simulation.duration_s", duration_s)],
        )
        for xt, f in cases
    ]


def test_simulate_batch_steps_its_group_through_the_one_stepper(scenario_path, monkeypatch):
    """A batch's intervals are solved by ChainStepper (issue 31: one stacked solve): one stack of the
    member chains as given under WHOLE_RUNS, one stepper call per interval of the run; each member
    equals its run alone (an independent route: the single run's IntervalSolver) within the
    batched path's documented 0.1 %."""
    from snoworm.simulation import stepper as stepper_mod

    seen = []
    real = stepper_mod.ChainStepper.solve

    def spy(self, ctl, t0, t1, y, t_eval, label="step"):
        seen.append((self.policy, [(m.start, m.stop, model.n_batch) for m, model in self.stacks]))
        return real(self, ctl, t0, t1, y, t_eval, label)

    monkeypatch.setattr(stepper_mod.ChainStepper, "solve", spy)
    scs = _tow6_members(scenario_path, [(0.6, 0.0), (0.9, 200.0), (1.0, 300.0)])
    batched = simulate_batch(scs)
    assert [mb.status for mb in batched] == ["ok"] * 3
    assert len(seen) == batched[0].result.stats["intervals"] > 1  # every interval, none elsewhere
    assert {(p, tuple(s)) for p, s in seen} == {(stepper_mod.WHOLE_RUNS, ((0, 3, 3),))}
    n_stepped = len(seen)
    for sc, mb in zip(scs, batched):
        assert_metrics_close(case_metrics(simulate(sc)), case_metrics(mb.result))
    assert len(seen) == n_stepped  # the runs alone do not step through it


def test_a_failed_stack_runs_each_member_alone_from_its_start(scenario_path, monkeypatch):
    """If the stacked solve fails, every member runs alone from t = 0: its result is its single
    run's, bit for bit (the same code path: simulate)."""
    from snoworm.simulation import stepper as stepper_mod

    def fail(self, *a, **k):
        raise SolverError("injected stack failure")

    scs = _tow6_members(scenario_path, [(0.6, 0.0), (0.9, 200.0)], duration_s=2)
    alone = [simulate(sc) for sc in scs]
    monkeypatch.setattr(stepper_mod.ChainStepper, "solve", fail)
    batched = simulate_batch(scs)
    for ref, mb in zip(alone, batched):
        assert mb.status == "ok" and "batch_size" not in mb.result.stats
        for k in ("x_m", "v_mps"):
            np.testing.assert_array_equal(mb.result.segments[k], ref.segments[k])


def test_a_batch_member_is_held_to_its_own_chains_speed_limit(scenario_path, monkeypatch):
    """check_sane holds each member to the speed limit of its own chain (SPEED_SANITY_FACTOR x its
    no-load wheel speed + joint rate), as when it runs alone: a member beyond its own limit fails
    alone ("solver_failure", the speed named) and the other, within its own, is its run alone.
    Before, a stack was checked against the group's largest no-load speed and the slow chain passed.
    The factor is lowered so that the members' measured speeds (~1.8 m/s, the commanded wheel
    speed) fall between the two chains' limits."""
    from snoworm.simulation import guard
    from snoworm.simulation.driver import chain_model

    scs = [
        load_scenario(
            scenario_path("tow6_uniform"),
            [("vehicle.segment.no_load_speed_radps", nl), ("simulation.duration_s", 3)],
        )
        for nl in (18.326, 24.0)  # FrostyBoy's (7000 rpm / 40), and a faster motor
    ]
    assert batch_key(scs[0]) == batch_key(scs[1])
    models = [chain_model(sc) for sc in scs]

    def speed(res, m):  # check_sane's speed: ground and wheel-rim speeds
        return max(np.abs(res.segments["v_mps"]).max(), np.abs(res.segments["wheel_speed_mps"]).max())

    s = max(speed(simulate(sc), m) for sc, m in zip(scs, models))
    vnl = [float(np.max(m.seg.wheel_radius_m * m.seg.no_load_speed_radps)) for m in models]
    rate = float(np.max(models[0].links.rate_max_mps))
    factor = float(np.sqrt((s - rate) / vnl[1] * (s - rate) / vnl[0]))  # between the two limits
    assert factor * vnl[0] + rate < s < factor * vnl[1] + rate
    monkeypatch.setattr(guard, "SPEED_SANITY_FACTOR", factor)
    slow, fast = simulate_batch(scs)
    assert slow.status == "solver_failure" and "speed" in slow.error and slow.result is None
    assert fast.status == "ok"
    np.testing.assert_array_equal(fast.result.segments["v_mps"], simulate(scs[1]).segments["v_mps"])
