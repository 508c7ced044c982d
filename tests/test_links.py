"""Link law (snoworm.links): spring, damper, link force and the prismatic actuator's limits.

docs/model.md section 4: ``T_k = k_c (x_k - x_{k+1} - L_0 - s_k) + c_c (v_k - v_{k+1} - ds_k/dt)``,
tension positive.  Hand values use the FrostyBoy link values k_c = 2e4 N/m, c_c = 1.5e3 N s/m.
"""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from snoworm import links

K_C, C_C = 2.0e4, 1.5e3  # docs/model.md section 4 [assumed]
S_MIN, S_MAX, RATE_MAX = 0.0, 0.3, 0.5  # prismatic joint travel [m] and rate limit [m/s]


def rate(cmd, s, rate_max=RATE_MAX, k_stop=links.K_STOP):
    return links.actuator_rate_mps(cmd, s, rate_max, -rate_max, S_MIN, S_MAX, k_stop)


def test_spring_force_hand_values():
    # fixed link: 1 cm stretch -> 200 N tension; 2 mm compression -> -40 N
    np.testing.assert_allclose(links.spring_force_N(np.array([0.01, -0.002]), None, K_C), [200.0, -40.0], rtol=1e-12)
    # prismatic link: the actuator extension takes up stretch, 0.12 m - 0.1 m = 2 cm -> 400 N
    assert links.spring_force_N(0.12, 0.1, K_C) == pytest.approx(400.0, rel=1e-12)
    assert links.spring_force_N(0.1, 0.1, K_C) == pytest.approx(0.0, abs=1e-9)


def test_link_force_is_spring_plus_damper():
    # 300 N spring, closing speed 0.02 m/s -> 300 + 1500 * 0.02 = 330 N
    assert links.link_force_N(300.0, 0.02, C_C) == pytest.approx(330.0, rel=1e-12)
    # opening speed: the damper pushes, 300 - 1500 * 0.1 = 150 N
    assert links.link_force_N(300.0, -0.1, C_C) == pytest.approx(150.0, rel=1e-12)


def test_damper_power_is_dissipative():
    # c (dv)^2: 1500 * 0.02^2 = 0.6 W, and the same for the opposite sign
    np.testing.assert_allclose(links.damper_power_W(np.array([0.02, -0.02, 0.0]), C_C), [0.6, 0.6, 0.0], rtol=1e-12)


def test_actuator_rate_hand_values():
    # mid-stroke: the rate limit clips the command
    assert rate(2.0, 0.15) == pytest.approx(RATE_MAX)
    assert rate(-2.0, 0.15) == pytest.approx(-RATE_MAX)
    assert rate(0.2, 0.15) == pytest.approx(0.2)
    # 1 mm before the upper stop: at most K_STOP * 0.001 = 0.05 m/s outward, inward unaffected
    assert rate(0.4, S_MAX - 0.001) == pytest.approx(links.K_STOP * 0.001, rel=1e-9)
    assert rate(-0.4, S_MAX - 0.001) == pytest.approx(-0.4)
    # beyond the lower stop (numerical overshoot): driven back towards the stroke
    assert rate(-0.4, S_MIN - 0.002) == pytest.approx(links.K_STOP * 0.002, rel=1e-9)


@settings(max_examples=200, deadline=None)
@given(
    cmd=st.floats(-10.0, 10.0), s=st.floats(S_MIN, S_MAX), rate_max=st.floats(0.01, 2.0), k_stop=st.floats(1.0, 200.0)
)
def test_actuator_rate_within_limits_and_stops(cmd, s, rate_max, k_stop):
    """Inside the stroke: |ds/dt| <= rate_max, and an explicit Euler step of any length up to
    1 / k_stop never crosses a stop (the soft stop rate is k_stop times the distance to it)."""
    r = float(rate(cmd, s, rate_max, k_stop))
    tol = 1e-12
    assert -rate_max - tol <= r <= rate_max + tol
    assert r <= k_stop * (S_MAX - s) + tol  # never drives s beyond the upper stop
    assert r >= k_stop * (S_MIN - s) - tol  # nor below the lower stop
    s_next = s + r / k_stop
    assert S_MIN - 1e-12 <= s_next <= S_MAX + 1e-12
    # a command that respects every limit is delivered unchanged
    if abs(cmd) <= rate_max and k_stop * (S_MIN - s) <= cmd <= k_stop * (S_MAX - s):
        assert r == cmd
