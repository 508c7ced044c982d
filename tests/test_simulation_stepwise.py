"""Step-by-step simulation (snoworm.simulation.stepwise.Simulator)."""

import numpy as np
import pytest

from snoworm import Result, Simulator, load_scenario, simulate
from snoworm.simulation.driver import chain_model
from tests.conftest import SCENARIOS


@pytest.fixture
def tow6():
    return load_scenario(SCENARIOS / "tow6_uniform.yaml").with_({"simulation.duration_s": 3.0})


def test_reset_step_result(tow6):
    sim = Simulator(tow6)
    obs = sim.reset()
    assert obs.t_s == 0.0 and np.all(obs.v_mps == 0) and np.all(obs.motor_torque_Nm == 0)
    for _ in range(10):
        obs = sim.step({"wheel_speed_mps": [1.8] * 6}, 0.1)
    assert obs.t_s == pytest.approx(1.0, abs=1e-12) and sim.t_s == obs.t_s
    assert np.all(obs.v_mps > 0.1)
    res = sim.result()
    assert isinstance(res, Result)
    assert res.t[0] == 0.0 and res.t[-1] == pytest.approx(1.0)
    assert np.all(np.diff(res.t) > 0)
    np.testing.assert_array_equal(res.segments["x_m"][-1], obs.x_m)
    s = res.summary()
    assert s["distance_m"] > 0.3 and s["solver"]["intervals"] == 10
    obs = sim.reset()  # back to the start, nothing kept
    assert obs.t_s == 0.0 and np.all(obs.x_m == sim.observation().x_m)
    with pytest.raises(ValueError, match="step"):
        sim.result()


def test_matches_simulate_for_the_same_schedule(tow6):
    """Motors on at 1 s at 1.8 m/s: tow6_uniform's run, up to solver tolerance."""
    ref = simulate(tow6)
    sim = Simulator(tow6)
    sim.reset()
    sim.step(None, 1.0)
    sim.step({"wheel_speed_mps": [1.8] * 6}, 2.0)
    res = sim.result()
    np.testing.assert_allclose(res.t, ref.t, atol=1e-12)
    assert np.max(np.abs(res.links["force_N"] - ref.links["force_N"])) < 0.05


@pytest.mark.parametrize("dt", [0.004, 0.5])
def test_small_or_large_steps_keep_the_accuracy(tow6, dt):
    sims = []
    for step in (dt, 2.0):
        sim = Simulator(tow6)
        sim.reset()
        sim.step({"wheel_speed_mps": [1.5] * 6}, 0.5)
        n = int(round(2.0 / step))
        for _ in range(n):
            obs = sim.step(None, step)
        sims.append(obs)
    a, b = sims
    assert a.t_s == pytest.approx(b.t_s, abs=1e-9)
    np.testing.assert_allclose(a.x_m, b.x_m, atol=1e-4)
    np.testing.assert_allclose(a.link_force_N, b.link_force_N, atol=0.05)


@pytest.mark.parametrize("dt", [0, -0.1, np.nan, np.inf, "0.1", True])
def test_bad_dt(tow6, dt):
    sim = Simulator(tow6)
    with pytest.raises(ValueError, match="dt"):
        sim.step(None, dt)


def test_bad_command_changes_nothing(tow6):
    sim = Simulator(tow6)
    sim.step({"wheel_speed_mps": [1.0] * 6}, 0.2)
    with pytest.raises(ValueError, match="'wheel_lok'"):
        sim.step({"wheel_lok": [True] * 6}, 0.2)
    assert sim.t_s == pytest.approx(0.2)
    np.testing.assert_array_equal(sim.commands.controls.speed_sp_mps, 1.0)


def test_wheel_lock_holds_the_wheels(tow6):
    sim = Simulator(tow6)
    sim.step({"wheel_speed_mps": [1.5] * 6}, 1.0)
    obs = sim.step({"wheel_lock": [True] * 6}, 2.0)
    assert np.max(np.abs(obs.wheel_speed_mps)) < 0.01


def test_joint_force_and_length_commands_through_the_actuator():
    sc = load_scenario(SCENARIOS / "inchworm2.yaml")  # starts fully extended
    L = chain_model(sc).links
    sim = Simulator(sc)
    s0 = sim.reset().joint_extension_m[0]
    assert s0 == pytest.approx(L.stroke_max_m[0])
    sim.step({"wheel_lock": [True, True]}, 0.5)
    for ref in (80.0, 200.0):  # tension: the joint pulls
        obs = sim.step({"joint_force_N": [ref]}, 1.0)
        assert obs.link_force_N[0] == pytest.approx(ref, abs=1.0)
    # length command: the extension moves towards it no faster than the actuator's rate limit
    s0 = obs.joint_extension_m[0]
    obs = sim.step({"joint_length_m": [0.1]}, 0.1)
    assert 0 < s0 - obs.joint_extension_m[0] <= L.rate_max_mps[0] * 0.1 + 1e-6
    obs = sim.step(None, 2.0)
    assert obs.joint_extension_m[0] == pytest.approx(0.1, abs=0.005)
    obs = sim.step({"joint_force_N": [-120.0]}, 0.5)  # compression, away from the end stops
    assert obs.link_force_N[0] == pytest.approx(-120.0, abs=1.0)
    obs = sim.step({"joint_length_m": [-5.0]}, 3.0)  # beyond the stroke: held at the end stop
    assert obs.joint_extension_m[0] >= L.stroke_min_m[0] - 0.01


