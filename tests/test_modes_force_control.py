"""Force-control mode (paper section 5.2, Figs 8-11; docs/model.md section 5).

Steady states are checked against the force balance of docs/model.md section 5 and the one-segment
steady-state solver; forces within 2 N, set-points within 5 mm/s (the steady solver's
predictions agree with the simulation to < 1e-4 m/s; the tolerance leaves room for solver
settings).
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from snoworm import simulate
from snoworm.cli import main
from snoworm.config.scenario import ScenarioError, dump_scenario, load_scenario, scenario_from_dict

SCEN = Path(__file__).resolve().parent.parent / "scenarios"
F_TOL_N = 2.0
V_TOL_MPS = 5e-3


def _run(name, overrides=()):
    return simulate(load_scenario(SCEN / f"{name}.yaml", overrides))


def _final(res, window_s=0.5):
    """Means over the last ``window_s`` seconds: link forces, wheel nets, set-points, connector nets."""
    last = res.t >= res.t[-1] - window_s
    return (
        res.links["force_N"][last].mean(0),
        res.segments["net_force_N"][last].mean(0),
        res.segments["speed_setpoint_mps"][last].mean(0),
        res.segments["connector_net_N"][last].mean(0),
    )


def _raw(name):
    return yaml.safe_load((SCEN / f"{name}.yaml").read_text())


@pytest.fixture(scope="module")
def runs():
    return {n: _run(n) for n in ("pi2_zero", "pi3_equal", "pi3_middle_positive", "tow6_weak_segment")}


# ---------------------------------------------------------------- steady states (docs/model.md 5)
def test_fig8_leader_zeroes_link_force(runs):
    T, W, sp, _ = _final(runs["pi2_zero"])
    assert abs(T[0]) < F_TOL_N
    assert W[1] == pytest.approx(200.0, abs=F_TOL_N)  # the rear carries the whole tow
    assert sp[0] == pytest.approx(1.679, abs=V_TOL_MPS)  # docs/model.md section 5, Fig 8
    assert sp[1] == pytest.approx(1.8, abs=1e-9)  # the free rear segment at its nominal speed


def test_fig9_10_equal_links_middle_slowest(runs):
    T, W, sp, C = _final(runs["pi3_equal"])
    np.testing.assert_allclose(T, [100.0, 100.0], atol=F_TOL_N)
    np.testing.assert_allclose(W, [100.0, 0.0, 100.0], atol=F_TOL_N)
    np.testing.assert_allclose(sp, [1.800, 1.747, 1.800], atol=V_TOL_MPS)
    assert np.argmin(sp) == 1
    assert abs(C[1]) < F_TOL_N  # zero net connector force on the middle


def test_fig11_middle_positive_connector_force(runs):
    T, W, sp, C = _final(runs["pi3_middle_positive"])
    np.testing.assert_allclose(T, [50.0, -50.0], atol=F_TOL_N)
    np.testing.assert_allclose(W, [50.0, -100.0, 250.0], atol=F_TOL_N)
    assert C[1] > 90.0  # pulled ahead and pushed from behind: +100 N
    assert np.argmin(sp) == 1


def test_predicted_steady_state_matches_simulation(runs):
    for name, res in runs.items():
        fc = res.mode_summary["force_control"]
        _, W, sp, _ = _final(res)
        np.testing.assert_allclose(sp, fc["predicted_setpoints_mps"], atol=V_TOL_MPS, err_msg=name)
        np.testing.assert_allclose(W, fc["wheel_net_targets_N"], atol=F_TOL_N, err_msg=name)
        assert fc["saturated_at_end"] == [], name


def test_setpoints_within_limits(runs):
    for name, res in runs.items():
        sp = res.segments["speed_setpoint_mps"]
        vmax = 0.265 * 18.326  # default v_max: the no-load wheel speed
        assert sp.min() >= 0.0, name
        assert sp.max() <= vmax + 1e-9, name


def test_weak_segment_is_relieved(runs):
    res = runs["tow6_weak_segment"]
    T, W, _, _ = _final(res)
    others = np.delete(W, 2)
    assert W[2] < 0.5 * others.min()  # the weakened segment carries much less
    assert W[2] == pytest.approx(200.0 * 75.44 / (5 * 345.42 + 75.44), abs=F_TOL_N)
    np.testing.assert_allclose(others, others.mean(), atol=F_TOL_N)
    assert W.sum() == pytest.approx(200.0, abs=F_TOL_N)  # the tow is carried in full
    fc = res.mode_summary["force_control"]
    assert fc["drawbar_limited_by"][2] == "motor" and fc["drawbar_limited_by"][0] == "terrain"


def test_weak_segment_settles_within_duration(runs):
    res = runs["tow6_weak_segment"]
    ref = np.array(res.mode_summary["force_control"]["link_force_refs_N"])
    late = res.t >= 10.0  # start at 1 s; settled by 10 s
    assert np.max(np.abs(res.links["force_N"][late] - ref)) < F_TOL_N


def test_solver_work_is_bounded(runs):
    # a slowdown (e.g. a loop that chatters) fails here without timing anything
    assert runs["pi3_equal"].stats["nfev"] < 5000
    assert runs["tow6_weak_segment"].stats["nfev"] < 10000


# ---------------------------------------------------------------- limits (conversions: test_modes_force_plan.py)
def test_saturation_reported():
    # the rear's motors stay off: the tow tensions the link, and the leader could zero it only by
    # driving backwards, so its set-point is pinned at 0 (paper Fig 8: "constrained to positive values")
    res = _run("pi2_zero", [("mode.start_time_s", [1.0, 10.0]), ("simulation.duration_s", 5.0)])
    fc = res.mode_summary["force_control"]
    assert fc["saturated_at_end"] == [{"segment": 0, "at": "zero"}]
    assert fc["saturation"][0]["fraction_at_zero"] > 0.5
    assert res.segments["speed_setpoint_mps"].min() >= 0.0


# ---------------------------------------------------------------- errors (exit 2)
def test_impossible_target_exit_2(tmp_path):
    runner = CliRunner()
    out = tmp_path / "out"
    r = runner.invoke(main, ["run", str(SCEN / "pi2_zero.yaml"), "--out", str(out), "--set", "tow.force_N=400"])
    assert r.exit_code == 2
    assert "impossible target" in r.output and "segment 1" in r.output and "345" in r.output
    assert not out.exists()
    r = runner.invoke(
        main, ["validate", str(SCEN / "pi3_equal.yaml"), "--set", "mode.targets.net_connector_N={1: -400}"]
    )
    assert r.exit_code == 2
    assert "mode.targets" in r.output and "impossible target" in r.output


def test_tow_beyond_whole_chain_exit_2():
    r = CliRunner().invoke(main, ["validate", str(SCEN / "pi3_equal.yaml"), "--set", "tow.force_N=1100"])
    assert r.exit_code == 2
    assert "whole chain" in r.output and "tow.force_N" in r.output


def test_resolved_scenario_round_trip(tmp_path, runs):
    # the scenario.yaml written with the results re-validates to the same configuration
    for name, res in runs.items():
        path = tmp_path / f"{name}.yaml"
        path.write_text(dump_scenario(res.scenario))
        assert load_scenario(path).mode == res.scenario.mode, name


def test_setpoint_above_vmax_exit_2():
    r = CliRunner().invoke(main, ["validate", str(SCEN / "pi3_equal.yaml"), "--set", "mode.max_speed_mps=1.75"])
    assert r.exit_code == 2
    assert "max_speed_mps" in r.output


@pytest.mark.parametrize(
    "change, words",
    [
        (
            lambda m: m["targets"].update(link_force_N=[1, 2]),
            ["mode.targets.link_force_N", "unknown key", "link_forces_N"],
        ),
        (lambda m: m.update(kp=1.0), ["mode.kp", "unknown key"]),
        (
            lambda m: m["targets"].update(net_connector_N=None, link_forces_N=[100.0]),
            ["link_forces_N", "2 for 3 segments"],
        ),
        (lambda m: m["targets"].update(net_connector_N=None, load_shares=[0.5, 0.5]), ["load_shares", "(3)"]),
        (lambda m: m["targets"].update(net_connector_N=None, load_shares=[0.5, 0.3, 0.3]), ["sum to 1"]),
        (lambda m: m["targets"].update(net_connector_N=None, load_shares="evn"), ["unknown rule", "'even'"]),
        (lambda m: m.update(targets={}), ["give a target"]),
        (lambda m: m["targets"].update(link_forces_N=[1, 2]), ["cannot be combined"]),
        (lambda m: m.update(free_segment=3), ["free_segment", "0..2"]),
        (lambda m: m.update(speed_mps=[1.8, 1.8]), ["speed_mps", "3"]),
        (lambda m: m["targets"].update(net_connector_N={5: 0}), ["net_connector_N.5", "out of range"]),
    ],
)
def test_config_validation(change, words):
    raw = _raw("pi3_equal")
    m = raw["mode"]
    change(m)
    for k in [k for k, v in m.get("targets", {}).items() if v is None]:
        del m["targets"][k]
    with pytest.raises(ScenarioError) as exc:
        scenario_from_dict(copy.deepcopy(raw))
    for w in words:
        assert w in str(exc.value)


def test_one_segment_rejected():
    raw = _raw("pi2_zero")
    raw["vehicle"]["segments"] = 1
    with pytest.raises(ScenarioError, match="at least 2 segments"):
        scenario_from_dict(raw)


def test_force_diagram_written(tmp_path, runs):
    paths = runs["pi3_equal"].write(tmp_path)
    names = {Path(p).name for p in paths}
    assert {"force_diagram.png", "forces.png", "speeds.png"} <= names
    assert (tmp_path / "force_diagram.png").stat().st_size > 10_000
