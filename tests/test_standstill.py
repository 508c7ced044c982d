"""The slip near rest: the shear-displacement law (``terrain.model.standstill: shear``, docs/model.md
section 2, "Standstill") against hand computations from the laws of snoworm.terrain.

Issue 32: with the regularised Eq. 1 a chain parked on a slope far below its hold angle creeps
downhill (a viscous law at rest).  The shear displacement ``j`` per axle makes the traction a
spring at rest: the chain holds, up to the grade at which the peak traction of its locked wheels
no longer carries ``m g sin(theta)``, computed here by a root finder from
:func:`snoworm.terrain.traction_force` and :func:`snoworm.terrain.normal_load_N` alone.
"""

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

from snoworm import load_scenario, simulate, steady, terrain
from snoworm.config.params import parameter_set

SEG = parameter_set("frostyboy")["segment"]


def parked(grade_deg, xt, *, standstill="shear", segments=1, duration_s=90.0, extra=()):
    """``(t, x of the leader, scenario, result)`` for a chain at zero wheel-speed command (motors on from t = 0)."""
    sc = load_scenario(
        "frostyboy_case3",
        [
            ("terrain.model.standstill", standstill),
            ("terrain.grade_deg", grade_deg),
            ("terrain.xt", xt),
            ("mode.speed_mps", 0.0),
            ("mode.start_time_s", 0.0),
            ("vehicle.segments", segments),
            ("simulation.duration_s", duration_s),
            ("simulation.output_dt_s", 0.5),
            *extra,
        ],
    )
    r = simulate(sc)
    return r.t, r.segments["x_m"][:, 0], sc, r


def moved_after(t, x, t0):
    """Distance travelled from ``t0`` to the end of the run [m] (negative: downhill)."""
    return float(x[-1] - x[np.searchsorted(t, t0)])


def hold_angle_deg(xt, tp, com_height_m):
    """The largest grade on which the peak traction of a segment's locked wheels, on the grade's
    normal loads (docs/model.md section 7), carries ``m g sin(theta)``: by hand from the laws."""
    m, g, n_axle = SEG["mass_kg"], SEG["gravity_mps2"], SEG["wheels_per_axle"]
    W = m * g / (2 * n_axle)
    transfer = 2.0 * com_height_m / SEG["wheelbase_m"]

    def peak_N(F_n):  # the largest traction over the slips a locked wheel reaches, |i| <= 1
        res = minimize_scalar(lambda i: -terrain.traction_force(i, F_n, xt, tp), bounds=(0.0, 1.0), method="bounded")
        return max(-res.fun, float(terrain.traction_force(1.0, F_n, xt, tp)))

    def margin(theta):
        Fn = terrain.normal_load_N(W, np.sin(theta), np.cos(theta), transfer)
        return n_axle * (peak_N(Fn[0]) + peak_N(Fn[1])) - m * g * np.sin(theta)

    return float(np.degrees(brentq(margin, 1e-6, np.radians(60.0), xtol=1e-12)))


@pytest.mark.parametrize("K", [0.01, 0.05])
@pytest.mark.parametrize("wheel_mps,V", [(1.8, 1.7), (2.05, 1.2), (0.3, -0.2), (-1.0, -1.1), (0.0, -0.5)])
def test_the_shear_state_settles_at_eq1_slip_whatever_K(wheel_mps, V, K):
    """At any steady rolling the fixed point of dj/dt is Eq. 1's slip (its regularised form wherever
    |R_w w| or |V| exceeds v_eps), independent of K: steady results do not depend on it."""
    j = brentq(lambda j: terrain.shear_displacement_rate(wheel_mps, V, j, K), -3 * K, 3 * K, xtol=1e-15)
    hand = (wheel_mps - V) / max(abs(wheel_mps), abs(V))
    assert j / K == pytest.approx(hand, rel=1e-12, abs=1e-12)
    assert terrain.shear_slip(j, K) == pytest.approx(np.clip(hand, -1, 1), abs=1e-12)
    # the regularised law's slip, v_eps = 0.05 m/s, below every speed here
    assert terrain.shear_slip(j, K) == pytest.approx(terrain.slip(wheel_mps, V, 0.05), abs=1e-12)


def _tp(standstill, K=0.025):
    sc = load_scenario(
        "frostyboy_case3", [("terrain.model.standstill", standstill), ("terrain.model.shear_modulus_K_m", K)]
    )
    return sc.terrain.model.params()


@pytest.mark.parametrize("K", [0.01, 0.05])
def test_steady_rolling_is_the_steady_state_whatever_K(K):
    """Table 2 case 3 run with the shear law ends at snoworm.steady's slip (root finding on Eq. 1-3),
    for K = 1 and 5 cm: the shear state changes transients only."""
    sc = load_scenario(
        "frostyboy_case3", [("terrain.model.standstill", "shear"), ("terrain.model.shear_modulus_K_m", K)]
    )
    r = simulate(sc)
    assert sc.terrain.model.params().standstill == "shear"
    ss = steady.steady_state(sc.terrain.xt, sc.vehicle.segment, sc.terrain.model.params(), wheel_speed_mps=2.05)
    # the solver's relative tolerance 1e-5 on speeds of ~2 m/s: slips agree to ~1e-5
    assert r.segments["slip"][-1, 0] == pytest.approx(ss.slip, abs=1e-4)
    assert r.segments["v_mps"][-1, 0] == pytest.approx(ss.ground_speed_mps, rel=1e-4)


