"""The verdict of a run (snoworm/results/verdict.py): moving, reached the end, immobilised.

Expectations come from the steady laws (snoworm.steady) and from the output series by hand, never
from the verdict's own computation.
"""

import dataclasses

import numpy as np
import pytest

from snoworm import ScenarioError, load_scenario, scenario_from_dict, simulate, steady
from snoworm.results.verdict import IMMOBILISED_SIGN_FACTOR, IMMOBILISED_SPEED_MPS, criteria_of, goal_of, verdict
from tests.conftest import SCENARIOS, shipped_result

PATCH_START_M, PATCH_END_M, PATCH_XT, FIRM_XT = 15.0, 60.0, 0.35, 0.9
WHEEL_SPEED_MPS = 1.8


def rolling_raw(segments=3, duration_s=30.0, **terrain):
    """Uniform rolling at 1.8 m/s of FrostyBoy segments on fixed links (terrain: the ``terrain`` keys)."""
    return {
        "name": "verdict_case",
        "vehicle": {"parameter_set": "frostyboy", "segments": segments, "links": {"type": "fixed"}},
        "terrain": terrain or {"xt": FIRM_XT},
        "tow": {"force_N": 0},
        "mode": {"type": "uniform", "speed_mps": WHEEL_SPEED_MPS, "start_time_s": 0.5},
        "simulation": {"duration_s": duration_s, "output_dt_s": 0.05},
    }


@pytest.fixture(scope="module")
def patch_run():
    """Three segments rolling from firm snow (X_t 0.9) into a long weak patch (X_t 0.35 < 0.586)."""
    raw = rolling_raw(xt=FIRM_XT, patches=[{"start_m": PATCH_START_M, "end_m": PATCH_END_M, "xt": PATCH_XT}])
    return simulate(scenario_from_dict(raw))


def steady_stop_leader_m(res):
    """Where the steady laws say the chain must stop: the first leader position at which the
    chain's largest steady pull, the sum over its axles of max_drawbar_N(X_t under the axle) / 2
    (an axle carries half a segment), is no longer positive."""
    sc = res.scenario
    seg, tp = sc.vehicle.segment_params()[0], sc.terrain.model.params()
    offsets = res.segments["x_m"][0] - res.segments["x_m"][0, 0]  # fixed links: the chain's shape
    half = seg.wheelbase_m / 2.0
    pull = {X: steady.max_drawbar_N(X, seg, tp, WHEEL_SPEED_MPS) for X in (PATCH_XT, FIRM_XT)}
    assert pull[PATCH_XT] < 0 < pull[FIRM_XT]  # the patch is below the rolling limit, the firm snow above
    for s in np.arange(0.0, PATCH_END_M, 0.005):
        axles = np.concatenate([s + offsets + half, s + offsets - half])
        inside = (axles >= PATCH_START_M) & (axles <= PATCH_END_M)
        total = sum(pull[PATCH_XT] if k else pull[FIRM_XT] for k in inside) / 2.0
        if total <= 0:
            return s
    raise AssertionError("the chain never stops")


def test_a_weak_patch_immobilises_the_chain_where_the_steady_limit_says(patch_run):
    v = verdict(patch_run)
    assert v.status == "immobilised" and v.cause == "slip"
    spacing = -np.diff(patch_run.segments["x_m"][0]).max()  # one segment length of the chain
    stop = steady_stop_leader_m(patch_run)
    assert abs(v.x_m - stop) <= spacing, (v.x_m, stop)
    # x is the leader's position at t; X_t, grade and slip are the chain's there
    k = int(np.searchsorted(patch_run.t, v.t_s))
    assert patch_run.t[k] == v.t_s
    assert v.x_m == patch_run.segments["x_m"][k, 0]
    assert v.xt == pytest.approx(np.mean(patch_run.segments["xt"][k]), abs=1e-12)
    assert PATCH_XT < v.xt < FIRM_XT  # the chain straddles the patch's edge
    assert v.grade_deg == 0.0
    # the chain's slip 1 - progress / driven travel: the wheels spin (Eq. 1 slip near 1 on every segment)
    window = (patch_run.t >= v.t_s) & (patch_run.t <= v.t_s + v.criteria.window_s)
    assert v.slip > v.criteria.slip
    assert v.slip == pytest.approx(np.mean(patch_run.segments["slip"][window]), abs=0.05)
    # after t the chain stays put (less than the stall speed times the rest of the run)
    centre = patch_run.segments["x_m"].mean(axis=1)
    assert centre[-1] - centre[k] < v.criteria.speed_mps * (patch_run.t[-1] - v.t_s)
    assert v.reason == (
        f"immobilised at x = {v.x_m:.1f} m, t = {v.t_s:.1f} s (X_t {v.xt:.2f}, grade 0.0 deg, slip {v.slip:.2f})"
    )
    assert v.immobilised_at_m == v.x_m


