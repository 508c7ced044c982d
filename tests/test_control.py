"""Control laws (snoworm.control): wheel-speed PI, link-force PI, prismatic-joint servos.

docs/model.md section 4 (controllers) and section 5 (force control, inchworm joints).
"""
import pytest

from snoworm import control, drivetrain

SLOPE, WNL, TMAX = 10.0507, 18.326, 88.64


def test_pi_clips_to_envelope_and_winds_back():
    lo, hi = drivetrain.motor_envelope(0.0, SLOPE, WNL, TMAX)
    T, dI = control.speed_pi(5.0, 0.0, 200.0, 30.0, 150.0, lo, hi, 1.0)
    assert T == pytest.approx(TMAX)
    # saturated with a large integral: back-calculation pulls the integral down
    assert dI < 0


def test_pi_off_before_start():
    T, dI = control.speed_pi(5.0, 0.0, 10.0, 30.0, 150.0, -TMAX, TMAX, 0.0)
    assert T == 0 and dI == 0


def test_pi_unsaturated_integrates_error():
    T, dI = control.speed_pi(1.0, 0.5, 2.0, 30.0, 150.0, -TMAX, TMAX, 1.0)
    assert T == pytest.approx(30.0 * 0.5 + 2.0)
    assert dI == pytest.approx(150.0 * 0.5)
