"""Free-rolling resistance and the failed drivetrain (docs/model.md sections 2 and 4, issue 32 item 2).

The fitted resistance torque T_rr of a driven wheel splits into the terrain's share T_free, which makes
a free wheel resist with exactly Eq. 3, and the driveline losses T_loss = T_rr - T_free >= 0.  A
segment whose drivetrain has failed (``vehicle.segment_overrides.K.drivetrain: failed``) gives no
torque and its wheels roll free with T_free: it rolls down a grade where Eq. 3 alone says it must,
atan(b_trF / X^A) (10.7 deg on X_t = 0.8), not at 27 deg as with the driven wheels' T_rr.
"""

import math

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from snoworm import load_scenario, simulate, steady, terrain
from snoworm.cli import main
from snoworm.config.params import terrain_params
from snoworm.model.inputs import Controls
from snoworm.simulation.driver import chain_model

FAILED = {"drivetrain": "failed"}


def _segment_on_grade(grade_deg, xt=0.8, drivetrain="failed", balance="contact"):
    sc = load_scenario(
        "tow6_uniform",
        [f"terrain.xt={xt}", f"terrain.grade_deg={grade_deg}", "vehicle.segments=1", "tow.force_N=0"],
    )
    sc = sc.with_(
        {"vehicle.segment_overrides": {0: {"drivetrain": drivetrain}}, "terrain.model.torque_balance": balance}
    )
    return sc, chain_model(sc)


# ------------------------------------------------------------------ the law
@pytest.mark.parametrize("balance", ["contact", "traction"])
def test_the_split_of_the_fitted_torque(balance):
    """contact: T_free = R_w F_tr (Eq. 3 at full sign) where the fit allows it, T_loss = T_rr - T_free >= 0
    on all of (0, 1]; traction: T_free = 0, T_loss = T_rrB.  The fit meets R_w F_tr at X* (root by hand),
    below which T_free = T_rr."""
    from dataclasses import replace

    tp = replace(terrain_params("frostyboy"), torque_balance=balance)
    X = np.concatenate([np.geomspace(1e-4, 0.1, 200), np.linspace(0.1, 1.0, 400)])
    F_n, R = 220.725, 0.265
    T_rr = terrain.resistance_torque(1.0, F_n, X, R, tp)
    T_free = terrain.free_rolling_torque(1.0, F_n, X, R, tp)
    loss = T_rr - T_free
    assert np.all(loss >= 0)
    if balance == "traction":
        assert np.all(T_free == 0)
        return
    x_star = brentq(lambda x: tp.tau0 + tp.tau1 * (1 - x) - tp.b_trF / x**tp.A, 1e-4, 0.5)
    assert x_star == pytest.approx(0.0178, abs=1e-4)  # the value docs/model.md states
    RF = R * terrain.resistance_force(np.inf, F_n, X, tp)
    above = X >= x_star
    np.testing.assert_allclose(T_free[above], RF[above], rtol=1e-13)
    np.testing.assert_allclose(T_free[~above], T_rr[~above], rtol=1e-13)
    # on the fitted range the driveline loss is most of T_rr at loose snow, little on neve
    np.testing.assert_allclose(loss[X == 1.0], F_n * R * (tp.tau0 - tp.b_trF), rtol=1e-12)
    # the sign follows the wheel's spin, as T_rr's
    assert terrain.free_rolling_torque(-1.0, F_n, 0.8, R, tp) == pytest.approx(-R * F_n * tp.b_trF / 0.8**tp.A)


# ------------------------------------------------------------------ a free segment on a grade
def _threshold_deg(tp, X):
    return math.degrees(math.atan(tp.b_trF / X**tp.A))


@pytest.mark.parametrize("offset", [-1.0, 1.0])
def test_a_free_segment_rolls_down_at_the_resistance_angle(offset):
    """One segment with a failed drivetrain, at rest on an uphill of theta* -+ 1 deg, theta* = atan(b_trF / X^A)
    (10.68 deg at X_t 0.8: Eq. 3 alone).

    Below: it creeps back at the speed where Eq. 3's smooth sign balances gravity, with its wheels at zero
    slip: b_trF/X^A cos(theta) tanh(|V|/v_s) = sin(theta), V = -v_s atanh(tan(theta) X^A / b_trF) (1.5 cm/s).
    Above: it rolls down with a = -g (sin - mu cos) m / (m + n J / R^2) (the free wheels' inertia spun up by
    their traction, mu = b_trF / X^A).  Both on the float kernel and on the NumPy kernel; the driven wheels'
    T_rr (the branch point's law for a segment whose motors are off) held it to 27 deg."""
    X = 0.8
    sc0, m0 = _segment_on_grade(0.0, X)
    tp = m0.tp
    th_star = _threshold_deg(tp, X)
    assert th_star == pytest.approx(10.68, abs=0.01)
    grade = th_star + offset
    sc, m = _segment_on_grade(grade, X)
    seg = sc.vehicle.segment_params()[0]
    assert seg.drivetrain == "failed"
    L = m.layout
    ctl = Controls.rolling(1, 1.0, 1.8)  # motors commanded on: a failed drivetrain ignores it
    th, mu = math.radians(grade), tp.b_trF / X**tp.A
    for rhs in (m.rhs, lambda t, y, c: m.evaluate(m.unpack(y), c)[0].reshape(-1)):
        sol = solve_ivp(
            rhs,
            (0.0, 6.0),
            m.initial_state(),
            args=(ctl,),
            method="Radau",
            rtol=1e-10,
            atol=1e-12,
            t_eval=[4.0, 5.0, 6.0],
            jac=lambda t, y, c: m.jacobian_sparse(t, y, c),
        )
        assert sol.success
        v = sol.y[L.v]
        if offset < 0:
            creep = -tp.sign_eps_mps * math.atanh(math.tan(th) / mu)
            # settled (time constant ~40 ms): to the solver tolerance
            np.testing.assert_allclose(v, creep, rtol=1e-6)
            assert -0.02 < creep < -0.01
        else:
            n_w = 2 * seg.wheels_per_axle
            a_hand = -seg.gravity_mps2 * (math.sin(th) - mu * math.cos(th)) * seg.mass_kg
            a_hand /= seg.mass_kg + n_w * seg.wheel_inertia_kgm2 / seg.wheel_radius_m**2
            a = np.diff(v)  # per second
            assert v[0] < -0.3  # rolling down, the smooth signs saturated
            # 1e-3: the wheels' small slip while they spin up (|i| ~ 2e-3) makes w' differ from a/R by ~i
            np.testing.assert_allclose(a, a_hand, rtol=1e-3)