def test_the_stall_starts_where_the_chain_stops_advancing(patch_run):
    """t is the start of the first window of window_s over which the centre advances less than
    speed_mps per second: one output step earlier, the window still sees that much progress."""
    v = verdict(patch_run)
    t, centre = patch_run.t, patch_run.segments["x_m"].mean(axis=1)
    crit = v.criteria
    k = int(np.searchsorted(t, v.t_s))
    assert np.interp(t[k - 1] + crit.window_s, t, centre) - centre[k - 1] >= crit.speed_mps * crit.window_s
    assert np.interp(t[k] + crit.window_s, t, centre) - centre[k] < crit.speed_mps * crit.window_s


def test_a_level_run_is_moving():
    res = simulate(scenario_from_dict(rolling_raw(duration_s=12.0)))
    v = verdict(res)
    assert v.status == "moving"
    assert v.t_s == res.t[-1] and v.x_m == res.segments["x_m"][-1, 0]
    assert v.immobilised_at_m is None and v.xt is None and v.slip is None
    speed = np.mean(res.segments["x_m"][-1] - res.segments["x_m"][0]) / (res.t[-1] - res.t[0])
    assert v.reason == f"moving at the end (t = {res.t[-1]:.1f} s, x = {v.x_m:.1f} m, mean speed {speed:.2f} m/s)"


def test_rolling_on_weak_snow_is_immobilised_from_the_start():
    """rolling6_xt025 (X_t 0.25, below the rolling limit): the wheels spin from the moment the
    motors start (mode.start_time_s), which is when the chain is immobilised."""
    res = shipped_result("rolling6_xt025")
    v = verdict(res)
    assert v.status == "immobilised"
    start = max(res.scenario.mode.start_time_s)
    assert start <= v.t_s <= start + res.scenario.simulation.output_dt_s
    assert v.xt == pytest.approx(0.25)


def test_a_chain_whose_wheels_are_not_driven_is_not_immobilised():
    """The same chain on the same snow with its motors never started stands still: not driven, so
    not immobilised (a parked chain)."""
    sc = load_scenario(SCENARIOS / "rolling6_xt025.yaml", ["mode.start_time_s=40", "simulation.duration_s=10"])
    res = simulate(sc)
    assert np.max(np.abs(res.segments["x_m"][-1] - res.segments["x_m"][0])) < 1e-6
    assert verdict(res).status == "moving"


def test_a_slow_command_followed_is_not_a_stall():
    """Commanded at 0.03 m/s on firm snow the chain advances less than speed_mps (0.05 m/s) per
    second, but covers nearly all of its wheels' travel: slow, not stuck."""
    raw = rolling_raw(segments=2, duration_s=12.0)
    raw["mode"]["speed_mps"] = 0.03
    res = simulate(scenario_from_dict(raw))
    centre = res.segments["x_m"].mean(axis=1)
    late = (centre[-1] - centre[-101]) / (res.t[-1] - res.t[-101])  # the last 5 s
    assert 0 < late < criteria_of(res.scenario).speed_mps  # a speed-only rule would call it stuck
    assert verdict(res).status == "moving"


