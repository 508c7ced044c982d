"""The shipped controller examples (examples/controllers/) do what their descriptions claim."""

import numpy as np
import pytest
from click.testing import CliRunner

from snoworm import load_scenario, simulate
from snoworm.cli import main
from tests.conftest import ROOT, SCENARIOS

EX = ROOT / "examples" / "controllers"


@pytest.mark.slow
def test_tow6_driven_by_controller_reproduces_uniform_mode():
    """Issue 14: 1.8 m/s to every segment from t = 1 s reproduces tow6_uniform's link forces within 1 N."""
    a = simulate(load_scenario(SCENARIOS / "tow6_uniform.yaml"))
    b = simulate(load_scenario(EX / "tow6_uniform_controller.yaml"))
    # the controller run also has a sample at every period's end: compare at the uniform run's times
    idx = np.minimum(np.searchsorted(b.t, a.t - 1e-9), b.t.size - 1)
    np.testing.assert_allclose(b.t[idx], a.t, atol=1e-9)
    assert np.max(np.abs(a.links["force_N"])) > 100  # the comparison is not of two idle chains
    assert np.max(np.abs(b.links["force_N"][idx] - a.links["force_N"])) < 1.0


@pytest.mark.slow
def test_fig8_pi_controller_drives_link_force_to_zero():
    """Like the built-in force-control mode (scenarios/pi2_zero.yaml): |link force| < 2 N."""
    res = simulate(load_scenario(EX / "fig8_pi.yaml"))
    f = res.links["force_N"][:, 0]
    late = res.t > 15.0
    assert np.max(np.abs(f[late])) < 2.0
    assert np.max(np.abs(f)) > 20.0  # it had something to regulate
    ref = simulate(load_scenario(SCENARIOS / "pi2_zero.yaml"))
    assert res.segments["speed_setpoint_mps"][-1, 0] == pytest.approx(
        ref.segments["speed_setpoint_mps"][-1, 0], abs=0.01
    )


@pytest.mark.slow
def test_inching_gait_progresses_where_rolling_is_immobilised():
    sc = load_scenario(EX / "inching2.yaml")
    res = simulate(sc)
    x = res.segments["x_m"]
    assert np.all(x[-1] - x[0] > 1.0)
    ext = res.links["extension_m"][:, 0]
    assert ext.max() > 0.25 and ext.min() < 0.05  # full strokes
    roll = simulate(
        sc.with_({"mode": {"type": "uniform", "speed_mps": 0.6, "start_time_s": 0.5}, "vehicle.links.type": "fixed"})
    )
    xr = roll.segments["x_m"]
    assert np.all(xr[-1] - xr[0] < 0.2)


@pytest.mark.slow
def test_slip_balance_shares_the_load_evenly():
    sc = load_scenario(EX / "slip_balance6.yaml")
    res = simulate(sc)
    W = res.segments["net_force_N"][-1]
    assert np.ptp(res.segments["slip"][-1]) < 0.002
    assert np.max(np.abs(W - W.mean())) < 2.0  # even shares (200 N / 6 each plus nothing else)
    speeds = sc.mode.params["speeds_mps"]
    fixed = simulate(sc.with_({"mode": {"type": "uniform", "speed_mps": speeds, "start_time_s": 1.0}}))
    assert np.ptp(fixed.segments["net_force_N"][-1]) > 100.0  # without it the front segments pull the rear


def test_example_runs_from_yaml_through_the_cli(tmp_path):
    out = tmp_path / "out"
    r = CliRunner().invoke(
        main,
        [
            "run",
            str(EX / "slip_balance6.yaml"),
            "--out",
            str(out),
            "--no-plot",
            "--set",
            "simulation.duration_s=2",
            "--set",
            "mode.params.ki_mps=4",
        ],
    )
    assert r.exit_code == 0, r.output
    written = (out / "scenario.yaml").read_text()
    assert "slip_balance.py:SlipBalance" in written and "ki_mps: 4" in written
