"""Steady states of one driven segment by root finding (snoworm.steady), against docs/model.md.

FrostyBoy parameters, default model (d = 2), wheel speed R_w*omega = 1.8 m/s unless stated.
"""

from types import SimpleNamespace

import pytest

from snoworm import steady
from snoworm.config.params import parameter_set, terrain_params

SEG = SimpleNamespace(**parameter_set("frostyboy")["segment"])
TP = terrain_params("frostyboy")
W = 1.8  # wheel speed R_w*omega [m/s]


def test_fig6_tow_share_slip():
    """docs/model.md section 5 (Fig 6): X = 0.9, 200 N / 6 = 33.3 N per segment: slip 4.80 %, V 1.714 m/s."""
    ss = steady.steady_state(0.9, SEG, TP, wheel_speed_mps=W, drawbar_N=200.0 / 6)
    assert 100 * ss.slip == pytest.approx(4.80, abs=0.01)
    assert ss.ground_speed_mps == pytest.approx(1.714, abs=0.001)
    assert ss.drawbar_N == pytest.approx(200.0 / 6, abs=1e-6)  # the root balances the drawbar
    assert ss.wheel_speed_mps == W


@pytest.mark.parametrize("X, drawbar_N", [(1.0, 472.0), (0.9, 345.0), (0.8, 229.0), (0.7, 122.0), (0.65, 71.0)])
def test_max_drawbar_table(X, drawbar_N):
    """docs/model.md section 2 table: maximum drawbar per 4-wheel segment, within 1 N."""
    assert steady.max_drawbar_N(X, SEG, TP, W) == pytest.approx(drawbar_N, abs=1.0)


@pytest.mark.parametrize("X, slip_pct", [(1.0, 2.13), (0.9, 3.90), (0.8, 7.78), (0.7, 17.9), (0.65, 30.4)])
def test_free_running_slip_table(X, slip_pct):
    """docs/model.md section 2 table: steady free-running slip (no drawbar), within 0.05 points."""
    ss = steady.steady_state(X, SEG, TP, wheel_speed_mps=W)
    assert 100 * ss.slip == pytest.approx(slip_pct, abs=0.05)


def test_immobilisation_limit():
    """docs/model.md section 2: rolling immobilises below X = 0.586 (no tow)."""
    x_lim = steady.immobilisation_limit_xt(SEG, TP, wheel_speed_mps=W)
    assert x_lim == pytest.approx(0.586, abs=1e-3)
    assert steady.max_drawbar_N(x_lim, SEG, TP, W) == pytest.approx(0.0, abs=1e-6)


def test_immobilised_raises():
    with pytest.raises(steady.Immobilised, match="exceeds the maximum"):
        steady.steady_state(0.5, SEG, TP, wheel_speed_mps=W)
    with pytest.raises(steady.Immobilised):
        steady.steady_state(0.9, SEG, TP, wheel_speed_mps=W, drawbar_N=400.0)  # above the 345 N maximum


def test_ground_speed_form_agrees_with_wheel_speed_form():
    """Giving the ground speed instead of the wheel speed finds the same state (to root-finder tolerance)."""
    a = steady.steady_state(0.8, SEG, TP, wheel_speed_mps=W, drawbar_N=50.0)
    b = steady.steady_state(0.8, SEG, TP, ground_speed_mps=a.ground_speed_mps, drawbar_N=50.0)
    assert b.slip == pytest.approx(a.slip, abs=1e-9)
    assert b.wheel_speed_mps == pytest.approx(W, abs=1e-9)
    with pytest.raises(ValueError, match="exactly one"):
        steady.steady_state(0.8, SEG, TP)
