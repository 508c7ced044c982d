"""A sled towed behind the rear segment (docs/model.md section 4, "Towed load"; issue 32 item 3).

``tow: {force_N, mass_kg, friction}``: the rear segment is pulled back by
F = force_N + m_s g (sin(theta_rear) + mu cos(theta_rear) tanh(v_rear / v_s)), friction opposing the sled's
motion and only gravity at rest; in steady forward motion D(theta) = force_N + m_s g (sin + mu cos), which the
steady gradeability takes (steady.max_grade_deg).
"""

import math

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.optimize import brentq, minimize_scalar

from snoworm import load_scenario, simulate, steady
from snoworm.cli import main
from snoworm.model.inputs import Controls
from snoworm.results.energy import energy_balance
from snoworm.simulation.driver import chain_model

M_S, MU = 150.0, 0.1


def _hand_pull(force_N, grade_deg, g, moving=1.0):
    th = math.radians(grade_deg)
    return force_N + M_S * g * (math.sin(th) + MU * math.cos(th) * moving)


@pytest.mark.parametrize("grade", [0.0, 5.0])
def test_the_chain_pulls_the_sled_at_the_steady_state(grade):
    """tow6_uniform (X_t 0.9, 200 N) with a 150 kg sled, mu 0.1: in steady motion the tow is
    D = 200 + m_s g (sin + mu cos) (347.2 N level, 474.8 N at 5 deg, by hand) and every segment runs at
    steady.steady_state with a sixth of it; the energy balance closes with the sled's work in the tow term."""
    sc = load_scenario(
        "tow6_uniform",
        [f"terrain.grade_deg={grade}", f"tow.mass_kg={M_S}", f"tow.friction={MU}", "simulation.rtol=1e-8"],
    )
    res = simulate(sc)
    seg, tp = sc.vehicle.segment_params()[0], sc.terrain.model.params()
    D = _hand_pull(200.0, grade, seg.gravity_mps2)
    # the tow the rear segment felt: the last link's pull minus the connector force on it
    tow = res.links["force_N"][-1, -1] - res.segments["connector_net_N"][-1, -1]
    assert tow == pytest.approx(D, rel=1e-6)
    assert steady.tow_drawbar_N(200.0, seg, grade, M_S, MU) == pytest.approx(D, rel=1e-14)
    ss = steady.steady_state(0.9, seg, tp, drawbar_N=D / 6, wheel_speed_mps=1.8, grade_deg=grade)
    np.testing.assert_allclose(res.segments["slip"][-1], ss.slip, rtol=1e-5)
    np.testing.assert_allclose(res.segments["v_mps"][-1], ss.ground_speed_mps, rtol=1e-6)
    b = energy_balance(res)
    assert abs(b["residual_J"]) < 5e-3 * b["throughput_J"]
    # the tow's work is the sled's pull times the distance, within the start-up's share (pull at rest < D)
    dist = res.segments["x_m"][-1, -1] - res.segments["x_m"][0, -1]
    assert b["tow_J"] == pytest.approx(D * dist, rel=2e-2)


def _models(route):
    base = ["vehicle.segments=3", "tow.force_N=50"]
    sc0 = load_scenario("tow6_uniform", base).with_(route)
    sc1 = sc0.with_({"tow.mass_kg": M_S, "tow.friction": MU})
    return chain_model(sc0), chain_model(sc1)


