"""Motor envelope at the wheel (docs/model.md section 1); the wheel-speed PI is in test_feedback.py."""

import numpy as np
import pytest

from snoworm import drivetrain

SLOPE, WNL, TMAX = 10.0507, 18.326, 88.64


def test_envelope_values():
    lo, hi = drivetrain.motor_envelope(np.array([0.0, 10.0, WNL]), SLOPE, WNL, TMAX)
    assert hi[0] == pytest.approx(TMAX)  # stall: torque limit
    assert hi[1] == pytest.approx(SLOPE * (WNL - 10.0))  # on the torque-speed line (83.6 N m)
    assert hi[2] == pytest.approx(0.0, abs=1e-12)  # no-load speed: no torque
    assert lo[0] == pytest.approx(-TMAX)
