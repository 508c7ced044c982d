"""Supervisor mode (snoworm.modes.supervisor): rolls, inches through a patch rolling cannot cross, rolls on.

Beyond the paper (docs/beyond.md); route traverse_patch: X_t = 0.3 on [8, 18] m with 0.5 m ramps.
"""

import json

import pytest

from snoworm.config.scenario import ScenarioError, scenario_from_dict
from snoworm.results.energy import energy_metrics
from snoworm.simulation.driver import chain_model
from tests.conftest import traverse_raw as _base

PATCH_START_M, PATCH_END_M, PATCH_RAMP_M = 8.0, 18.0, 0.5


def test_supervisor_validation_errors():
    raw = _base(xt=0.9)
    raw["mode"]["inching"] = {**raw["mode"]["inching"], "start_time_s": 1.0}
    with pytest.raises(ScenarioError, match=r"mode\.inching\.start_time_s: not allowed here"):
        scenario_from_dict(raw)
    raw = _base(xt=0.9)
    raw["vehicle"]["links"] = {"type": "fixed"}
    with pytest.raises(ScenarioError, match="must be 'prismatic' for the gait"):
        scenario_from_dict(raw)


def test_rolling_alone_stays_stuck_in_patch(stuck):
    x = stuck.segments["x_m"]
    t = stuck.t
    assert PATCH_START_M < x[-1, 0] < PATCH_END_M  # leader stopped inside the patch
    late = t >= t[-1] - 10.0
    v_mean = (x[late][-1].mean() - x[late][0].mean()) / 10.0
    assert abs(v_mean) < 0.01  # no progress over the last 10 s [m/s]
    assert stuck.segments["slip"][-1, 0] > 0.9  # the leader's wheels spin


def test_supervisor_switches_in_the_patch_and_back(traverse):
    sw = [e for e in traverse.events if e["kind"].startswith("switch_")]
    assert [e["kind"] for e in sw] == ["switch_to_inching", "switch_to_rolling"]
    to_inch, to_roll = sw
    assert PATCH_START_M < to_inch["x_m"] < PATCH_END_M  # leader inside the patch when stuck
    assert to_roll["x_m"] > PATCH_END_M + PATCH_RAMP_M  # leader past the patch when rolling resumes
    assert to_inch["t_s"] < to_roll["t_s"]
    # gets through: the whole chain (rear segment) is past the patch at the end
    assert traverse.segments["x_m"][-1, -1] > PATCH_END_M + PATCH_RAMP_M
    s = traverse.summary()
    assert s["supervisor"]["final_state"] == "rolling"
    assert s["supervisor"]["distance_inching_m"] > 5.0
    # the switches reach summary.json
    kinds = [e["kind"] for e in json.loads(json.dumps(s))["events"]]
    assert kinds.count("switch_to_inching") == 1 and kinds.count("switch_to_rolling") == 1


def test_supervisor_plot_and_energy(traverse, tmp_path):
    from snoworm import plotting

    p = plotting.save(plotting.plot_positions(traverse), tmp_path / "positions.png")
    assert p.stat().st_size > 10000
    e = energy_metrics(traverse)
    assert e["total_electrical_J"] == pytest.approx(
        e["motor_electrical_total_J"] + e["joint_electrical_total_J"], rel=1e-12
    )
    # electrical >= mechanical (drivetrain efficiency 0.8, joint efficiency 0.7)
    assert e["motor_electrical_total_J"] >= sum(e["motor_mechanical_J"]) / 0.8 * 0.999
    mass = 6 * 90.0
    assert e["cost_of_transport"] == pytest.approx(e["total_electrical_J"] / (mass * 9.81 * e["distance_m"]), rel=1e-12)
    assert traverse.summary()["energy_metrics"]["energy_per_metre_J_per_m"] == pytest.approx(
        e["total_electrical_J"] / e["distance_m"], rel=1e-12
    )


def test_rolling_surplus_includes_the_grade():
    """The supervisor's resume test on a constant grade: the chain's rolling surplus is
    sum_k (cos(theta) D_k(0) - m g sin(theta)) - tow (docs/model.md section 7)."""
    import math

    import numpy as np

    from snoworm import load_scenario
    from snoworm.modes.supervisor import chain_drawbar_surplus_N

    level = load_scenario("traverse_patch")
    slope = level.with_({"terrain.grade_deg": 6.0})
    segs = level.vehicle.segment_params()
    x = np.array([30.0 - 1.5 * k for k in range(6)])  # past the patch: X_t = 0.9 under every axle
    s0 = chain_drawbar_surplus_N(chain_model(level), segs, x, 1.8)
    s6 = chain_drawbar_surplus_N(chain_model(slope), segs, x, 1.8)
    th = math.radians(6.0)
    m_g = segs[0].mass_kg * segs[0].gravity_mps2
    assert s6 == pytest.approx(math.cos(th) * s0 - 6 * m_g * math.sin(th), rel=1e-9)