@pytest.mark.parametrize(
    "route",
    [
        {"terrain.grade_deg": 0.0},
        {"terrain.grade_deg": 8.0},
        {"terrain.elevation": [[-10.0, 0.0], [-3.2, 0.0], [2.8, 1.5], [30.0, 1.5]]},
    ],
    ids=["level", "constant", "table"],
)
@pytest.mark.parametrize("v_rear", [0.0, 0.004, 1.0, -1.0])
def test_the_kernel_adds_the_sled_at_the_rear_grade(route, v_rear):
    """The kernel (float code and NumPy alike) adds m_s g (sin(theta_r) + mu cos(theta_r) tanh(v_r / v_s)) to
    the rear segment's backward load and nothing elsewhere: at rest only gravity, the friction opposing the
    motion either way.  theta_r is the chord grade under the rear segment (on the table, its axles at
    x_r -+ b/2 astride the foot of a 1.5 m rise over 6 m: sin = (z(x + b/2) - z(x - b/2)) / b, by hand)."""
    m0, m1 = _models(route)
    L = m0.layout
    y = m0.initial_state().reshape(m0.n, L.n_s)
    y[:, L.v] = v_rear
    y = y.reshape(-1)
    ctl = Controls.rolling(m0.n, 1.0, 1.8)
    seg_g, m_rear, b = m0.seg.gravity_mps2[-1], m0.seg.mass_kg[-1], m0.seg.wheelbase_m[-1]
    x_r = y[L.flat_index(m0.n - 1, "x_m")]
    if "terrain.elevation" in route:

        def z(s):
            return float(np.interp(s, [-10.0, -3.2, 2.8, 30.0], [0.0, 0.0, 1.5, 1.5]))

        sin_r = (z(x_r + b / 2) - z(x_r - b / 2)) / b
        assert 0.1 < sin_r < 0.2  # the rear segment astride the foot of the rise
    else:
        sin_r = math.sin(math.radians(route["terrain.grade_deg"]))
    cos_r = math.sqrt(1 - sin_r**2)
    pull = M_S * seg_g * (sin_r + MU * cos_r * math.tanh(v_rear / m0.tp.sign_eps_mps))
    d_float = (m1.rhs(0.0, y, ctl) - m0.rhs(0.0, y, ctl)).reshape(m0.n, L.n_s)
    d_numpy = (m1.evaluate(m1.unpack(y), ctl)[0] - m0.evaluate(m0.unpack(y), ctl)[0]).reshape(m0.n, L.n_s)
    for d in (d_float, d_numpy):
        assert d[-1, L.v] * m_rear == pytest.approx(-pull, rel=1e-12, abs=1e-9)
        d[-1, L.v] = 0.0
        assert np.all(d == 0.0)  # nothing else changes


def _hand_max_drawbar(X, seg, tp):
    """Largest drawbar of one segment on level ground by hand: m g max_i (X^d b_tF sin(2.8 X atan(atan(4 X^2 i)))
    - b_trF / X^A) (Eqs. 2 and 3 per unit load, moving forward)."""

    def net(i):
        ft = X**tp.peak_exponent_d * tp.b_tF * math.sin(2.8 * X * math.atan(math.atan(4 * X * X * i)))
        return ft - tp.b_trF / X**tp.A

    r = minimize_scalar(lambda i: -net(i), bounds=(0, 1), method="bounded", options={"xatol": 1e-12})
    return seg.mass_kg * seg.gravity_mps2 * net(r.x)


@pytest.mark.parametrize("X", [0.7, 0.9, 1.0])
def test_the_steady_gradeability_drops_by_the_sled(X):
    """Six segments, 200 N and a 150 kg sled (mu 0.1): the steepest rolling grade is the root, found here
    independently, of cos(theta) D0 - m g sin(theta) = (200 + m_s g (sin(theta) + mu cos(theta))) / 6 with D0
    the level maximum drawbar by hand.  Without the sled the limit is higher: by 2.5 deg at X_t 0.7 to
    6.2 deg at 1.0 (the sled's share grows with sin(theta))."""
    sc = load_scenario("tow6_uniform")
    seg, tp = sc.vehicle.segment_params()[0], sc.terrain.model.params()
    D0, mg = _hand_max_drawbar(X, seg, tp), seg.mass_kg * seg.gravity_mps2

    def balance(th_deg):
        th = math.radians(th_deg)
        return math.cos(th) * D0 - mg * math.sin(th) - _hand_pull(200.0, th_deg, seg.gravity_mps2) / 6

    hand = brentq(balance, -40.0, 40.0, xtol=1e-12)
    got = steady.max_grade_deg(X, seg, tp, 1.8, 200.0 / 6, segments=6, sled_mass_kg=M_S, sled_friction=MU)
    # the steady solver maximises over the slip at wheel speed 1.8 m/s (full resistance): the same peak
    assert got == pytest.approx(hand, abs=1e-6)
    without = steady.max_grade_deg(X, seg, tp, 1.8, 200.0 / 6)
    assert without > got + 2.0


