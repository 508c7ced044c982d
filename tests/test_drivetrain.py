"""Motor envelope and wheel-speed PI (MODEL.md section 1)."""
import numpy as np
import pytest

from snoworm import control, drivetrain

SLOPE, WNL, TMAX = 10.0507, 18.326, 88.64


def test_envelope_values():
    lo, hi = drivetrain.motor_envelope(np.array([0.0, 10.0, WNL]), SLOPE, WNL, TMAX)
    assert hi[0] == pytest.approx(TMAX)                      # stall: torque limit
    assert hi[1] == pytest.approx(SLOPE * (WNL - 10.0))       # on the torque-speed line (83.6 N m)
    assert hi[2] == pytest.approx(0.0, abs=1e-12)             # no-load speed: no torque
    assert lo[0] == pytest.approx(-TMAX)


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
