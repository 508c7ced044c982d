"""Terrain laws (docs/model.md section 2): hand-computed values and properties (hypothesis)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from snoworm import terrain
from snoworm.config.params import terrain_params
from snoworm.terrain import TerrainProfile

TP = terrain_params("frostyboy")

FN = 90 * 9.81 / 4  # static normal force per wheel [N]
RW = 0.265


def test_traction_hand_value():
    # Eq. 2 by hand at X = 1, i = 2 %: 220.725 * 0.7 * sin(2.8 atan(atan(0.08)))
    inner = math.atan(math.atan(4 * 1.0 * 0.02))
    expected = FN * 0.7 * math.sin(2.8 * 1.0 * inner)
    assert terrain.traction_force(0.02, FN, 1.0, TP) == pytest.approx(expected, rel=1e-12)
    assert expected == pytest.approx(34.18, abs=0.01)  # by hand: 154.5 N * sin(0.22305)


def test_resistance_hand_values():
    # Eq. 3: b_trF F_n / X^A, forward motion well above the smooth-sign scale
    assert terrain.resistance_force(1.0, FN, 1.0, TP) == pytest.approx(0.165 * FN, rel=1e-9)
    assert terrain.resistance_force(1.0, FN, 0.25, TP) == pytest.approx(0.165 * FN / 0.25**0.6, rel=1e-9)
    # docs/model.md section 5: ~335 N per 4-wheel segment at X = 0.25
    assert abs(4 * terrain.resistance_force(1.0, FN, 0.25, TP) - 335) < 1.0


def test_resistance_torque_matches_table2_torques():
    # free running: T_m = T_rr; Table 2 cases 1 and 5 (10 N m at X = 1, 45 N m at X = 0.65)
    assert abs(terrain.resistance_torque(1.0, FN, 1.0, RW, TP) - 10.0) < 0.05
    assert abs(terrain.resistance_torque(1.0, FN, 0.65, RW, TP) - 45.0) < 0.05


def test_locked_wheel_slip_is_finite():
    assert terrain.slip(0.0, 0.0, 0.05) == 0.0
    assert terrain.slip(0.0, -0.3, 0.05) == 1.0  # locked, sliding backward: full braking slip
    assert terrain.slip(0.0, 0.3, 0.05) == -1.0
    assert terrain.slip(2.0, 1.9, 0.05) == pytest.approx(0.05)  # equals Eq. 1 when driving


speeds = st.floats(-5, 5, allow_nan=False)
slips = st.floats(-1, 1, allow_nan=False)
xts = st.floats(0.05, 1.5, allow_nan=False)


@given(slips, xts)
def test_traction_odd_and_bounded(i, X):
    f = terrain.traction_force(i, FN, X, TP)
    assert terrain.traction_force(-i, FN, X, TP) == -f
    assert abs(f) <= FN * X**TP.peak_exponent_d * TP.b_tF * (1 + 1e-12)


@given(speeds, speeds)
def test_slip_finite_and_bounded(wheel, V):
    i = terrain.slip(wheel, V, TP.slip_eps_mps)
    assert np.isfinite(i) and -1 - 1e-12 <= i <= 1 + 1e-12


@given(xts, xts, st.floats(0.001, 5))
def test_resistance_falls_as_xt_rises(x1, x2, V):
    lo, hi = sorted((x1, x2))
    if hi - lo < 1e-6:
        return
    assert terrain.resistance_force(V, FN, hi, TP) < terrain.resistance_force(V, FN, lo, TP)


@settings(max_examples=50)
@given(st.lists(st.floats(-50, 50), min_size=1, max_size=10))
def test_profile_constant_and_interp(xs):
    p = TerrainProfile.constant(0.7)
    assert np.all(p(np.array(xs)) == 0.7)
    q = TerrainProfile((0.0, 10.0), (0.9, 0.3))
    v = q(np.array(xs))
    assert np.all((v >= 0.3 - 1e-12) & (v <= 0.9 + 1e-12))
    assert q(5.0) == pytest.approx(0.6)
