"""Control laws (snoworm.feedback): wheel-speed PI, link-force PI, prismatic-joint servos.

docs/model.md section 4 (controllers) and section 5 (force control, inchworm joints).
"""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from snoworm import drivetrain, feedback

SLOPE, WNL, TMAX = 10.0507, 18.326, 88.64


def test_pi_clips_to_envelope_and_winds_back():
    lo, hi = drivetrain.motor_envelope(0.0, SLOPE, WNL, TMAX)
    T, dI = feedback.speed_pi(5.0, 0.0, 200.0, 30.0, 150.0, lo, hi, 1.0)
    assert T == pytest.approx(TMAX)
    # saturated with a large integral: back-calculation pulls the integral down
    assert dI < 0


def test_pi_off_before_start():
    T, dI = feedback.speed_pi(5.0, 0.0, 10.0, 30.0, 150.0, -TMAX, TMAX, 0.0)
    assert T == 0 and dI == 0


def test_pi_unsaturated_integrates_error():
    T, dI = feedback.speed_pi(1.0, 0.5, 2.0, 30.0, 150.0, -TMAX, TMAX, 1.0)
    assert T == pytest.approx(30.0 * 0.5 + 2.0)
    assert dI == pytest.approx(150.0 * 0.5)


def test_pi_fast_path_is_the_masked_law():
    """on=None (every motor runs) and a precomputed ki/kp give the masked law with on = 1, to
    rounding (1e-14 relative: the two paths may round a product differently on another CPU)."""
    rng = np.random.default_rng(3)
    w_ref, w, integ = rng.normal(5, 3, (6, 2)), rng.normal(5, 3, (6, 2)), rng.normal(0, 50, (6, 2))
    kp, ki = np.full((6, 1), 30.0), np.full((6, 1), 150.0)
    lo, hi = drivetrain.motor_envelope(w, SLOPE, WNL, TMAX)
    T0, dI0 = feedback.speed_pi(w_ref, w, integ, kp, ki, lo, hi, np.ones((6, 1)))
    T1, dI1 = feedback.speed_pi(w_ref, w, integ, kp, ki, lo, hi, None, ki / kp)
    np.testing.assert_allclose(T1, T0, rtol=1e-14, atol=1e-12)
    np.testing.assert_allclose(dI1, dI0, rtol=1e-14, atol=1e-12)
    assert np.any(T0 == hi) or np.any(T0 == lo)  # the sample reaches the envelope's clip too


# ------------------------------------------------------------------ link-force PI (force control, Figs 8-11)

KP_F, KI_F, VNOM, VMAX = 0.01, 0.02, 1.8, 3.0  # [m/(s N)], [m/(s^2 N)], [m/s], [m/s]


def test_link_force_pi_unsaturated_hand_values():
    # sigma = +1 (link behind): 50 N below the reference -> drive faster by kp * 50 = 0.5 m/s
    vsp, dq = feedback.link_force_pi(50.0, 100.0, 1.0, 0.1, VNOM, KP_F, KI_F, VMAX)
    assert vsp == pytest.approx(VNOM + 0.5 + 0.1, rel=1e-12)
    assert dq == pytest.approx(KI_F * 50.0, rel=1e-12)
    # sigma = -1 (link ahead): the same error slows the segment
    vsp, dq = feedback.link_force_pi(50.0, 100.0, -1.0, 0.0, VNOM, KP_F, KI_F, VMAX)
    assert vsp == pytest.approx(VNOM - 0.5, rel=1e-12)
    assert dq == pytest.approx(-KI_F * 50.0, rel=1e-12)


def test_link_force_pi_setpoint_clipped_to_0_vmax():
    F = np.array([-1e4, 0.0, 1e4])
    vsp, _ = feedback.link_force_pi(F, 0.0, 1.0, 0.0, VNOM, KP_F, KI_F, VMAX)
    np.testing.assert_allclose(vsp, [VMAX, VNOM, 0.0], rtol=0, atol=1e-12)  # never negative, never above vmax


@pytest.mark.parametrize("q, sign", [(5.0, -1.0), (-5.0, 1.0)])
def test_link_force_pi_anti_windup_pulls_integral_back(q, sign):
    """Saturated (above vmax with q = 5, below 0 with q = -5) at zero force error: the
    back-calculation term moves q back towards the unsaturated range."""
    vsp, dq = feedback.link_force_pi(100.0, 100.0, 1.0, q, VNOM, KP_F, KI_F, VMAX)
    assert vsp == (VMAX if q > 0 else 0.0)
    assert np.sign(dq) == sign
    raw = VNOM + q
    assert dq == pytest.approx((KI_F / KP_F) * (vsp - raw), rel=1e-12)