@pytest.mark.parametrize("segments", [1, 6])
def test_a_parked_chain_holds_on_10_deg_where_the_regularised_law_creeps(segments):
    """Issue 32: zero wheel-speed command on 10 deg of X_t 0.8 snow.  Once the wheel-speed PI has
    taken the load (its integral lets the wheels turn back by T / k_i, ~1.8 cm here, over ~5 s of
    the resistance torque's smooth sign), the shear law holds: < 1 cm in the next 60 s, without
    ringing and within the solver work of the regularised law, which creeps downhill at mm/s over
    the same minute."""
    t, x, _, held = parked(10.0, 0.8, segments=segments)
    assert abs(moved_after(t, x, 30.0)) < 0.01
    # overdamped (docs/model.md section 2): no segment ever moves uphill, i.e. the hold does not ring
    assert np.max(held.segments["v_mps"]) <= 1e-9
    t, x, _, creep = parked(10.0, 0.8, standstill="regularised", segments=segments)
    assert moved_after(t, x, 30.0) < -0.05  # 2.6 mm/s of creep
    # the spring at rest costs the solver no more than the viscous law (measured 220-360 against 210-550)
    assert held.summary()["solver"]["nfev"] <= 1.5 * creep.summary()["solver"]["nfev"]


def test_the_hold_angle_is_the_peak_traction_of_the_locked_wheels():
    """Without pitch transfer (h = 0) both axles share one slip, so the chain holds to the grade at
    which the peak traction carries the weight along the grade (by hand: 24.13 deg on X_t 0.8) and
    slides beyond it."""
    tp = _tp("shear")
    theta = hold_angle_deg(0.8, tp, com_height_m=0.0)
    assert theta == pytest.approx(np.degrees(np.arctan(0.8**2 * 0.7)), abs=1e-6)  # tan = X^d b_tF there
    flat = [("vehicle.segment.com_height_m", 0.0)]
    t, x, *_ = parked(theta - 0.1, 0.8, duration_s=300.0, extra=flat)
    assert abs(moved_after(t, x, 30.0)) < 0.01
    t, x, *_ = parked(theta + 0.1, 0.8, duration_s=300.0, extra=flat)
    assert moved_after(t, x, 30.0) < -0.1


def test_with_pitch_transfer_the_hold_angle_is_an_upper_bound():
    """With FrostyBoy's pitch transfer the lighter front axle reaches its peak first (the axles'
    wheels turn back by different angles under the PI), so the chain holds somewhat below the sum
    of the peaks (measured 23.6-23.7 deg against 24.13 deg on X_t 0.8) and slides above it."""
    tp = _tp("shear")
    theta = hold_angle_deg(0.8, tp, com_height_m=SEG["com_height_m"])
    assert theta == pytest.approx(np.degrees(np.arctan(0.8**2 * 0.7)), abs=1e-6)  # the laws are linear in F_n
    t, x, *_ = parked(theta - 1.0, 0.8, duration_s=300.0)
    assert abs(moved_after(t, x, 30.0)) < 0.01
    t, x, *_ = parked(theta + 0.1, 0.8, duration_s=300.0)
    assert moved_after(t, x, 30.0) < -0.1


@pytest.mark.parametrize("pull_N", [50.0, 150.0, 300.0])
def test_a_held_segment_pulled_back_moves_by_the_janosi_displacement(pull_N):
    """One segment on level X_t 0.8, wheels held at zero speed, pulled back by a constant tow.  At
    rest dj/dt = -V (1 - j / K) while it slides back (w = 0, V < 0), so j = K (1 - exp(-d / K)) after
    a slide d: the Janosi-Hanamoto shear curve.  It stops where Eq. 2 at i = j / K carries the pull:
    d = K ln(1 / (1 - i)), plus the wheels' own turn back under the PI, R_w^2 F / (4 k_i) (a stiff
    integral gain keeps that small; the hand value includes it)."""
    ki = 1e5
    sc = load_scenario(
        "frostyboy_case3",
        [
            ("terrain.model.standstill", "shear"),
            ("terrain.xt", 0.8),
            ("mode.speed_mps", 0.0),
            ("mode.start_time_s", 0.0),
            ("tow.force_N", pull_N),
            ("vehicle.segment.speed_ki_Nm_per_rad", ki),
            ("simulation.duration_s", 20.0),
        ],
    )
    tp, R = sc.terrain.model.params(), SEG["wheel_radius_m"]
    F_n = SEG["mass_kg"] * SEG["gravity_mps2"] / 4
    i = brentq(lambda i: terrain.traction_force(i, F_n, 0.8, tp) - pull_N / 4, 0.0, 0.43, xtol=1e-14)
    K = tp.shear_modulus_K_m
    hand = K * np.log(1.0 / (1.0 - i)) + R * R * pull_N / (4 * ki)
    r = simulate(sc)
    assert -r.segments["x_m"][-1, 0] == pytest.approx(hand, rel=1e-3)
    assert r.segments["slip"][-1, 0] == pytest.approx(i, rel=1e-6)
    assert -r.segments["x_m"][-1, 0] < K  # a push below the peak moves a held segment less than K
