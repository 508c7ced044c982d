"""End-to-end physics of the rolling chain: paper Figs 6-7 steady state, energy balance, failures."""
import numpy as np
import pytest

from snoworm import load_scenario, simulate
from snoworm.energy import energy_balance
from snoworm import SolverError


@pytest.fixture(scope="module")
def fig6(request):
    from tests.conftest import SCENARIOS
    return simulate(load_scenario(SCENARIOS / "tow6_uniform.yaml"))


def test_fig6_steady_state(fig6):
    """MODEL.md section 5: link tensions 33.3 k N (+-1 N), 33.3 N per segment, slip 4.80 %, V 1.714 m/s."""
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
    from snoworm.params import parameter_set, terrain_params
    from snoworm.steady import steady_state
    FROSTYBOY_TERRAIN = terrain_params("frostyboy")
    seg = SimpleNamespace(**parameter_set("frostyboy")["segment"])
    ss = steady_state(0.9, seg, FROSTYBOY_TERRAIN, wheel_speed_mps=1.8, drawbar_N=200.0 / 6)
    assert fig6.segments["slip"][-1, 0] == pytest.approx(ss.slip, abs=2e-4)
    assert fig6.segments["motor_torque_Nm"][-1, 0] == pytest.approx(ss.torque_Nm, abs=0.05)


def test_energy_balance(scenario_path):
    """Motor work - dissipation - tow work = change of kinetic + spring energy (within 0.5 % of motor work)."""
    sc = load_scenario(scenario_path("tow6_staggered"),
                       ["simulation.output_dt_s=0.002", "simulation.rtol=1e-7", "simulation.duration_s=10"])
    res = simulate(sc)
    b = energy_balance(res)       # fixed links: throughput = |motor work| (no joint power)
    assert b["joint_J"] == 0.0
    assert b["throughput_J"] > 1e4
    assert abs(b["residual_J"]) < 5e-3 * b["throughput_J"]


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
