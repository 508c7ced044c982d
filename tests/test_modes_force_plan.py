"""The force-control mode's plan (snoworm.modes.force_plan; paper section 5.2, docs/model.md section 5):
targets -> link-force references, available drawbar pull, load-share rules.

Conversions are exact sums (atol 1e-9 N); drawbar limits are checked against the hand formula
of the module docstring (rel 1e-6) and the terrain's peak drawbar of docs/model.md section 2 (1 N).
"""

from pathlib import Path

import numpy as np
import pytest
import yaml

from snoworm.config.scenario import load_scenario, scenario_from_dict
from snoworm.modes.force_plan import available_drawbar_N, plan
from snoworm.simulation.driver import chain_model

SCEN = Path(__file__).resolve().parent.parent / "scenarios"


def _raw(name):
    return yaml.safe_load((SCEN / f"{name}.yaml").read_text())


def test_available_drawbar_terrain_and_motor_limits():
    sc = load_scenario(SCEN / "tow6_weak_segment.yaml")
    model = chain_model(sc)
    segs = sc.vehicle.segment_params()
    healthy, why_h = available_drawbar_N(0.9, segs[0], model.tp, 1.8)
    weak, why_w = available_drawbar_N(0.9, segs[2], model.tp, 1.8)
    assert healthy == pytest.approx(345.0, abs=1.0) and why_h == "terrain"  # docs/model.md section 2 table
    F_n = 90 * 9.81 / 4
    T_rr = F_n * 0.265 * (0.1710 + 1.7096 * 0.1)
    assert weak == pytest.approx(4 * (25.0 - T_rr) / 0.265, rel=1e-6) and why_w == "motor"


@pytest.mark.parametrize(
    "targets, refs",
    [
        ({"link_forces_N": [30.0, -20.0, 10.0]}, [30.0, -20.0, 10.0]),
        ({"load_shares": "even"}, [50.0, 100.0, 150.0]),
        ({"load_shares": [0.1, 0.2, 0.3, 0.4]}, [20.0, 60.0, 120.0]),
        ({"net_connector_N": {1: 0.0}}, [200 / 3, 200 / 3, 400 / 3]),
        ({"net_connector_N": {0: 20.0, 2: -10.0}, "load_shares": "even"}, [-20.0, 85.0, 95.0]),
    ],
)
def test_target_conversion(targets, refs):
    raw = _raw("pi3_equal")
    raw["vehicle"]["segments"] = 4
    raw["mode"]["targets"] = targets
    raw["mode"]["free_segment"] = 2
    sc = scenario_from_dict(raw)
    res_plan = plan(sc.mode, sc, chain_model(sc))
    np.testing.assert_allclose(res_plan.link_ref_N, refs, atol=1e-9)
    assert res_plan.wheel_net_N.sum() == pytest.approx(200.0, abs=1e-9)
    # loops around the free segment 2: 0 and 1 hold the link behind, 3 the link ahead
    assert res_plan.fc_link[[0, 1, 3]].tolist() == [0, 1, 2]
    assert res_plan.fc_sigma[[0, 1, 3]].tolist() == [1.0, 1.0, -1.0]
    assert not res_plan.controlled[2]


@pytest.mark.parametrize("rule", ["drawbar", "inverse_slip"])
def test_share_rules_favour_the_stronger_segment(rule):
    # a heavier leader (more normal load) pulls more at less slip: it gets the larger share
    raw = _raw("pi3_equal")
    raw["vehicle"]["segment_overrides"] = {0: {"mass_kg": 120.0}}
    raw["mode"]["targets"] = {"load_shares": rule}
    sc = scenario_from_dict(raw)
    W = plan(sc.mode, sc, chain_model(sc)).wheel_net_N
    assert W.sum() == pytest.approx(200.0, abs=1e-9)
    assert W[1] == pytest.approx(W[2], rel=1e-9)
    assert W[0] > 1.05 * W[1]  # drawbar: 80 vs 60 N; inverse_slip: 70.6 vs 64.7 N
