"""Uniform wheel-speed mode (snoworm.modes.uniform): paper Figs 6-7 steady state (docs/model.md section 5)."""

import numpy as np
import pytest

from snoworm import load_scenario, simulate


@pytest.fixture(scope="module")
def fig6(request):
    from tests.conftest import SCENARIOS

    return simulate(load_scenario(SCENARIOS / "tow6_uniform.yaml"))


def test_fig6_steady_state(fig6):
    """docs/model.md section 5: link tensions 33.3 k N (+-1 N), 33.3 N per segment, slip 4.80 %, V 1.714 m/s."""
    T = fig6.links["force_N"][-1]
    assert np.allclose(T, 200.0 / 6 * np.arange(1, 6), atol=1.0)
    assert np.allclose(fig6.segments["net_force_N"][-1], 200.0 / 6, atol=1.0)
    assert np.allclose(fig6.segments["slip"][-1], 0.0480, atol=0.0005)
    assert np.allclose(fig6.segments["v_mps"][-1], 1.714, atol=0.002)


def test_fig7_staggered_reaches_fig6(fig6, scenario_path):
    res = simulate(load_scenario(scenario_path("tow6_staggered")))
    assert np.allclose(res.links["force_N"][-1], fig6.links["force_N"][-1], atol=1.0)
    # motors really were off before their start times: rear segment not driven before 6 s
    early = res.t < 5.9
    assert np.all(res.segments["motor_torque_Nm"][early, 5] == 0.0)
    assert np.any(res.segments["motor_torque_Nm"][~early, 5] > 1.0)


def test_steady_state_agrees_with_root_finder(fig6):
    from types import SimpleNamespace

    from snoworm.config.params import parameter_set, terrain_params
    from snoworm.steady import steady_state

    FROSTYBOY_TERRAIN = terrain_params("frostyboy")
    seg = SimpleNamespace(**parameter_set("frostyboy")["segment"])
    ss = steady_state(0.9, seg, FROSTYBOY_TERRAIN, wheel_speed_mps=1.8, drawbar_N=200.0 / 6)
    assert fig6.segments["slip"][-1, 0] == pytest.approx(ss.slip, abs=2e-4)
    assert fig6.segments["motor_torque_Nm"][-1, 0] == pytest.approx(ss.torque_Nm, abs=0.05)
