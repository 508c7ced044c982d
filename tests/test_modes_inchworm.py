"""Inchworm mode (paper section 5.1, Fig 5, Eqs. 4-6) and its gaits (joint roles and gait checks)."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from snoworm import load_scenario, simulate, terrain
from snoworm.config.params import terrain_params
from snoworm.config.scenario import apply_overrides, read_yaml, scenario_from_dict
from snoworm.config.schema import ScenarioError
from snoworm.modes.inchworm import GAITS, gait_plan, progress_conditions
from snoworm.simulation.driver import chain_model
from tests.conftest import SCENARIOS

FROSTYBOY_TERRAIN = terrain_params("frostyboy")

FN = 90 * 9.81 / 4
V_S = 0.002  # smooth-sign speed of the property test [m/s] (see test docstring)
MARGIN = 0.10  # Eq. 4/5 margin, as a fraction of the terrain resistance involved


def two_segment_push(x_front, x_rear, force_N, duration=0.6):
    """The first (push) phase of a 2-segment vehicle: rear held (wheels locked), the joint pushes
    the front with a constant force, front wheels driven forward at 2 m/s; a 1 m stroke so the
    phase outlasts the run.  Returns (front advance, rear advance) [m]."""
    raw = read_yaml(SCENARIOS / "inchworm2.yaml")
    raw = apply_overrides(
        raw,
        [
            ("terrain.profile", [[-0.95, x_rear], [-0.55, x_front]]),
            ("terrain.model.sign_eps_mps", V_S),
            ("vehicle.links.stroke_max_m", 1.0),
            ("vehicle.links.rate_max_mps", 5.0),
            ("mode.gait", [[0], [1]]),
            ("mode.joint_control", "force"),
            ("mode.joint_force_N", force_N),
            ("mode.hold_margin", None),
            ("mode.mover_wheel_speed_mps", 2.0),
            ("mode.start_time_s", 0.0),
            ("simulation.duration_s", duration),
            ("simulation.output_dt_s", 0.01),
        ],
    )
    res = simulate(scenario_from_dict(raw))
    x = res.segments["x_m"]
    return x[-1, 0] - x[0, 0], x[-1, 1] - x[0, 1]


def full_resistance(X):
    return 4 * float(terrain.resistance_force(np.inf, FN, X, FROSTYBOY_TERRAIN))


def traction(i, X):
    return 4 * float(terrain.traction_force(i, FN, X, FROSTYBOY_TERRAIN))


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(x_front=st.floats(0.35, 0.8), x_rear=st.floats(0.2, 0.8), force=st.floats(20.0, 390.0))
def test_eqs_4_to_6_predict_a_simulated_push_phase(x_front, x_rear, force):
    """Eqs. 4-5 with a margin decide what a short simulated push phase does.

    The mover's traction lies between 0 (driven wheels never brake: slip >= 0) and its peak
    over slip, so Eq. 4 is taken as holding when ``F_c - F_tr,front > m F_tr,front`` and as
    failing when ``F_c + F_t,peak - F_tr,front < -m F_tr,front``.  The anchor's capacity is its
    full resistance, plus (as an upper bound) its locked-wheel braking traction at slip +1, which a
    creeping anchor does not reach (its slip stays near 0).  The margin m = 10 % is
    what the smooth sign of Eq. 3 needs: below the margin a loaded segment creeps at most at
    ``v_s atanh(1 - m)`` = 3 mm/s with ``v_s`` = 2 mm/s, so 'no motion' means under 5 mm in 0.6 s,
    while 10 % of net force (>= 18 N on 90 kg) moves a segment more than 3 cm in that time.
    """
    Ftr_f, Ftr_r = full_resistance(x_front), full_resistance(x_rear)
    Ft_peak = max(traction(i, x_front) for i in np.linspace(0, 1, 201))
    anchor_hi = Ftr_r + traction(1.0, x_rear)  # sliding fast: locked wheels brake at slip 1
    eq4_holds = force - Ftr_f > MARGIN * Ftr_f
    eq4_fails = force + Ft_peak - Ftr_f < -MARGIN * Ftr_f
    eq5_fails = force > (1 + MARGIN) * anchor_hi
    eq5_holds = force < (1 - MARGIN) * Ftr_r  # creeping: locked-wheel slip ~ 0, resistance only
    if not (eq4_holds or eq4_fails or eq5_fails or eq5_holds):
        return
    front, rear = two_segment_push(x_front, x_rear, force)
    if eq4_holds:
        assert front > 0.015
    if eq4_fails:
        assert front < 0.005
    if eq5_fails:
        assert rear < -0.015
    if eq5_holds:
        assert rear > -0.005
    # and the paper's combined condition agrees with the separate ones
    pc = progress_conditions(force, 0.0, Ftr_f, Ftr_r)
    assert pc["progress"] == (pc["eq4_N"] > 0 and pc["eq5_N"] >= 0)
    assert pc["eq6_N"] == pytest.approx(pc["eq4_N"] + pc["eq5_N"])


@pytest.fixture(scope="module")
def inch6():
    return simulate(load_scenario(SCENARIOS / "inchworm6.yaml", ["simulation.duration_s=16"]))


def test_inchworm6_progresses_where_rolling_is_stuck(inch6):
    roll = simulate(load_scenario(SCENARIOS / "rolling6_xt025.yaml", ["simulation.duration_s=16"]))
    s_inch, s_roll = inch6.summary(), roll.summary()
    assert s_inch["distance_m"] > 0.8  # ~0.07 m/s of steady progress
    assert abs(s_roll["distance_m"]) < 0.05  # rolling: immobilised
    assert s_inch["gait_cycles"] >= 3
    # every segment advanced, none slid back overall
    adv = inch6.segments["x_m"][-1] - inch6.segments["x_m"][0]
    assert np.all(adv > 0.5)


def test_fig5_groups_share_speed_traces(inch6):
    """Segments 0 & 3, 1 & 4, 2 & 5 move together (Fig 5): their speed traces overlap."""
    v = inch6.segments["v_mps"]
    late = inch6.t > 2.0
    peak = np.abs(v[late]).max()
    corr = np.corrcoef(v[late].T)
    for a, b in ((0, 3), (1, 4), (2, 5)):
        rms = np.sqrt(np.mean((v[late, a] - v[late, b]) ** 2))
        assert corr[a, b] > 0.95 and rms < 0.15 * peak, (a, b, corr[a, b], rms, peak)
    # and segments of different groups move at different times
    for a, b in ((0, 1), (1, 2), (3, 5)):
        assert corr[a, b] < 0.3 and np.sqrt(np.mean((v[late, a] - v[late, b]) ** 2)) > 0.3 * peak


def test_phase_changes_happen_on_stroke_limits(inch6):
    """Every phase change coincides with a joint at its stroke limit (events, not timers)."""
    L = inch6.scenario.vehicle.links
    ext = inch6.links["extension_m"]
    changes = [e for e in inch6.events if e["kind"] == "phase_change"]
    assert len(changes) >= 6
    for e in changes:
        i = np.argmin(np.abs(inch6.t - e["t_s"]))
        at_limit = np.minimum(np.abs(ext[i] - L.stroke_max_m), np.abs(ext[i] - L.stroke_min_m))
        assert at_limit.min() < 2e-3
    # phases have different durations (they are not driven by a clock)
    dts = np.diff([e["t_s"] for e in changes])
    assert np.ptp(dts) > 0.01


def test_strokes_stay_within_limits(inch6):
    L = inch6.scenario.vehicle.links
    ext = inch6.links["extension_m"]
    assert ext.min() > L.stroke_min_m - 1e-6 and ext.max() < L.stroke_max_m + 1e-6
    assert np.abs(inch6.links["force_N"]).max() < L.force_max_N * 1.05


def test_higher_xt_faster_less_sliding_lower_force(inch6):
    """Paper: 'higher terrain coefficients ... less backwards sliding, higher forward speeds, and
    lower forces required for the prismatic joints'."""
    hi = simulate(load_scenario(SCENARIOS / "inchworm6.yaml", ["simulation.duration_s=16", "terrain.xt=0.5"]))
    a, b = inch6.summary(), hi.summary()
    assert b["mean_speed_mps"] > a["mean_speed_mps"]
    assert b["peak_backward_speed_held_mps"] < a["peak_backward_speed_held_mps"]
    assert b["peak_joint_force_N"] < a["peak_joint_force_N"]