def test_the_driven_law_held_the_same_segment():
    """The branch point's behaviour, kept for a segment whose drivetrain works but whose motors are off
    (before its start time): T_rr brakes its wheels, and 1 deg above atan(b_trF / X^A) it still creeps
    (6 mm/s, the smooth signs' creep), where a failed one rolls away at 0.14 m/s^2.  In steady rolling the
    contact balance passes -T_rr / R_w per wheel to the chassis, so it rolls down only where
    tan(theta) = T_rr / (F_n R_w) = tau0 + tau1 (1 - X): 27 deg on X_t 0.8."""
    X = 0.8
    sc, m = _segment_on_grade(_threshold_deg(terrain_params("frostyboy"), X) + 1.0, X, drivetrain="working")
    tp = m.tp
    ctl = Controls.rolling(1, 0.0, 0.0)  # motors off
    sol = solve_ivp(m.rhs, (0.0, 6.0), m.initial_state(), args=(ctl,), method="Radau", rtol=1e-10, atol=1e-12)
    assert sol.success and abs(sol.y[m.layout.v, -1]) < 1e-2
    c = float(terrain.torque_coefficient(1.0, X, 1.0, tp))  # T_rr / (F_n R_w)
    assert math.degrees(math.atan(c)) == pytest.approx(27.0, abs=0.3)


def test_a_chain_tows_a_failed_segment():
    """tow6_uniform (X_t 0.9, 200 N, 1.8 m/s) with the rear segment's drivetrain failed: five driven
    segments tow it.  Its motor torque is 0 and its wheels roll at zero slip (Eq. 3 alone), so the last
    link carries the tow plus the failed segment's Eq. 3 resistance, 200 + b_trF m g / X^A = 355.2 N (by hand),
    and each driven segment pulls a fifth of that at the slip of steady.steady_state.  (With the driven
    wheels' T_rr, a segment with its motors off cost 302 N instead of 155 N.)"""
    sc = load_scenario("tow6_uniform").with_({"vehicle.segment_overrides": {5: FAILED}})
    res = simulate(sc)
    s = res.segments
    seg, tp = sc.vehicle.segment_params()[0], sc.terrain.model.params()
    assert np.all(s["motor_torque_Nm"][:, 5] == 0.0)
    resist = tp.b_trF * seg.mass_kg * seg.gravity_mps2 / 0.9**tp.A
    np.testing.assert_allclose(res.links["force_N"][-1, 4], 200.0 + resist, rtol=1e-5)
    ss = steady.steady_state(0.9, seg, tp, drawbar_N=(200.0 + resist) / 5, wheel_speed_mps=1.8)
    np.testing.assert_allclose(s["slip"][-1, :5], ss.slip, rtol=1e-4)
    np.testing.assert_allclose(s["v_mps"][-1], ss.ground_speed_mps, rtol=1e-5)
    np.testing.assert_allclose(s["motor_torque_Nm"][-1, :5], ss.torque_Nm, rtol=1e-5)
    assert abs(s["slip"][-1, 5]) < 1e-5


def test_a_bad_drivetrain_value_is_refused(tmp_path):
    """Exit 2 and a message naming the field and the allowed values, no traceback."""
    p = tmp_path / "bad.yaml"
    p.write_text(
        "name: bad\nvehicle:\n  parameter_set: frostyboy\n  segments: 2\n  links: {type: fixed}\n"
        "  segment_overrides:\n    1: {drivetrain: broken}\nterrain: {xt: 0.8}\ntow: {force_N: 0}\n"
        "mode: {type: uniform, speed_mps: 1.8}\nsimulation: {duration_s: 1}\n"
    )
    r = CliRunner().invoke(main, ["run", str(p), "--out", str(tmp_path / "o")])
    assert r.exit_code == 2
    assert "vehicle.segment_overrides.1.drivetrain" in r.output and "'failed'" in r.output
    assert "Traceback" not in r.output
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("scenario", ["tow6_weak_segment", "inchworm6", "traverse_patch"])
def test_modes_that_plan_driven_segments_refuse_a_failed_one(scenario, tmp_path):
    """Force control (its plan gives each segment a wheel force), inchworm and the supervisor (they hold
    segments on locked wheels) refuse a failed drivetrain with a message naming the segment's field (exit 2)."""
    from snoworm.config.schema import ScenarioError

    with pytest.raises(ScenarioError, match=r"vehicle\.segment_overrides\.1\.drivetrain: the .* mode"):
        load_scenario(scenario).with_({"vehicle.segment_overrides": {1: FAILED}})
    r = CliRunner().invoke(
        main,
        ["run", scenario, "--set", "vehicle.segment_overrides.1.drivetrain=failed", "--out", str(tmp_path / "o")],
    )
    assert r.exit_code == 2 and "segment 1's drivetrain has failed" in r.output
