"""Output quantities from states (snoworm.model.quantities): the documented columns, consistent with the state."""

import numpy as np

from snoworm.model.inputs import Controls
from snoworm.model.quantities import output_series
from snoworm.results.result import LINK_COLUMNS, SEGMENT_COLUMNS
from tests.conftest import SCENARIOS, model_for, random_state


def test_columns_and_shapes_for_many_samples():
    m = model_for(SCENARIOS / "tow6_uniform.yaml")
    rng = np.random.default_rng(1)
    ys = np.stack([random_state(m, rng) for _ in range(4)])
    seg, lk = output_series(m, ys, Controls.rolling(m.n, np.ones(m.n), np.full(m.n, 1.8)))
    assert set(seg) == set(SEGMENT_COLUMNS) and set(lk) == set(LINK_COLUMNS)
    assert all(v.shape == (4, 6) for v in seg.values()) and all(v.shape == (4, 5) for v in lk.values())


def test_quantities_follow_from_the_state():
    m = model_for(SCENARIOS / "tow6_uniform.yaml")
    rng = np.random.default_rng(2)
    y = random_state(m, rng)
    Y = m.unpack(y)
    seg, lk = output_series(m, y[None], Controls.rolling(m.n, np.ones(m.n), np.full(m.n, 1.8)))
    x, v = Y[:, m.layout.x], Y[:, m.layout.v]
    np.testing.assert_array_equal(seg["x_m"][0], x)
    np.testing.assert_array_equal(seg["v_mps"][0], v)
    np.testing.assert_allclose(lk["length_m"][0], x[:-1] - x[1:], rtol=1e-15)
    R = m.seg.wheel_radius_m
    np.testing.assert_allclose(seg["wheel_speed_mps"][0], Y[:, m.layout.omega].mean(-1) * R, rtol=1e-12)
    np.testing.assert_allclose(seg["net_force_N"][0], seg["traction_N"][0] - seg["resistance_N"][0], rtol=1e-12)
    assert np.all(seg["motor_electrical_power_W"] >= 0)
    np.testing.assert_array_equal(lk["extension_m"], 0.0)  # fixed links


def test_motors_off_give_no_torque():
    m = model_for(SCENARIOS / "tow6_uniform.yaml")
    y = random_state(m, np.random.default_rng(3))
    seg, _ = output_series(m, y[None], Controls.rolling(m.n, np.zeros(m.n), np.full(m.n, 1.8)))
    np.testing.assert_array_equal(seg["motor_torque_Nm"], 0.0)