def test_solver_failure_leaves_the_simulator_at_the_step_start(tow6, monkeypatch):
    from snoworm.simulation.driver import SolverError
    from snoworm.simulation.interval import IntervalSolver

    sim = Simulator(tow6)
    sim.step({"wheel_speed_mps": [1.0] * 6}, 0.2)
    before = sim.observation()

    def boom(*a, **k):
        raise SolverError("every method failed (test)")

    monkeypatch.setattr(IntervalSolver, "solve", boom)
    with pytest.raises(SolverError):
        sim.step({"wheel_speed_mps": [2.0] * 6}, 0.2)
    assert sim.t_s == before.t_s
    np.testing.assert_array_equal(sim.observation().x_m, before.x_m)
    np.testing.assert_array_equal(sim.commands.controls.speed_sp_mps, 1.0)  # the failed step's command undone
    assert sim.result().t[-1] == pytest.approx(0.2)


def test_simulator_observes_the_grade_under_each_segment():
    """A controller sees the chord grade under each segment (docs/model.md section 7): on a route that
    rises 1 m in 10 m from x = 0, the leader sits on it while the segments behind are level."""
    import snoworm

    sc = snoworm.load_scenario("tow6_uniform", ["terrain.elevation=[[0,0],[10,1],[20,1]]"])
    obs = snoworm.Simulator(sc).observation()
    grade = obs.grade_deg
    assert grade.shape == (6,)
    assert 0.0 < grade[0] < np.degrees(np.arcsin(0.1)) + 1e-9  # straddles the foot of the rise
    np.testing.assert_allclose(grade[1:], 0.0, atol=1e-12)
    blank = snoworm.modes.command.Observation(
        t_s=0.0,
        **{k: np.zeros(6) for k in ("x_m", "v_mps", "wheel_speed_mps", "slip", "motor_torque_Nm", "xt")},
        **{k: np.zeros(5) for k in ("link_force_N", "link_length_m", "joint_extension_m")},
    )
    np.testing.assert_array_equal(blank.grade_deg, np.zeros(6))  # built by hand without a grade: level


@pytest.mark.parametrize("dt", [5e-324, 10**400, 1e300, 1e6, -(10**400), 1e-7])
def test_dt_out_of_bounds_is_a_clear_value_error(tow6, dt):
    sim = Simulator(tow6)
    with pytest.raises(ValueError, match=r"dt: the step length must be a number of seconds from 1e-06 to") as err:
        sim.step(None, dt)
    assert len(str(err.value)) < 300  # the value is quoted short
    assert sim.t_s == 0.0


def _snoworm_bytes(snapshot):
    """Bytes still allocated by snoworm's own code (innermost frame in the package): SciPy 1.17's
    LSODA keeps ~24 kB per solve_ivp call alive by itself, which snoworm cannot free."""
    import os
    import tracemalloc

    import snoworm

    # the package's own folder, not any path holding "snoworm" (a checkout named snoworm/ holds the
    # venv, and with it SciPy)
    package = os.path.join(os.path.dirname(os.path.abspath(snoworm.__file__)), "*")
    return sum(st.size for st in snapshot.filter_traces([tracemalloc.Filter(True, package)]).statistics("filename"))


def test_record_false_keeps_snoworms_memory_flat_and_record_true_is_bounded(tow6):
    import gc
    import tracemalloc

    sim = Simulator(tow6, record=False)
    sim.reset()
    sim.step({"wheel_speed_mps": [1.0] * 6}, 0.01)
    tracemalloc.start()
    for _ in range(100):
        sim.step(None, 0.01)
    gc.collect()
    mid = _snoworm_bytes(tracemalloc.take_snapshot())
    for _ in range(400):
        sim.step(None, 0.01)
    gc.collect()
    end = _snoworm_bytes(tracemalloc.take_snapshot())
    rec = Simulator(tow6)
    for _ in range(400):
        rec.step(None, 0.01)
    gc.collect()
    recorded = _snoworm_bytes(tracemalloc.take_snapshot())
    tracemalloc.stop()
    # 400 more steps without recording: under 20 kB kept; a recording one keeps its samples (~0.4 kB a
    # step allocated in snoworm frames, measured 152 kB for 400 steps)
    assert end - mid < 20_000, (mid, end)
    assert recorded - end > 100_000, (end, recorded)
    with pytest.raises(ValueError, match="record=False"):
        sim.result()
    with pytest.raises(ValueError, match="recorded history would pass"):
        for _ in range(10_000):
            rec.step(None, 0.5)
    assert rec.result().t[-1] == pytest.approx(rec.t_s)


def test_record_false_steps_start_at_their_start_and_state_is_a_copy(tow6):
    kept, light = Simulator(tow6), Simulator(tow6, record=False)
    for sim in (kept, light):
        sim.reset()
        for _ in range(3):
            t0 = sim.t_s
            y0 = sim.state
            sim.step({"wheel_speed_mps": [1.8] * 6}, 0.1)
    ts, ys, _ = light.last_step  # y0, t0: light's last step start
    assert ts[0] == t0  # the step's start is its first sample
    np.testing.assert_allclose(ys[0], y0, rtol=1e-12, atol=1e-12)  # (solve_ivp's interpolant at its node)
    assert kept.last_step[0][0] > t0  # the Result has the start already
    np.testing.assert_array_equal(light.state, kept.state)  # the same solve either way
    light.state[0] = 99.0  # a copy: the simulator is untouched
    assert light.state[0] != 99.0
