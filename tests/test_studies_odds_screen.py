"""The steady screen of an odds study (snoworm/studies/odds/screen.py): the analytic P(go) of rolling on a
constant grade, the tables against snoworm.steady, steady against transient, the cached inching table."""

import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.stats import norm

from snoworm import load_scenario, steady
from snoworm.config.schema import ScenarioError
from snoworm.studies.odds import odds, screen
from snoworm.studies.odds.screen import XT_GRID, rolling_table


def _x_star(sc, grade_deg, wheel_speed):
    """The X_t at which a rolling segment's largest steady drawbar on the grade falls to zero (the steady map's
    stop of rolling without tow), by root finding on snoworm.steady directly."""
    seg, tp = sc.vehicle.segment_params()[0], sc.terrain.model.params()
    return brentq(lambda x: steady.max_drawbar_N(x, seg, tp, wheel_speed, grade_deg=grade_deg), 0.3, 1.0, xtol=1e-10)


@pytest.mark.parametrize("mu,sigma", [(0.75, 0.04), (0.70, 0.06)])
def test_rolling_on_a_constant_grade_agrees_with_the_normal_tail(mu, sigma):
    """Rolling on climb's 10 deg grade with X_t ~ Normal(mu, sigma) constant along the route: p_go's 95 % interval
    holds 1 - Phi((x* - mu) / sigma)."""
    sc = load_scenario("climb")
    xs = _x_star(sc, 10.0, 1.0)
    p = 1 - norm.cdf((xs - mu) / sigma)
    res = odds(
        "climb",
        vary=[f"terrain.xt=normal:{mu}:{sigma}"],
        samples=400,
        seed=11,
        strategies=["rolling"],
        rolling_speed=1.0,
        fidelity="steady",
        goal_m=20.0,
        progress=False,
    )
    st = res.summary["strategies"]["rolling"]
    assert st["n"] == 400
    assert st["p_go_ci"][0] <= p <= st["p_go_ci"][1], (p, st)
    # every draw above x* (beyond the table's interpolation, 1e-3 in X_t) gets through, every one below stops
    for r in res.rows:
        if abs(r["terrain.xt"] - xs) > 1e-3:
            assert r["go"] == int(r["terrain.xt"] > xs)


def test_rolling_table_interpolates_snoworm_steady():
    """At the grid nodes the table is steady.max_drawbar_N; between them it errs by at most h^2/8 max|D''|
    (linear interpolation), D'' estimated by differences on a grid ten times finer."""
    sc = load_scenario("climb")
    seg, tp = sc.vehicle.segment_params()[0], sc.terrain.model.params()
    tab = rolling_table(seg, tp, 6, 0.0, 1.0, np.array([10.0]))
    nodes = XT_GRID[::9]
    exact = [steady.max_drawbar_N(x, seg, tp, 1.0, grade_deg=10.0) for x in nodes]
    assert np.allclose(tab.drawbar(nodes, np.full(nodes.shape, 10.0)), exact, rtol=1e-12)
    fine = np.linspace(0.5, 0.9, 401)
    D = np.array([steady.max_drawbar_N(x, seg, tp, 1.0, grade_deg=10.0) for x in fine])
    d2 = np.max(np.abs(np.diff(D, 2))) / (fine[1] - fine[0]) ** 2
    h = XT_GRID[1] - XT_GRID[0]
    err = np.max(np.abs(tab.drawbar(fine, np.full(fine.shape, 10.0)) - D))
    assert err <= 1.05 * h * h / 8 * d2


def test_steady_and_transient_agree_far_from_the_threshold():
    """X_t well above and below x* (about 0.72 on climb's 10 deg at 1 m/s): the screen and the simulation
    give the same go/stop, and the screen's time to the end lies within 25 % of the simulated one (the
    screen leaves out the start-up)."""
    kw = dict(strategies=["rolling"], rolling_speed=1.0, goal_m=3.0, samples=1, progress=False)
    for xt, go in ((0.9, 1), (0.6, 0)):
        v = [f"terrain.xt=normal:{xt}:1e-9"]
        s = odds("climb", vary=v, fidelity="steady", **kw).rows[0]
        t = odds("climb", vary=v, sets=["simulation.duration_s=8"], fidelity="transient", **kw).rows[0]
        assert s["go"] == t["go"] == go
        if go:
            assert s["time_s"] == pytest.approx(t["time_s"], rel=0.25)


def test_steady_needs_the_end_of_the_route():
    with pytest.raises(ScenarioError, match="--goal-m"):
        odds(
            "climb",
            vary=["terrain.xt=normal:0.8:0.05"],
            samples=2,
            strategies=["rolling"],
            rolling_speed=1.0,
            fidelity="steady",
            progress=False,
        )


def test_inching_table_is_computed_once_and_cached_in_the_folder(tmp_path, monkeypatch):
    """The inching table's runs go once; the table is written to inching_table.json with its key and read
    back from there (no simulation) by the next study in the folder with the same inputs."""
    monkeypatch.setattr(screen, "INCH_XT", (0.5, 0.9))
    monkeypatch.setattr(screen, "INCH_TABLE_S", 3.0)
    screen._MEMO.clear()
    kw = dict(
        vary=["terrain.xt=normal:0.8:0.02"],
        samples=4,
        strategies=["inching"],
        goal_m=1.0,
        fidelity="steady",
        progress=False,
        plot=False,
    )
    first = odds("climb", out_dir=tmp_path / "a", **kw)
    doc = json.loads((tmp_path / "a" / "inching_table.json").read_text())
    assert doc["xt"] == [0.5, 0.9] and len(doc["speed_mps"]) == 2
    assert doc["speed_mps"][1][0] > 0.05  # the gait climbs 10 deg on X_t 0.9
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "inching_table.json").write_text((tmp_path / "a" / "inching_table.json").read_text())
    screen._MEMO.clear()

    def no_runs(*a, **k):
        raise AssertionError("the cached table should be read, not simulated again")

    monkeypatch.setattr(screen, "simulate", no_runs)
    again = odds("climb", out_dir=tmp_path / "b", overwrite=True, **kw)
    assert [r["go"] for r in again.rows] == [r["go"] for r in first.rows]
    assert all(math.isfinite(r["time_s"]) for r in first.rows if r["go"])


def test_supervisor_screen_moves_wherever_rolling_or_inching_moves(monkeypatch):
    """weak_climb, the same draws: the supervisor's screen gets through whenever rolling or inching does, and
    no slower than inching alone (it rolls, faster, wherever rolling works)."""
    monkeypatch.setattr(screen, "INCH_XT", (0.5, 0.9))
    monkeypatch.setattr(screen, "INCH_TABLE_S", 3.0)
    screen._MEMO.clear()
    res = odds(
        "weak_climb",
        samples=30,
        seed=4,
        strategies=["rolling", "inching", "supervisor"],
        fidelity="steady",
        progress=False,
    )
    by = {}
    for r in res.rows:
        by.setdefault(r["draw"], {})[r["strategy"]] = r
    assert any(not d["rolling"]["go"] for d in by.values())  # the draws test something
    for d in by.values():
        assert d["supervisor"]["go"] >= max(d["rolling"]["go"], d["inching"]["go"])
        if d["supervisor"]["go"] and d["inching"]["go"]:
            assert d["supervisor"]["time_s"] <= d["inching"]["time_s"] + 1e-9
    screen._MEMO.clear()
