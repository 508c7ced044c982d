"""Beyond the paper: terrain along the route, supervisor switching, energy, mobility map (issue 8)."""
import json

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from snoworm import steady
from snoworm.cli import main
from snoworm.energy import energy_balance, energy_metrics
from snoworm.mobility import mobility_map
from snoworm.scenario import ScenarioError, load_scenario, scenario_from_dict
from snoworm import simulate

PATCH_START_M, PATCH_END_M, PATCH_RAMP_M = 8.0, 18.0, 0.5
UNIFORM = 'mode={type: uniform, speed_mps: 1.8, start_time_s: 0.5}'


@pytest.fixture(scope="module")
def traverse():
    """traverse_patch with the supervisor, long enough to leave the patch (~30 s wall time)."""
    from tests.conftest import SCENARIOS
    sc = load_scenario(SCENARIOS / "traverse_patch.yaml", ["simulation.duration_s=92", "simulation.output_dt_s=0.1"])
    return simulate(sc)


@pytest.fixture(scope="module")
def stuck():
    """The same vehicle and route, rolling only (uniform mode)."""
    from tests.conftest import SCENARIOS
    sc = load_scenario(SCENARIOS / "traverse_patch.yaml", [UNIFORM, "simulation.duration_s=30",
                                                           "simulation.output_dt_s=0.01"])
    return simulate(sc)


def _base(**terrain):
    from tests.conftest import SCENARIOS
    raw = yaml.safe_load((SCENARIOS / "traverse_patch.yaml").read_text())
    raw["terrain"] = terrain
    return raw


# ------------------------------------------------------------------ terrain along the route

def test_patches_compile_to_one_profile():
    sc = scenario_from_dict(_base(xt=0.9, patches=[{"start_m": 8, "end_m": 18, "xt": 0.3, "ramp_m": 0.5},
                                                   {"start_m": 30, "end_m": 31, "xt": 0.5}]))
    p = sc.terrain.compile()
    X = p(np.array([0.0, 7.5, 7.75, 8.0, 13.0, 18.0, 18.25, 18.5, 25.0, 30.5, 29.998, 40.0]))
    np.testing.assert_allclose(X, [0.9, 0.9, 0.6, 0.3, 0.3, 0.3, 0.6, 0.9, 0.9, 0.5, 0.9, 0.9], atol=1e-3)
    # the chain model evaluates the same table (one evaluation path)
    assert sc.chain_model.profile == p


def test_random_profile_reproducible_and_seeded():
    spec = {"mean": 0.6, "std": 0.15, "correlation_length_m": 5.0, "seed": 7, "length_m": 2000.0, "min_xt": 0.1}
    a = scenario_from_dict(_base(random=spec)).terrain.compile()
    b = scenario_from_dict(_base(random=dict(spec))).terrain.compile()
    c = scenario_from_dict(_base(random={**spec, "seed": 8})).terrain.compile()
    assert a == b                                     # same seed: identical table
    va, vc = np.array(a.values), np.array(c.values)
    assert va.shape == vc.shape and np.max(np.abs(va - vc)) > 0.1    # another seed: another profile
    assert va.min() >= 0.1                             # clipped, X_t > 0
    # 400 correlation lengths: sampling error of the mean ~0.01 (tolerance 0.04), of the std ~7 % (tolerance 25 %)
    assert abs(va.mean() - 0.6) < 0.04 and abs(va.std() - 0.15) < 0.25 * 0.15
    # correlation at one correlation length ~ 1/e (sampling error ~0.07, tolerance 0.15)
    x = va - va.mean()
    lag = 8                                            # grid spacing is correlation_length_m / 8
    assert abs(np.corrcoef(x[:-lag], x[lag:])[0, 1] - np.exp(-1)) < 0.15


