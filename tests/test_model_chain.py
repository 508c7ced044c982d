"""Chain kernel invariants (snoworm.model.chain): momentum of internal forces, stacking.

The named state layout is in test_model_arrays.py; the Jacobian pattern and banded finite
differences are in test_model_jacobian.py."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from snoworm.dynamics import Controls
from tests.conftest import SCENARIOS, TERRAIN_LAWS, busy_controls, model_for, random_state


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000))
def test_internal_link_forces_cancel(seed):
    """Links only move momentum between segments: sum of connector forces = -tow (docs/model.md section 4)."""
    rng = np.random.default_rng(seed)
    m = model_for(SCENARIOS / "tow6_uniform.yaml", [("vehicle.links.type", "prismatic")], force_loop=True)
    Y = m.unpack(random_state(m, rng))
    _, out = m.evaluate(Y, busy_controls(m, rng), outputs=True)
    assert out["link_net_N"].sum() == pytest.approx(-m.tow_force_N, abs=1e-9 * (1 + np.abs(out["link_force_N"]).sum()))


@pytest.mark.parametrize("standstill", list(TERRAIN_LAWS))
def test_stacked_model_is_the_members_side_by_side(scenario_path, standstill):
    """ChainModel.stack: same derivatives and block-banded Jacobian as each member alone."""
    from snoworm.dynamics import ChainModel

    rng = np.random.default_rng(3)
    ms = [
        model_for(
            scenario_path("tow6_uniform"),
            [("terrain.xt", xt), ("tow.force_N", f), *TERRAIN_LAWS[standstill]],
        )
        for xt, f in [(0.7, 0.0), (0.9, 200.0), (1.0, 50.0)]
    ]
    big = ChainModel.stack(ms)
    ys = [random_state(m, rng) for m in ms]
    ctls = [Controls.rolling(6, np.ones(6), rng.uniform(0, 2, 6)) for _ in ms]
    ctl = Controls.stack(ctls)
    f = big.rhs(0.0, np.concatenate(ys), ctl).reshape(3, -1)
    J = big.jacobian_banded(0.0, np.concatenate(ys), ctl)
    n = ms[0].n_states
    for b, m in enumerate(ms):
        # the same laws on arrays of another shape: equal to rounding (SIMD loops may split differently)
        np.testing.assert_allclose(f[b], m.rhs(0.0, ys[b], ctls[b]), rtol=1e-13, atol=1e-9)
        np.testing.assert_allclose(
            J[:, b * n : (b + 1) * n], m.jacobian_banded(0.0, ys[b], ctls[b]), rtol=1e-7, atol=1e-6
        )
    assert big.bandwidths() == ms[0].bandwidths()


def test_direct_torque_replaces_the_speed_pi_only_where_commanded():
    from snoworm.drivetrain import motor_envelope

    m = model_for(SCENARIOS / "tow6_uniform.yaml")
    y = random_state(m, np.random.default_rng(7))
    Y = m.unpack(y)
    base = Controls.rolling(m.n, np.ones(m.n), np.full(m.n, 1.8))
    dY0, out0 = m.evaluate(Y, base, outputs=True)
    ctl = base.with_(torque_active=np.r_[1.0, np.zeros(m.n - 1)], torque_cmd_Nm=np.full(m.n, 12.0))
    dY1, out1 = m.evaluate(Y, ctl, outputs=True)
    lo, hi = motor_envelope(Y[0, m.layout.omega], m._slope[0], m._wnl[0], m._Tmax[0])
    np.testing.assert_allclose(out1["motor_torque_Nm"][0], np.clip(12.0, lo, hi), rtol=1e-15)
    np.testing.assert_array_equal(out1["motor_torque_Nm"][1:], out0["motor_torque_Nm"][1:])
    np.testing.assert_array_equal(dY1[0, m.layout.integral], 0.0)  # the PI integral frozen there
    np.testing.assert_array_equal(dY1[1:, m.layout.integral], dY0[1:, m.layout.integral])