def test_user_gait_four_segments_one_at_a_time():
    raw = apply_overrides(
        read_yaml(SCENARIOS / "inchworm6.yaml"),
        [("vehicle.segments", 4), ("mode.gait", [[3], [2], [1], [0]]), ("simulation.duration_s", 8)],
    )
    res = simulate(scenario_from_dict(raw))
    assert np.all(res.segments["x_m"][-1] - res.segments["x_m"][0] > 0.2)
    assert res.summary()["gait_cycles"] >= 1


def test_phase_diagnostics_reported(inch6):
    ph = inch6.summary()["phases"]
    assert ph and all("predicted" in p and "observed" in p for p in ph)
    d = ph[1]["predicted"][0]
    assert set(d) >= {"eq4_N", "eq5_N", "eq6_N", "progress"}
    assert d["progress"] is True


# ------------------------------------------------------------------ phase changes robust to rounding
def _long_chain(n, duration):
    gait = [list(range(p, n, 3)) for p in range(3)]  # the six-segment gait's pattern, repeated
    return load_scenario(
        "inchworm6", [("vehicle.segments", n), ("mode.gait", gait), ("simulation.duration_s", duration)]
    )


@pytest.mark.parametrize("n", [12, 24, 32, 48])
def test_both_kernels_give_the_same_gait_on_long_chains(n, monkeypatch):
    """A long chain moves several identical groups per phase: they reach their stroke limits within
    ~1e-13 s of each other, and whether the others were then a rounding error short of their event
    level or past it decided whether the phase ever ended (8ca4e02: 32 segments on the float kernel
    stopped inching after 3 s, 0.09 m against the NumPy kernel's 0.70 m in 10 s; the kernels agree to
    1e-13 per evaluation).  Now the runs of the two kernels agree on distance within 1e-3."""
    from snoworm.model import floatkernel

    res = {}
    for kernel, limit in (("numpy", 0), ("float", 10**6)):
        monkeypatch.setattr(floatkernel, "MAX_SEGMENTS", limit)
        sc = _long_chain(n, 10.0)
        assert (chain_model(sc).float_kernel is None) == (kernel == "numpy")
        res[kernel] = simulate(sc).summary()
    d_np, d_fl = res["numpy"]["distance_m"], res["float"]["distance_m"]
    assert d_np > 0.5  # several gait cycles: more than one phase change per group
    assert d_fl == pytest.approx(d_np, rel=1e-3)
    assert len(res["float"]["events"]) == len(res["numpy"]["events"])