@pytest.mark.parametrize("terrain, match", [
    ({"xt": 0.9, "patches": [{"start_m": 5, "end_m": 5, "xt": 0.3}]}, "end_m: must be greater than start_m"),
    ({"xt": 0.9, "patches": [{"start_m": 5, "end_m": 8, "xt": 0.0}]}, r"patches\[0\]\.xt: must be greater than 0"),
    ({"xt": 0.9, "patches": [{"start_m": 5, "end_m": 8, "xt": 0.3, "ramp_m": 1},
                             {"start_m": 9, "end_m": 12, "xt": 0.3}]}, r"patches\[1\]: overlaps patches\[0\]"),
    ({"xt": 0.9, "patches": [{"start_m": 5, "end_m": 8, "xt": 0.3, "ramp": 1}]}, "Did you mean 'ramp_m'"),
    ({"xt": 0.9, "patches": [{"start_m": 5, "end_m": 8, "xt": 0.3, "ramp_m": -1}]}, "ramp_m: must be at least 0"),
    ({"profile": [[0, 0.9], [5, 0.3]], "patches": []}, "patches lie on a base X_t"),
    ({"xt": 0.9, "random": {"mean": 0.6, "std": 0.1, "correlation_length_m": 5, "seed": 1, "length_m": 50}},
     "give exactly one of 'xt'"),
    ({"random": {"mean": 0.6, "std": -0.1, "correlation_length_m": 5, "seed": 1, "length_m": 50}},
     r"random\.std: must be at least 0"),
    ({"random": {"mean": 0.6, "std": 0.1, "correlation_length_m": 0, "seed": 1, "length_m": 50}},
     r"random\.correlation_length_m: must be greater than 0"),
    ({"random": {"mean": 0.6, "std": 0.1, "correlation_length_m": 5, "length_m": 50}}, r"random\.seed: is required"),
    ({"random": {"mean": 0.6, "std": 0.1, "correlation_length_m": 5, "seed": 1.5, "length_m": 50}},
     "whole number"),
    ({"random": {"mean": 0.6, "std": 0.1, "correlation_length_m": 1e-4, "seed": 1, "length_m": 50}},
     "200000 grid points"),
])
def test_terrain_validation_errors(terrain, match):
    with pytest.raises(ScenarioError, match=match):
        scenario_from_dict(_base(**terrain))


def test_supervisor_validation_errors():
    raw = _base(xt=0.9)
    raw["mode"]["inching"] = {**raw["mode"]["inching"], "start_time_s": 1.0}
    with pytest.raises(ScenarioError, match=r"mode\.inching\.start_time_s: not allowed here"):
        scenario_from_dict(raw)
    raw = _base(xt=0.9)
    raw["vehicle"]["links"] = {"type": "fixed"}
    with pytest.raises(ScenarioError, match="must be 'prismatic' for the gait"):
        scenario_from_dict(raw)


# ------------------------------------------------------------------ supervisor on traverse_patch

def test_rolling_alone_stays_stuck_in_patch(stuck):
    x = stuck.segments["x_m"]
    t = stuck.t
    assert PATCH_START_M < x[-1, 0] < PATCH_END_M                 # leader stopped inside the patch
    late = t >= t[-1] - 10.0
    v_mean = (x[late][-1].mean() - x[late][0].mean()) / 10.0
    assert abs(v_mean) < 0.01                                     # no progress over the last 10 s [m/s]
    assert stuck.segments["slip"][-1, 0] > 0.9                    # the leader's wheels spin


def test_supervisor_switches_in_the_patch_and_back(traverse):
    sw = [e for e in traverse.events if e["kind"].startswith("switch_")]
    assert [e["kind"] for e in sw] == ["switch_to_inching", "switch_to_rolling"]
    to_inch, to_roll = sw
    assert PATCH_START_M < to_inch["x_m"] < PATCH_END_M          # leader inside the patch when stuck
    assert to_roll["x_m"] > PATCH_END_M + PATCH_RAMP_M           # leader past the patch when rolling resumes
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
    p = plotting.plot_positions(traverse, tmp_path / "positions.png")
    assert p.stat().st_size > 10000
    e = energy_metrics(traverse)
    assert e["total_electrical_J"] == pytest.approx(e["motor_electrical_total_J"] + e["joint_electrical_total_J"],
                                                    rel=1e-12)
    # electrical >= mechanical (drivetrain efficiency 0.8, joint efficiency 0.7)
    assert e["motor_electrical_total_J"] >= sum(e["motor_mechanical_J"]) / 0.8 * 0.999
    mass = 6 * 90.0
    assert e["cost_of_transport"] == pytest.approx(e["total_electrical_J"] / (mass * 9.81 * e["distance_m"]), rel=1e-12)
    assert traverse.summary()["energy_metrics"]["energy_per_metre_J_per_m"] == pytest.approx(
        e["total_electrical_J"] / e["distance_m"], rel=1e-12)