def test_an_inching_gait_that_progresses_is_not_immobilised():
    """inchworm2 holds each segment still (its anchor even slides back a little) for a whole
    phase (about 1.2 s) by design; judged on the chain's centre against the wheels' driven travel,
    even a window shorter than a phase finds it moving.  The same chain rolling on the same snow
    (X_t 0.4, below the rolling limit) is immobilised."""
    res = shipped_result("inchworm2")
    t, x = res.t, res.segments["x_m"]
    window = 1.0
    later = np.searchsorted(t, t + window)
    i = np.nonzero(later < t.size)[0]
    per_segment = [np.min(x[later[i], k] - x[i, k]) for k in range(2)]
    assert max(per_segment) < 0  # a rule on any one segment would call the gait stuck
    assert verdict(res).status == "moving"
    assert verdict(res, {"window_s": window}).status == "moving"
    rolling = load_scenario(
        SCENARIOS / "inchworm2.yaml",
        ["mode={type: uniform, speed_mps: 0.6, start_time_s: 0.5}", "simulation.duration_s=10"],
    )
    assert verdict(simulate(rolling)).status == "immobilised"


def test_a_run_shorter_than_the_window_is_not_judged():
    res = shipped_result("rolling6_xt025")
    assert verdict(res, {"window_s": res.t[-1] + 1.0}).status == "moving"


def test_reaching_the_goal_ends_the_route():
    """ramp_drift with simulation.goal_m = 100: reached_end at the time the leader passes 100 m."""
    sc = load_scenario(SCENARIOS / "ramp_drift.yaml", ["simulation.goal_m=100", "simulation.duration_s=80"])
    res = simulate(sc)
    v = verdict(res)
    leader = res.segments["x_m"][:, 0]
    k = int(np.argmax(leader >= 100.0))
    t_by_hand = np.interp(100.0, leader[k - 1 : k + 1], res.t[k - 1 : k + 1])
    assert v.status == "reached_end"
    assert v.t_s == pytest.approx(t_by_hand, abs=1e-9) and v.x_m == 100.0
    assert v.reason == f"reached the end of the route (x = 100.0 m) at t = {t_by_hand:.1f} s"


def test_a_route_without_goal_ends_at_its_last_point():
    sc = load_scenario(SCENARIOS / "ramp_drift.yaml")
    assert goal_of(sc) == sc.terrain.route_data().distance_m[-1] == 220.0
    elevation = scenario_from_dict(rolling_raw(xt=0.9, elevation=[[0, 0], [30, 1.0]]))
    assert goal_of(elevation) == 30.0
    assert goal_of(scenario_from_dict(rolling_raw())) is None  # no route: no end
    res = shipped_result("ramp_drift")  # 120 s: the leader stops short of 220 m
    assert res.segments["x_m"][-1, 0] < 220.0 and verdict(res).status == "moving"


def test_immobilised_before_the_goal_is_immobilised(patch_run):
    v = verdict(patch_run, {"goal_m": 40.0})  # beyond where the chain stops
    assert v.status == "immobilised"
    assert verdict(patch_run, {"goal_m": 5.0}).status == "reached_end"  # passed before the stall


def test_sinkage_reaching_its_limit_immobilises(patch_run):
    """With a sinkage series (issue 32's slip-sinkage state), the chain is dug in from the first
    sample at which its mean sinkage reaches the limit."""
    t = patch_run.t
    z = np.outer(0.01 * t, [1.0, 0.5, 0.0])  # mean 0.005 t m
    res = dataclasses.replace(patch_run, segments={**patch_run.segments, "sinkage_m": z})
    v = verdict(res, {"sinkage_m": 0.02})
    first = t[np.argmax(z.mean(axis=1) >= 0.02)]
    assert first == pytest.approx(4.0, abs=0.051)
    assert v.status == "immobilised" and v.cause == "sinkage" and v.t_s == first
    assert v.sinkage_m == pytest.approx(0.005 * first)
    assert "sinkage 0.020 m" in v.reason
    assert verdict(res).cause == "slip"  # no limit given and none in the terrain model: not judged


def test_default_stall_speed_follows_the_smooth_sign():
    sc = scenario_from_dict(rolling_raw())
    assert criteria_of(sc).speed_mps == max(IMMOBILISED_SPEED_MPS, IMMOBILISED_SIGN_FACTOR * 0.01)
    raw = rolling_raw()
    raw["terrain"]["model"] = {"sign_eps_mps": 0.03}
    assert criteria_of(scenario_from_dict(raw)).speed_mps == pytest.approx(IMMOBILISED_SIGN_FACTOR * 0.03)
    raw["simulation"]["immobilised"] = {"speed_mps": 0.02, "window_s": 3, "slip": 0.9}
    crit = criteria_of(scenario_from_dict(raw))
    assert (crit.speed_mps, crit.window_s, crit.slip) == (0.02, 3.0, 0.9)