def test_a_sled_without_friction_is_refused(tmp_path):
    """No silent default for the sled's friction: exit 2 naming tow.friction, nothing written."""
    r = CliRunner().invoke(main, ["run", "tow6_uniform", "--set", "tow.mass_kg=80", "--out", str(tmp_path / "o")])
    assert r.exit_code == 2
    assert "tow.friction" in r.output and "Traceback" not in r.output
    assert not (tmp_path / "o").exists()


def test_stacked_runs_with_sleds_and_failed_drivetrains_equal_the_runs_alone():
    """Same question, same answer: a sled and a failed drivetrain are parameters of a member, so chains with
    and without them share a batch key, and the stacked run gives each member the run it has alone
    (the tolerance of tests/test_studies_sweep_batched.py: the members share LSODA's steps)."""
    from snoworm.simulation.driver import batch_key, simulate_batch

    base = load_scenario("tow6_uniform", ["simulation.duration_s=4", "terrain.grade_deg=4"])
    members = [
        base,
        base.with_({"tow.mass_kg": M_S, "tow.friction": MU}),
        base.with_({"vehicle.segment_overrides": {5: {"drivetrain": "failed"}}}),
        base.with_(
            {"tow.mass_kg": 60.0, "tow.friction": 0.3, "vehicle.segment_overrides": {2: {"drivetrain": "failed"}}}
        ),
    ]
    assert len({batch_key(sc) for sc in members}) == 1
    alone = [simulate(sc) for sc in members]
    v_end = [a.segments["v_mps"][-1].mean() for a in alone]
    assert len({round(v, 3) for v in v_end}) == 4  # the members differ
    for m, a in zip(simulate_batch(members), alone):
        assert m.status == "ok"
        np.testing.assert_allclose(m.result.segments["v_mps"][-1], a.segments["v_mps"][-1], rtol=1e-4)
        np.testing.assert_allclose(
            m.result.segments["motor_torque_Nm"][-1], a.segments["motor_torque_Nm"][-1], rtol=1e-4, atol=1e-6
        )


def test_the_modes_plan_with_the_sled():
    """The force-control plan (level, docs/model.md section 5) shares the tow's steady pull, force_N + m_s g mu:
    pi3_equal's leader and rear each carry half of it (hand), and the simulated steady wheel forces follow.
    The supervisor's rolling surplus subtracts the sled's pull at the rear segment's grade (hand)."""
    import math

    from snoworm.modes.supervisor import chain_drawbar_surplus_N
    from snoworm.simulation.driver import assemble

    sc = load_scenario("pi3_equal", [f"tow.mass_kg={M_S}", f"tow.friction={MU}"])
    g = sc.vehicle.segment_params()[-1].gravity_mps2
    pull = _hand_pull(200.0, 0.0, g)
    plan = assemble(sc).mode.plan
    np.testing.assert_allclose(plan.wheel_net_N, [pull / 2, 0.0, pull / 2], rtol=1e-12, atol=1e-9)
    res = simulate(sc)
    np.testing.assert_allclose(res.segments["net_force_N"][-1], [pull / 2, 0.0, pull / 2], rtol=1e-3, atol=0.5)

    level = load_scenario("traverse_patch")
    segs = level.vehicle.segment_params()
    x = np.array([30.0 - 1.5 * k for k in range(6)])  # past the patch: X_t = 0.9 under every axle
    for grade in (0.0, 6.0):
        plain = level.with_({"terrain.grade_deg": grade})
        sled = plain.with_({"tow.mass_kg": M_S, "tow.friction": MU})
        s0 = chain_drawbar_surplus_N(chain_model(plain), segs, x, 1.8)
        s1 = chain_drawbar_surplus_N(chain_model(sled), segs, x, 1.8)
        th = math.radians(grade)
        assert s0 - s1 == pytest.approx(M_S * g * (math.sin(th) + MU * math.cos(th)), rel=1e-9)