def test_a_group_already_at_its_limit_when_an_interval_starts_is_done():
    """The rounding either side of the event level gives the same decision (EVENT_TOL_M)."""
    from snoworm.modes.inchworm import EVENT_TOL_M, InchwormMode

    sc = _long_chain(6, 5.0)
    for offset in (-0.1 * EVENT_TOL_M, 0.0, 1e-15, 1e-12):
        mode = InchwormMode(sc.mode, sc, chain_model(sc))
        y = mode.initial_state()
        mode.interval(1.0, y)  # phase 0 begins: groups [0] and [3] move
        plan = mode.plans[0]
        m = mode.model
        Y = m.unpack(y.copy())
        j = next(int(j) for j in np.nonzero(plan.role != 0)[0] if plan.group_of_joint[j] == 1)
        sign, level = mode._event_level(plan, j)
        Y[j, m.layout.s] = level + sign * offset  # group 1's joint at its level, a rounding error either side
        iv = mode.interval(1.0, Y.reshape(-1))
        assert mode.group_done[1] and not mode.group_done[0], offset
        assert j not in mode._event_joints  # its event is not armed again
        assert any(e["kind"] == "joint_limit" and f"joint {j} " in e["detail"] for e in mode.log)
        assert iv.events  # the other group's event still is
    mode = InchwormMode(sc.mode, sc, chain_model(sc))
    y = mode.initial_state()
    mode.interval(1.0, y)
    Y = m.unpack(y.copy())
    Y[j, m.layout.s] = level - sign * 10 * EVENT_TOL_M  # short of it by more than the tolerance: not done
    mode.interval(1.0, Y.reshape(-1))
    assert not mode.group_done.any()


# ---------------------------------------------------------------------------------------- gaits
def test_gait_validation():
    with pytest.raises(ScenarioError, match="jam"):
        gait_plan([[0], [0]], 2, ["prismatic"])
    with pytest.raises(ScenarioError, match="only extends"):
        gait_plan([[0]], 2, ["prismatic"])
    with pytest.raises(ScenarioError, match="every segment"):
        gait_plan([[0, 1]], 2, ["prismatic"])
    with pytest.raises(ScenarioError, match="must be 'prismatic'"):
        gait_plan([[1], [0]], 2, ["fixed"])
    with pytest.raises(ScenarioError, match="out of range"):
        gait_plan([[2], [0]], 2, ["prismatic"])
    # a 4-segment gait moving one segment at a time, rear to front, is valid
    plans = gait_plan([[3], [2], [1], [0]], 4, ["prismatic"] * 3)
    assert [list(p.role) for p in plans] == [[0, 0, -1], [0, -1, 1], [-1, 1, 0], [1, 0, 0]]


def test_shipped_gaits_alternate_every_joint_and_keep_anchors():
    """Fig 5's six-segment gait: each joint extends and contracts once per cycle, and each phase
    holds two segments for each moving one (the held clusters are the anchors)."""
    plans = gait_plan(GAITS["six_segment"], 6, ["prismatic"] * 5)
    roles = np.array([p.role for p in plans])  # (phase, joint)
    assert np.all((roles == 1).sum(0) == 1) and np.all((roles == -1).sum(0) == 1)
    assert [len(p.moving) for p in plans] == [2, 2, 2]
    assert all(sum(len(c) for c in p.clusters) == 4 for p in plans)
    two = gait_plan(GAITS["two_segment"], 2, ["prismatic"])
    assert [list(p.role) for p in two] == [[-1], [1]]  # pull the rear forward, then push the front