def test_bad_criteria_name_the_field(patch_run):
    with pytest.raises(ValueError, match="unknown 'windows'; give some of speed_mps, window_s"):
        verdict(patch_run, {"windows": 3})
    raw = rolling_raw()
    raw["simulation"]["immobilised"] = {"slip": 1.5}
    with pytest.raises(ScenarioError, match=r"simulation\.immobilised\.slip: must be at most 1"):
        scenario_from_dict(raw)


def test_a_stall_the_chain_gets_out_of_is_not_an_immobilisation():
    """tow6_staggered (paper Fig 7): the leader's motor starts at 1 s and spins (X_t 0.9, 200 N tow)
    while the others wait for theirs; the chain stalls for seconds, then rolls once enough motors
    run.  A first-stall rule would call it immobilised at about 1 s."""
    res = shipped_result("tow6_staggered")
    t, centre = res.t, res.segments["x_m"].mean(axis=1)
    crit = criteria_of(res.scenario)
    early = np.interp(crit.window_s, t, centre) - centre[0]
    assert early < crit.speed_mps * crit.window_s  # stalled over the first window, the leader's wheels spinning
    assert np.min(res.segments["slip"][(t > 1.5) & (t < 3.0), 0]) > crit.slip
    assert centre[-1] - centre[-101] > 5 * crit.speed_mps * crit.window_s  # then it rolls
    v = verdict(res)
    assert v.status == "moving" and v.t_s == t[-1]


def test_a_run_past_the_routes_last_point_reaches_the_end():
    """ramp_drift without goal_m, run long enough: reached_end when the leader passes the route
    file's last distance (220 m), the time interpolated between the samples by hand."""
    res = simulate(load_scenario(SCENARIOS / "ramp_drift.yaml", ["simulation.duration_s=150"]))
    leader = res.segments["x_m"][:, 0]
    end = res.scenario.terrain.route_data().distance_m[-1]
    assert leader[-1] > end
    k = int(np.argmax(leader >= end))
    t_by_hand = res.t[k - 1] + (res.t[k] - res.t[k - 1]) * (end - leader[k - 1]) / (leader[k] - leader[k - 1])
    v = verdict(res)
    assert v.status == "reached_end" and v.x_m == end
    assert v.t_s == pytest.approx(t_by_hand, abs=1e-9)
    assert res.summary()["status"] == "reached_end" and res.summary()["immobilised_at_m"] is None


UNIFORM_LEVEL = sorted(
    p.stem
    for p in SCENARIOS.glob("*.yaml")
    if (sc := load_scenario(p)).mode.type == "uniform"
    and sc.terrain.xt is not None
    and not sc.terrain.patches
    and sc.terrain.elevation_profile() is None
)


@pytest.mark.parametrize("name", UNIFORM_LEVEL)
def test_shipped_rolling_runs_are_immobilised_exactly_below_the_steady_limit(name):
    """Every shipped scenario rolling at one wheel speed on uniform level snow: immobilised when
    X_t is below the steady limit for its share of the tow (snoworm.steady), moving above it."""
    res = shipped_result(name)
    sc = res.scenario
    seg, tp = sc.vehicle.segment_params()[0], sc.terrain.model.params()
    limit = steady.immobilisation_limit_xt(
        seg, tp, wheel_speed_mps=sc.mode.rolling_speed(), drawbar_N=sc.tow.force_N / sc.vehicle.segments
    )
    assert abs(sc.terrain.xt - limit) > 0.05  # clear of the limit: the verdict must not hang on a margin
    assert verdict(res).status == ("immobilised" if sc.terrain.xt < limit else "moving")


def test_the_shipped_rolling_cases_span_both_sides_of_the_limit():
    assert {"rolling6_xt025", "tow6_uniform", "tow6_staggered"} <= set(UNIFORM_LEVEL)