# ------------------------------------------------------------------ prismatic joint servos (inchworm)

ZERO = np.array(0.0)


def test_joint_force_command_clipped_to_0_limit():
    np.testing.assert_allclose(
        feedback.joint_force_command_N(np.array([-50.0, 200.0, 900.0]), 390.0, ZERO),
        [0.0, 200.0, 390.0],
        rtol=0,
        atol=0,
    )


def test_joint_force_command_optional_terms():
    # speed loop only: 200 + 500 * (0.3 - 0.1) = 300 N
    assert feedback.joint_force_command_N(
        200.0, 390.0, ZERO, kv=500.0, v_target_mps=0.3, v_mover_mps=0.1
    ) == pytest.approx(300.0, rel=1e-12)
    # anchor term only: the anchor slides back at 0.05 m/s -> 200 - 1000 * 0.05 = 150 N
    assert feedback.joint_force_command_N(200.0, 390.0, ZERO, ka=1000.0, v_anchor_mps=-0.05) == pytest.approx(
        150.0, rel=1e-12
    )
    # an anchor moving forward does not change the command
    assert feedback.joint_force_command_N(200.0, 390.0, ZERO, ka=1000.0, v_anchor_mps=0.05) == pytest.approx(
        200.0, rel=1e-12
    )
    # both terms: 200 + 100 - 50 = 250 N; gains None: the feed-forward alone
    assert feedback.joint_force_command_N(
        200.0, 390.0, ZERO, kv=500.0, v_target_mps=0.3, v_mover_mps=0.1, ka=1000.0, v_anchor_mps=-0.05
    ) == pytest.approx(250.0, rel=1e-12)
    assert feedback.joint_force_command_N(200.0, 390.0, ZERO) == pytest.approx(200.0, rel=1e-12)


def test_servo_gain_hand_value():
    # g / k / (1 + c g / k) = 50 / 2e4 / (1 + 1500 * 50 / 2e4) = 2.5e-3 / 4.75
    assert feedback.servo_gain(50.0, 2.0e4, 1.5e3) == pytest.approx(2.5e-3 / 4.75, rel=1e-12)


def _length_rate(s, ref, vt, spring, limit, rel=0.0, gain=2.5e-3 / 4.75):
    return feedback.joint_length_rate_mps(s, ref, vt, -vt, rel, spring, limit, gain, feedback.K_LENGTH)


def test_joint_length_rate_hand_values():
    # far from the reference: the rate target; close to it: K_LENGTH * (s_ref - s)
    assert _length_rate(0.0, 0.3, 0.2, 0.0, 390.0) == pytest.approx(0.2, rel=1e-12)
    assert _length_rate(0.3, 0.0, 0.2, 0.0, 390.0) == pytest.approx(-0.2, rel=1e-12)
    assert _length_rate(0.295, 0.3, 0.2, 0.0, 390.0) == pytest.approx(feedback.K_LENGTH * 0.005, rel=1e-9)
    # spring already compressed to the force limit: extending further is refused (rate 0)
    assert _length_rate(0.0, 0.3, 0.2, -390.0, 390.0) == pytest.approx(0.0, abs=1e-15)


@settings(max_examples=200, deadline=None)
@given(
    s=st.floats(-0.1, 0.4),
    ref=st.floats(0.0, 0.3),
    vt=st.floats(0.01, 1.0),
    frac=st.floats(-1.0, 1.0),
    limit=st.floats(10.0, 400.0),
)
def test_joint_length_rate_bounded_by_v_target(s, ref, vt, frac, limit):
    """With the link force inside its limits (|T_spring| <= F_lim, no relative motion) the rate
    never exceeds the rate target, and it moves s towards the reference."""
    r = float(_length_rate(s, ref, vt, frac * limit, limit))
    assert -vt - 1e-12 <= r <= vt + 1e-12
    assert r * (ref - s) >= 0.0


def test_direct_torque_clips_to_envelope_and_freezes_the_integral():
    w = np.array([0.0, 5.0, 17.0])
    lo, hi = drivetrain.motor_envelope(w, SLOPE, WNL, TMAX)
    T_pi, dI_pi = np.full(3, 7.0), np.full(3, 3.0)
    T, dI = feedback.direct_torque(np.array([1e3, -1e3, 20.0]), lo, hi, np.array([True, True, False]), T_pi, dI_pi)
    np.testing.assert_allclose(T, [hi[0], lo[1], 7.0])
    np.testing.assert_array_equal(dI, [0.0, 0.0, 3.0])
    assert T[0] == pytest.approx(TMAX) and hi[2] < TMAX  # the envelope falls with speed