# ------------------------------------------------------------------ energy balance

def test_energy_balance_rolling(stuck):
    """Rolling into the patch and spinning there: residual below 0.5 % of the motor work.

    Tolerance: the wheel kinetic energy uses the mean of the two axles' speeds (they differ while
    a segment straddles the patch edge) and the trapezoidal rule on 10 ms output samples.
    """
    b = energy_balance(stuck)
    assert b["motor_J"] > 5e4
    assert abs(b["residual_J"]) < 5e-3 * b["throughput_J"]


def test_energy_balance_inching(scenario_path):
    """Inching on X_t = 0.25 (paper Fig 5): motor + joint work = dissipation + stored, within 0.5 %."""
    sc = load_scenario(scenario_path("inchworm6"), ["simulation.duration_s=5", "simulation.output_dt_s=0.005"])
    res = simulate(sc)
    b = energy_balance(res)
    assert b["joint_J"] > 300 and b["motor_J"] > 300      # both sources matter
    assert abs(b["residual_J"]) < 5e-3 * b["throughput_J"]
    e = energy_metrics(res)
    assert e["joint_electrical_total_J"] == pytest.approx(sum(e["joint_mechanical_J"]) / 0.7, rel=1e-12)


# ------------------------------------------------------------------ mobility map

def test_map_rolling_boundary_matches_steady_limit(scenario_path):
    sc = load_scenario(scenario_path("traverse_patch"))
    xts = np.linspace(0.2, 1.0, 33)                     # grid step 0.025
    dx = xts[1] - xts[0]
    m = mobility_map(sc, xts, [0.0, 200.0], wheel_speed_mps=1.8, inching=False)
    for tow, expected in ((0.0, 0.586), (200.0, m["rolling_limit_xt"][200.0])):
        roll = [r["xt"] for r in m["rows"] if r["tow_N"] == tow and r["rolling"]]
        first = min(roll)
        assert first - dx < expected <= first + 1e-12              # boundary within one grid step
        assert all(x >= first for x in roll) and len(roll) == sum(xts >= first - 1e-12)   # one boundary
    # MODEL.md section 2: 0.586 without tow; a 200 N tow (33 N per segment) raises it
    assert m["rolling_limit_xt"][0.0] == pytest.approx(0.586, abs=5e-4)
    seg = sc.vehicle.segment_params()[0]
    assert m["rolling_limit_xt"][200.0] == pytest.approx(
        steady.immobilisation_limit_xt(seg, sc.chain_model.tp, drawbar_N=200.0 / 6, wheel_speed_mps=1.8), abs=1e-9)
    assert m["rolling_limit_xt"][200.0] > m["rolling_limit_xt"][0.0] + 0.01


def test_cli_mobility_map_regions(scenario_path, tmp_path):
    r = CliRunner().invoke(main, ["mobility-map", str(scenario_path("traverse_patch")), "--xt", "0.3,0.9",
                                  "--tow", "0", "--inch-duration", "4", "--out", str(tmp_path)])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "mobility_map.png").stat().st_size > 10000
    lines = (tmp_path / "mobility_map.csv").read_text().splitlines()
    rows = [dict(zip(lines[0].split(","), ln.split(","))) for ln in lines[1:]]
    assert [(float(x["xt"]), x["region"]) for x in rows] == [(0.3, "inching only"), (0.9, "rolling")]
    assert float(rows[0]["inching_speed_mps"]) > 0.02
    assert float(rows[1]["rolling_speed_mps"]) == pytest.approx(1.8 * (1 - 0.039), abs=0.01)   # slip 3.9 %


def test_cli_mobility_map_bad_grid(scenario_path, tmp_path):
    r = CliRunner().invoke(main, ["mobility-map", str(scenario_path("traverse_patch")), "--xt", "0.2:1.0",
                                  "--out", str(tmp_path)])
    assert r.exit_code == 2 and "START:STOP:COUNT" in r.output
