"""Step-response metrics (snoworm.results.step): python-control's step_info conventions, checked
against first- and second-order responses whose metrics are known by hand.

Sampled 2000 times per time constant, the linear interpolation between samples puts a crossing
time within (dt^2 / 8) * |y''| / |y'| of the exact one: below 1e-7 time constants here, so times are
compared to 1e-5 of the time constant and percentages to 1e-4 points.
"""

import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from snoworm import load_scenario, simulate
from snoworm.results.result import load_result
from snoworm.results.step import step_info

TAU = 0.7


def test_first_order_response():
    """y = K (1 - exp(-t/tau)): rise time tau ln 9, settling time (2 %) tau ln 50, no overshoot;
    the step at t = 2 s from y0 = 3 and a reference 20 % above the final value."""
    t = np.linspace(0.0, 30 * TAU, 60001)
    K, y0, t_step = 1.5, 3.0, 2.0
    y = y0 + K * (1 - np.exp(-t / TAU))
    info = step_info(np.concatenate([[0.0, 1.0], t + t_step]), np.concatenate([[y0, y0], y]), y0 + 1.2 * K, t_step)
    assert info["rise_time_s"] == pytest.approx(TAU * math.log(9), abs=1e-5 * TAU)
    assert info["settling_time_s"] == pytest.approx(TAU * math.log(50), abs=1e-5 * TAU)
    assert info["overshoot_pct"] == 0.0 and info["undershoot_pct"] == 0.0
    assert info["initial_value"] == y0 and info["steady_state_value"] == pytest.approx(y0 + K, rel=1e-12)
    assert info["steady_state_error"] == pytest.approx(0.2 * K, rel=1e-9)
    assert info["steady_state_error_pct"] == pytest.approx(100 * 0.2 / 1.2, rel=1e-9)


def test_second_order_response():
    """Unit step of w^2 / (s^2 + 2 z w s + w^2), z = 0.5, w = 2 rad/s: overshoot
    100 exp(-pi z / sqrt(1 - z^2)) = 16.30 %, peak at pi / w_d; rise and settling times by root
    finding on the exact response (independent of the sampled one)."""
    z, w = 0.5, 2.0
    wd, phi = w * math.sqrt(1 - z * z), math.acos(z)

    def y(t):
        return 1 - np.exp(-z * w * t) / math.sqrt(1 - z * z) * np.sin(wd * t + phi)

    t = np.linspace(0.0, 20.0, 200001)
    info = step_info(t, y(t), 1.0)
    t10, t90 = brentq(lambda s: y(s) - 0.1, 0, 1.0), brentq(lambda s: y(s) - 0.9, 0, math.pi / wd)
    grid = np.linspace(0, 20, 20001)
    last_out = grid[np.flatnonzero(np.abs(y(grid) - 1) >= 0.02)[-1]]
    ts = brentq(lambda s: abs(y(s) - 1) - 0.02, last_out, last_out + 1e-3)
    assert info["overshoot_pct"] == pytest.approx(100 * math.exp(-math.pi * z / math.sqrt(1 - z * z)), abs=1e-4)
    assert info["peak_time_s"] == pytest.approx(math.pi / wd, abs=1e-4)
    assert info["rise_time_s"] == pytest.approx(t90 - t10, abs=1e-5)
    assert info["settling_time_s"] == pytest.approx(ts, abs=1e-5)
    assert info["steady_state_error"] == pytest.approx(1.0 - float(y(np.array(20.0))), abs=1e-15)  # e^-20 left


def test_a_response_that_does_not_move_has_no_times():
    info = step_info([0.0, 1.0, 2.0], [1.0, 1.0, 1.0], 2.0)
    assert info["rise_time_s"] is None and info["settling_time_s"] is None and info["overshoot_pct"] is None
    assert info["steady_state_error"] == 1.0


def test_a_controlled_run_has_step_response_in_summary_json_and_from_the_api(tmp_path):
    """Issue 34: step_response in summary.json and Result.step_info(), the same after reading back;
    force control measures each controlled link's force against its reference (the loops' aim)."""
    res = simulate(load_scenario("pi3_equal", ["simulation.duration_s=6"]))
    steps = res.step_info()
    loops = res.mode_summary["force_control"]["loops"]
    assert [s["response"].split(" force")[0] for s in steps] == [f"link {lp['link']}" for lp in loops]
    refs = res.mode_summary["force_control"]["link_force_refs_N"]
    F = res.links["force_N"]
    for s, lp in zip(steps, loops):
        j = lp["link"]
        assert s["reference"] == refs[j] and s["steady_state_value"] == F[-1, j]
        assert s["steady_state_error"] == pytest.approx(refs[j] - F[-1, j], abs=1e-12)
        assert s["t_step_s"] == 1.0 and s["initial_value"] == F[res.t >= 1.0][0, j]
    res.write(tmp_path / "o", plot=False)
    on_disk = json.loads((tmp_path / "o" / "summary.json").read_text())["step_response"]
    assert on_disk == json.loads(json.dumps(steps))
    # read back, the series carry the CSV files' 6 significant digits: the metrics agree to that
    loaded = load_result(tmp_path / "o")
    assert "step_response" not in loaded.mode_summary  # the run's own, not the mode's
    back = loaded.step_info()
    assert [b["response"] for b in back] == [s["response"] for s in steps]
    for b, s in zip(back, steps):
        for k, v in s.items():
            if isinstance(v, float):
                assert b[k] == pytest.approx(v, rel=1e-4, abs=1e-4 * max(abs(s["reference"]), 1.0)), k


def test_speed_response_of_a_uniform_run_and_none_for_a_gait():
    res = simulate(load_scenario("tow6_uniform", ["simulation.duration_s=4"]))
    (s,) = res.step_info()
    v = res.segments["v_mps"].mean(1)
    assert s["steady_state_value"] == v[-1]
    assert s["reference"] == pytest.approx(res.segments["speed_setpoint_mps"][-1].mean(), rel=1e-15)
    assert 0.0 < s["rise_time_s"] < s["settling_time_s"] <= s["window_s"]
    inch = simulate(load_scenario("inchworm2", ["simulation.duration_s=2"]))
    assert inch.step_info() is None and "step_response" not in inch.summary()
    early = simulate(load_scenario("tow6_uniform", ["simulation.duration_s=0.5"]))  # the step is at 1 s
    assert early.step_info() is None
