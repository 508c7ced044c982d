"""One draw of an odds study (snoworm/studies/odds/outcome.py): strategies, the end of the route, the X_t
field around the route, and the outcome of a run (sd -> 0 reproduces the deterministic run)."""

import numpy as np
import pytest

from snoworm import load_scenario, simulate
from snoworm.config.scenario import read_scenario_yaml
from snoworm.config.schema import ScenarioError
from snoworm.studies.odds import odds
from snoworm.studies.odds.inputs import XT_FIELD_FLOOR, XtField
from snoworm.studies.odds.outcome import _leader_crossing, draw_scenario, goal_of, strategy_raw


def _raw(name):
    raw, path = read_scenario_yaml(name)
    return raw, str(path.parent)


def test_strategies_map_to_modes():
    raw, _ = _raw("traverse_patch")
    sc = load_scenario("traverse_patch")
    r = strategy_raw(raw, sc, "rolling")["mode"]
    assert r == {"type": "uniform", "speed_mps": 1.8, "start_time_s": 0.5}
    i = strategy_raw(raw, sc, "inching")["mode"]
    assert i["type"] == "inchworm" and i["gait"] == "six_segment" and i["start_time_s"] == 0.5
    assert strategy_raw(raw, sc, "supervisor")["mode"]["type"] == "supervisor"
    craw, _ = _raw("climb")
    csc = load_scenario("climb")
    with pytest.raises(ScenarioError, match="--rolling-speed"):
        strategy_raw(craw, csc, "rolling")
    assert strategy_raw(craw, csc, "rolling", 1.2)["mode"]["speed_mps"] == 1.2
    with pytest.raises(ScenarioError, match="whose mode is 'supervisor'"):
        strategy_raw(craw, csc, "supervisor")


def test_the_end_of_the_route():
    ramp = load_scenario("ramp_drift")
    assert goal_of(ramp) == ramp.terrain.route_data().distance_m[-1]
    assert goal_of(ramp, 50.0) == 50.0
    assert goal_of(load_scenario("climb")) is None


def test_leader_crossing_is_linear_between_samples():
    t = np.array([0.0, 1.0, 2.0, 3.0])
    x = np.array([0.0, 0.5, 1.5, 1.6])
    assert _leader_crossing(t, x, 1.0) == pytest.approx(1.5)
    assert _leader_crossing(t, x, 2.0) is None


def test_field_is_added_around_the_route_xt_and_keeps_the_elevation():
    """On ramp_drift (a route file), a draw's X_t is the route's X_t plus the field (its sd within sampling
    error over ~1500 grid points of ~60 correlation lengths), clipped to [0.05, 1]; the elevation is the route's."""
    raw, base = _raw("ramp_drift")
    sc0 = load_scenario("ramp_drift")
    f = XtField(0.05, 5.0)
    sc = draw_scenario(raw, {}, f, 123, goal_of(sc0), base_dir=base)
    assert sc.terrain.route is None and sc.terrain.profile is not None
    x = np.linspace(0, 200, 2001)
    assert np.allclose(sc.terrain.elevation_profile().elevation(x), sc0.terrain.elevation_profile().elevation(x))
    dev = sc.terrain.compile()(x) - sc0.terrain.compile()(x)
    assert 0.03 < np.std(dev) < 0.07 and abs(np.mean(dev)) < 0.03
    again = draw_scenario(raw, {}, f, 123, goal_of(sc0), base_dir=base)
    assert again.terrain.profile == sc.terrain.profile
    wild = draw_scenario(raw, {}, XtField(0.4, 5.0), 1, goal_of(sc0), base_dir=base)
    v = np.array(wild.terrain.profile)[:, 1]
    assert v.min() >= XT_FIELD_FLOOR and v.max() <= 1.0 and (v == 1.0).any()


def test_sd_to_zero_reproduces_the_deterministic_run():
    """odds with sd 1e-9 (and a field of sd 1e-9) gives the deterministic run's outcome, time and energy per
    metre, computed here from a plain run: the crossing time by linear interpolation of the leader's position,
    the energy from Result.energy_along.  Tolerance 1e-4 relative: ten times the scenario's rtol (1e-5), as the
    1e-9 change of X_t may change the solver's steps."""
    sets = ["simulation.duration_s=6", "terrain.xt=0.85"]
    res = odds(
        "climb",
        vary=["terrain.xt=normal:0.85:1e-9"],
        xt_field="sd=1e-9,corr=5",
        sets=sets[:1],
        samples=1,
        strategies=["rolling"],
        rolling_speed=1.0,
        goal_m=2.0,
        progress=False,
    )
    row = res.rows[0]
    sc = load_scenario("climb", sets + ["mode={type: uniform, speed_mps: 1.0, start_time_s: 0.5}"])
    r = simulate(sc)
    lead = r.segments["x_m"][:, 0]
    j = int(np.argmax(lead >= 2.0))
    t_goal = r.t[j - 1] + (2.0 - lead[j - 1]) / (lead[j] - lead[j - 1]) * (r.t[j] - r.t[j - 1])
    e = np.interp(t_goal, r.energy_along()["t_s"], r.energy_along()["total_electrical_J"])
    assert row["go"] == 1 and row["verdict"] == "reached_end"
    assert row["time_s"] == pytest.approx(t_goal, rel=1e-4)
    assert row["energy_per_m_J"] == pytest.approx(e / 2.0, rel=1e-4)
    assert row["speed_made_good_mps"] == pytest.approx(2.0 / t_goal, rel=1e-4)
    assert res.summary["strategies"]["rolling"]["p_go"] == 1.0
