"""Slopes (snoworm.slope, docs/model.md section 7): the elevation profile and the grade in the chain physics.

Analytic checks of the model on a grade, each against the kernel or the dynamic simulation:
coasting on a constant slope, a chain with locked wheels holding or sliding, steady rolling
(drawbar drop) and the energy balance with the potential term; Eqs. 4-6 with gravity.
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from snoworm import load_scenario, simulate, steady, terrain
from snoworm.model.inputs import Controls
from snoworm.results.energy import energy_balance, energy_metrics
from snoworm.simulation.driver import chain_model
from snoworm.slope import MAX_GRADE_DEG, ElevationProfile, grade_patch_profile

G0 = 9.81


def _model(grade_deg, xt, segments=1, links="fixed", com_height_m=None):
    sets = [
        f"terrain.xt={xt}",
        f"terrain.grade_deg={grade_deg}",
        f"vehicle.segments={segments}",
        f"vehicle.links.type={links}",
        "tow.force_N=0",
    ]
    if com_height_m is not None:
        sets.append(f"vehicle.segment.com_height_m={com_height_m}")
    sc = load_scenario("tow6_uniform", sets)
    return sc, chain_model(sc)


def _coefficients(tp, X):
    """Per unit normal load: locked-wheel traction (Eq. 2 at |i| = 1), resistance (Eq. 3), resistance torque / R."""
    c_t = float(terrain.traction_force(1.0, 1.0, X, tp))
    c_r = float(terrain.resistance_force(np.inf, 1.0, X, tp))
    return c_t, c_r


# ------------------------------------------------------------------ the profile
@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-0.5, 0.5), min_size=2, max_size=8), st.floats(0.2, 2.0), st.floats(-20.0, 40.0))
def test_mean_elevation_rises_by_the_chord_grade(rises, half_base, s0):
    """d/ds of the wheelbase-mean elevation is the chord grade (so gravity's work is m g dz, exactly)."""
    pos = np.cumsum(np.r_[0.0, np.full(len(rises), 3.0)])
    z = np.cumsum(np.r_[0.0, np.array(rises) * 3.0])
    prof = ElevationProfile(tuple(pos), tuple(z))
    ds = 1e-5
    num = (prof.mean_elevation(s0 + ds, half_base) - prof.mean_elevation(s0 - ds, half_base)) / (2 * ds)
    # central difference of a piecewise quadratic: exact but where a knot lies within ds of s -+ h, where
    # it is off by at most ds |jump of dz/ds| / (2 h) <= 1e-5 * 1 / 0.4 = 2.5e-5 (and rounding, ~1e-11)
    assert num == pytest.approx(float(prof.sin_grade(s0, half_base)), abs=3e-5)


def test_constant_grade_and_patches():
    c = ElevationProfile.constant(8.0)
    assert float(c.sin_grade(12.3, 0.5)) == pytest.approx(math.sin(math.radians(8.0)), rel=1e-15)
    assert float(c.elevation(10.0)) == pytest.approx(10 * math.sin(math.radians(8.0)), rel=1e-15)
    assert ElevationProfile.constant(0.0).is_level and not c.is_level
    p = grade_patch_profile(2.0, [(10.0, 20.0, 12.0, 1.0)])
    s2, s12 = math.sin(math.radians(2.0)), math.sin(math.radians(12.0))
    assert float(p.sin_grade(15.0, 0.5)) == pytest.approx(s12, rel=1e-12)  # inside the patch
    assert float(p.sin_grade(30.0, 0.5)) == pytest.approx(s2, rel=1e-12)  # after it
    assert float(p.sin_grade(-30.0, 0.5)) == pytest.approx(s2, rel=1e-12)  # before it
    # the patch's rise: 10 m at 12 deg plus two 1 m ramps at the mean sine
    rise = float(p.elevation(21.0) - p.elevation(9.0))
    assert rise == pytest.approx(10 * s12 + 2 * 0.5 * (s2 + s12), rel=1e-12)
    assert p.max_abs_grade_deg() == pytest.approx(12.0, rel=1e-9)


def test_normal_load_law():
    """F_n = W (cos -+ 2h/b sin), front and rear: sums to the segment's W cos(theta) per wheel pair."""
    W, th, t = 220.725, math.radians(10.0), 2 * 0.4 / 1.094
    Fn = terrain.normal_load_N(np.array([W]), np.array([math.sin(th)]), np.array([math.cos(th)]), np.array([t]))
    assert Fn[0, 0] < Fn[0, 1]  # uphill: the rear axle carries more
    assert Fn[0].sum() == pytest.approx(2 * W * math.cos(th), rel=1e-15)
    assert Fn[0, 1] - Fn[0, 0] == pytest.approx(2 * W * t * math.sin(th), rel=1e-14)


# ------------------------------------------------------------------ coasting
@pytest.mark.parametrize("grade", [8.0, -6.0])
def test_coasting_segment_decelerates_by_gravity_and_resistance(grade):
    """Motors off, one segment rolling at 8 m/s on a constant grade.  The contact torque balance of
    section 2 passes F_t - F_tr = -(T_rr + J dw/dt)/R per wheel to the chassis, so over any interval

        m dv = -m g sin(theta) dt - n_w sum_axles (T_rr(F_n,axle) dt + J dw_axle) / R

    with T_rr at the axle's normal load (F_n = W (cos(theta) -+ 2h/b sin(theta)), summing to
    2 W cos(theta)).  Checked on the simulated v and w over [0.3, 0.9] s, where the smooth signs are
    saturated (speeds > 1 m/s): to the solver tolerance (rtol 1e-10), 1e-7 relative.  Without the
    cos(theta) in F_n the balance would be off by 0.5-1 %, without gravity by 20-30 %."""
    sc, m = _model(grade, 0.8)
    L = m.layout
    seg, tp = sc.vehicle.segment_params()[0], m.tp
    y0 = m.initial_state().reshape(m.n, L.n_s)
    y0[0, L.v] = 8.0
    y0[0, L.omega] = 8.0 / seg.wheel_radius_m
    ctl = Controls.rolling(1, 0.0, 0.0)
    sol = solve_ivp(
        m.rhs,
        (0.0, 0.9),
        y0.reshape(-1),
        args=(ctl,),
        method="Radau",
        rtol=1e-10,
        atol=1e-12,
        t_eval=[0.3, 0.9],
        jac=lambda t, y, c: m.jacobian_sparse(t, y, c),
    )
    assert sol.success
    Y = m.unpack(sol.y.T)
    v, w = Y[:, 0, L.v], Y[:, 0, L.omega]
    assert v.min() > 1.0 and w.min() * seg.wheel_radius_m > 1.0  # still rolling: sgn() saturated
    dt = 0.6
    th = math.radians(grade)
    n_w, R, J = seg.wheels_per_axle, seg.wheel_radius_m, seg.wheel_inertia_kgm2
    W = seg.mass_kg * seg.gravity_mps2 / (2 * n_w)
    t = 2 * seg.com_height_m / seg.wheelbase_m
    Fn = np.array([W * (math.cos(th) - t * math.sin(th)), W * (math.cos(th) + t * math.sin(th))])
    T_rr = terrain.resistance_torque(1.0, Fn, 0.8, R, tp)
    lhs = seg.mass_kg * (v[1] - v[0])
    rhs = -seg.mass_kg * seg.gravity_mps2 * math.sin(th) * dt - n_w * np.sum(T_rr * dt + J * (w[1] - w[0])) / R
    assert lhs == pytest.approx(rhs, rel=1e-7)


# ------------------------------------------------------------------ locked wheels on a slope
def _hold_angle_deg(tp, X):
    """Static balance, per unit normal load: m g sin(theta) = m g cos(theta) (c_t + c_r)."""
    c_t, c_r = _coefficients(tp, X)
    return math.degrees(math.atan(c_t + c_r))


@pytest.mark.parametrize("factor", [0.9, 1.1])
def test_locked_chain_holds_or_slides_where_the_terrain_law_says(factor):
    """Two segments, wheels locked (PI to zero speed), at rest on an uphill of factor x the hold angle
    theta* = atan(c_t(1) + c_r) (locked-wheel traction of Eq. 2 at |i| = 1 plus the Eq. 3 resistance):
    below it the chain creeps back at the speed where the smooth laws balance gravity and settles; above it the
    chain slides back with the analytic acceleration g (sin(theta) - cos(theta) (c_t + c_r))."""
    X = 0.5
    sc0, m0 = _model(0.0, X, 2)
    th_star = _hold_angle_deg(m0.tp, X)
    assert 15 < th_star < MAX_GRADE_DEG
    grade = factor * th_star
    sc, m = _model(grade, X, 2, com_height_m=0.0)
    ctl = Controls.rolling(2, 1.0, 0.0)
    L = m.layout
    sol = solve_ivp(
        m.rhs,
        (0.0, 6.0),
        m.initial_state(),
        args=(ctl,),
        method="Radau",
        rtol=1e-9,
        atol=1e-10,
        t_eval=[5.0, 6.0],
        jac=lambda t, y, c: m.jacobian_sparse(t, y, c),
    )
    assert sol.success
    v = sol.y[[L.flat_index(k, "v_mps") for k in range(2)]].mean(0)
    th = math.radians(grade)
    c_t, c_r = _coefficients(m.tp, X)
    if factor < 1:
        # holds: creeps back at the speed V* where the laws balance gravity, with the locked wheel's slip
        # |V|/v_eps (regularised Eq. 1) and the smooth sign of Eq. 3:  c_t(|V|/v_eps) + c_r tanh(|V|/v_s) = tan(theta)
        tp = m.tp

        def bal(u):
            return (
                float(terrain.traction_force(u / tp.slip_eps_mps, 1.0, X, tp))
                + float(terrain.resistance_force(u, 1.0, X, tp))
                - math.tan(th)
            )

        creep = brentq(bal, 1e-9, tp.slip_eps_mps)
        assert abs(v[1] - v[0]) < 1e-3  # settled (sliding would be ~0.4 m/s^2)
        # 10 %: the PI holds w at 0 only up to its integral's lag, so the wheel turns back slightly and the
        # slip is a little below |V|/v_eps (measured 6 %); a slide would be orders of magnitude faster
        assert -v[-1] == pytest.approx(creep, rel=0.1) and -v[-1] < tp.slip_eps_mps
    else:
        a = (v[1] - v[0]) / 1.0
        assert v[-1] < -1.0  # slides back
        # 5e-3 (measured 1.0e-3): the PI-held wheel turns slightly (|i| just below 1) while its integral settles
        assert a == pytest.approx(-G0 * (math.sin(th) - math.cos(th) * (c_t + c_r)), rel=5e-3)


# ------------------------------------------------------------------ steady rolling on a grade
@pytest.mark.parametrize("grade", [3.0, 10.0])
def test_drawbar_drops_by_gravity_and_the_cos_change(grade):
    """Largest steady drawbar of one segment: D(theta) = cos(theta) D(0) - m g sin(theta) (the laws are
    linear in F_n = W cos(theta)); for a chain of N, N times that."""
    sc, m = _model(0.0, 0.9)
    seg, tp = sc.vehicle.segment_params()[0], m.tp
    th = math.radians(grade)
    d0 = steady.max_drawbar_N(0.9, seg, tp, 1.8)
    dg = steady.max_drawbar_N(0.9, seg, tp, 1.8, grade_deg=grade)
    assert dg == pytest.approx(math.cos(th) * d0 - seg.mass_kg * G0 * math.sin(th), rel=1e-9)
    # the steepest grade is the root of the same balance (analytic: A cos - B sin = C)
    A, B, C = d0, seg.mass_kg * G0, 20.0
    phi = math.atan2(B, A)
    assert steady.max_grade_deg(0.9, seg, tp, 1.8, C) == pytest.approx(
        math.degrees(math.acos(C / math.hypot(A, B)) - phi), abs=1e-7
    )


def test_steady_on_grade_matches_the_simulation():
    """tow6 at X_t = 0.9, 200 N, 5 deg: the dynamic steady state (slip, speed, torque, wheel force)
    equals steady.steady_state(..., grade_deg=5) to the solver tolerance."""
    sc = load_scenario("tow6_uniform", ["terrain.grade_deg=5", "simulation.rtol=1e-8"])
    res = simulate(sc)
    seg, tp = sc.vehicle.segment_params()[0], sc.terrain.model.params()
    ss = steady.steady_state(0.9, seg, tp, drawbar_N=200 / 6, wheel_speed_mps=1.8, grade_deg=5.0)
    s = res.segments
    np.testing.assert_allclose(s["slip"][-1], ss.slip, rtol=1e-5)
    np.testing.assert_allclose(s["v_mps"][-1], ss.ground_speed_mps, rtol=1e-6)
    np.testing.assert_allclose(s["motor_torque_Nm"][-1], ss.torque_Nm, rtol=1e-5)
    np.testing.assert_allclose(s["net_force_N"][-1], 200 / 6 + seg.mass_kg * G0 * math.sin(math.radians(5)), rtol=1e-5)
    np.testing.assert_allclose(s["grade_deg"][-1], 5.0, rtol=1e-12)
    np.testing.assert_allclose(s["gravity_N"][-1], -seg.mass_kg * G0 * math.sin(math.radians(5)), rtol=1e-12)


def test_max_grade_against_the_simulation():
    """A chain rolling onto a slope: just below the steady maximum grade it keeps climbing, just above
    it it stalls.  (From rest on the slope the wheels pass through high slip, beyond the peak of the
    drawbar, and the chain can stall below this grade: the steady limit is for a rolling chain.)"""
    sc = load_scenario("tow6_uniform", ["terrain.xt=0.8", "tow.force_N=0", "simulation.duration_s=16"])
    seg, tp = sc.vehicle.segment_params()[0], sc.terrain.model.params()
    g_max = steady.max_grade_deg(0.8, seg, tp, 1.8)
    speeds = {}
    for g in (g_max - 0.5, g_max + 0.5):
        res = simulate(
            sc.with_(
                {
                    "terrain.grade_deg": 0.0,
                    "terrain.grade_patches": [{"start_m": 4.0, "end_m": 500.0, "grade_deg": g, "ramp_m": 2.0}],
                }
            )
        )
        np.testing.assert_allclose(res.segments["grade_deg"][-1], g, rtol=1e-9)  # the whole chain on the slope
        speeds[g] = float(res.segments["v_mps"][-1].mean())
    below = steady.steady_state(0.8, seg, tp, wheel_speed_mps=1.8, grade_deg=g_max - 0.5)
    assert speeds[g_max - 0.5] == pytest.approx(below.ground_speed_mps, rel=1e-3)  # climbs at the steady speed
    assert speeds[g_max + 0.5] < 0.2  # past the peak slip: falls to a crawl, spinning


# ------------------------------------------------------------------ energy with gravity
@settings(max_examples=3, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_energy_balance_closes_with_the_potential_term(seed):
    """Rolling over a random elevation profile: motor work = dissipation + tow + kinetic + spring +
    m g dz, residual within 0.5 % of the throughput (the tolerance of the level tests: trapezoidal
    rule on 10 ms samples), and the potential term is far larger than the residual."""
    rng = np.random.default_rng(seed)
    pos = np.arange(-10.0, 60.0, 5.0)
    z = np.cumsum(np.r_[0.0, rng.uniform(-0.15, 0.2, pos.size - 1) * 5.0])
    table = "[" + ",".join(f"[{p:g},{v:.6g}]" for p, v in zip(pos, z)) + "]"
    sc = load_scenario(
        "tow6_uniform",
        [
            f"terrain.elevation={table}",
            "simulation.duration_s=8",
            "simulation.output_dt_s=0.01",
            "simulation.rtol=1e-7",
        ],
    )
    res = simulate(sc)
    b = energy_balance(res)
    assert abs(b["residual_J"]) < 5e-3 * b["throughput_J"]
    assert abs(b["potential_change_J"]) > 20 * abs(b["residual_J"]) or abs(b["potential_change_J"]) < 50.0
    e = energy_metrics(res)
    assert e["elevation_gain_m"] == pytest.approx(
        float(np.mean(res.segments["elevation_m"][-1] - res.segments["elevation_m"][0]))
    )


def test_level_profile_skips_the_grade_terms():
    sc = load_scenario("tow6_uniform")
    assert chain_model(sc).elevation is None
    assert chain_model(load_scenario("tow6_uniform", ["terrain.grade_deg=0"])).elevation is None
    assert chain_model(load_scenario("tow6_uniform", ["terrain.grade_deg=3"])).elevation is not None


# ------------------------------------------------------------------ Eqs. 4-6 with gravity
_eq_values = st.floats(0.0, 2000.0)


@settings(max_examples=200, deadline=None)
@given(_eq_values, _eq_values, _eq_values, _eq_values, st.floats(-500.0, 500.0), st.floats(-500.0, 500.0))
def test_eq6_with_gravity_is_eq4_plus_eq5(F_c, Ft_f, Ftr_f, Ftr_r, G_f, G_r):
    """Eq. 6 with gravity is Eq. 4 + Eq. 5 for every joint force; so some F_c satisfies both Eq. 4
    (> 0) and Eq. 5 (>= 0) exactly when Eq. 6 > 0: the largest F_c the anchor holds, F_tr,rear + G_rear,
    makes Eq. 4 equal Eq. 6."""
    from snoworm.modes.inchworm import progress_conditions

    pc = progress_conditions(F_c, Ft_f, Ftr_f, Ftr_r, G_f, G_r)
    assert pc["eq6_N"] == pytest.approx(pc["eq4_N"] + pc["eq5_N"], abs=1e-9)
    best = progress_conditions(Ftr_r + G_r, Ft_f, Ftr_f, Ftr_r, G_f, G_r)
    assert best["eq5_N"] == pytest.approx(0.0, abs=1e-9)
    assert best["eq4_N"] == pytest.approx(pc["eq6_N"], abs=1e-9)
    if pc["progress"]:
        # Eq. 6 = Eq. 4 + Eq. 5 > 0, up to the rounding of sums of forces below 3 000 N (~1e-12 N): with
        # Eq. 4 a hair above 0 and Eq. 5 exactly 0, Eq. 6 summed in another order may round to <= 0
        assert pc["eq6_N"] > -1e-9


@settings(max_examples=200, deadline=None)
@given(st.floats(0.1, 1.0), st.floats(-MAX_GRADE_DEG, MAX_GRADE_DEG), st.floats(0.0, 1.0))
def test_eq6_on_a_uniform_slope_is_a_grade_limit(X, grade, slip):
    """Two segments on a uniform slope, the front one driven at slip i, the rear one held (wheels
    locked): with the laws' forces at F_n = W cos(theta), Eq. 6 with gravity reads
    W n cos(theta) c_t(i) > 2 m g sin(theta), i.e. tan(theta) < c_t(i) / 2 (the resistances cancel)."""
    from snoworm.modes.inchworm import progress_conditions

    sc, m = _model(0.0, X)
    seg, tp = sc.vehicle.segment_params()[0], m.tp
    n = 2 * seg.wheels_per_axle
    W = seg.mass_kg * seg.gravity_mps2 / n
    th = math.radians(grade)
    Fn = W * math.cos(th)
    Ft = n * float(terrain.traction_force(slip, Fn, X, tp))
    Ftr = n * float(terrain.resistance_force(np.inf, Fn, X, tp))
    G = float(terrain.gravity_force_N(seg.mass_kg, seg.gravity_mps2, math.sin(th)))
    eq6 = progress_conditions(0.0, Ft, Ftr, Ftr, G, G)["eq6_N"]
    c_t = float(terrain.traction_force(slip, 1.0, X, tp))
    margin = math.tan(th) - c_t / 2
    if abs(margin) > 1e-9:
        assert (eq6 > 0) == (margin < 0)
