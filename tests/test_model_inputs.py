"""Piecewise-constant inputs of an integration interval (snoworm.model.inputs.Controls)."""

import numpy as np
import pytest

from snoworm.model.inputs import Controls

SEGMENT_FIELDS = (
    "motor_on",
    "speed_sp_mps",
    "fc_active",
    "fc_link",
    "fc_sigma",
    "fc_ref_N",
    "fc_nominal_mps",
    "fc_kp",
    "fc_ki",
    "fc_vmax_mps",
    "torque_active",
    "torque_cmd_Nm",
)


@pytest.mark.parametrize("n", [1, 2, 6])
def test_rolling_shapes(n):
    c = Controls.rolling(n, 1.0, 1.8)
    for name in Controls.__dataclass_fields__:
        expected = (n,) if name in SEGMENT_FIELDS else (n - 1,)
        assert np.shape(getattr(c, name)) == expected, name
    np.testing.assert_array_equal(c.speed_sp_mps, np.full(n, 1.8))
    np.testing.assert_array_equal(c.motor_on, np.ones(n))
    assert not c.fc_active.any() and not c.joint_active.any()  # plain rolling: no force loop, joints locked
    assert c.fc_link.dtype.kind == "i" and c.joint_mover.dtype.kind == "i" and c.joint_anchor.dtype.kind == "i"
    np.testing.assert_array_equal(c.fc_link, np.full(n, n - 1))  # index N-1: the tow


def test_rolling_per_segment_values():
    c = Controls.rolling(3, [0.0, 1.0, 1.0], [1.8, 1.7, 1.6])
    np.testing.assert_array_equal(c.motor_on, [0.0, 1.0, 1.0])
    np.testing.assert_array_equal(c.speed_sp_mps, [1.8, 1.7, 1.6])


def test_stack_keeps_equal_arrays_and_stacks_differing_ones():
    a = Controls.rolling(4, 1.0, 1.8)
    b = Controls.rolling(4, 1.0, 1.5)
    c = Controls.rolling(4, [0, 1, 1, 1], 1.2)
    s = Controls.stack([a, b, c])
    assert s.speed_sp_mps.shape == (3, 4)  # differs: a leading batch axis
    np.testing.assert_array_equal(s.speed_sp_mps[:, 0], [1.8, 1.5, 1.2])
    assert s.motor_on.shape == (3, 4)
    np.testing.assert_array_equal(s.motor_on[2], [0, 1, 1, 1])
    assert s.fc_kp.shape == (4,) and s.joint_ff_N.shape == (3,)  # equal in every member: unchanged
    np.testing.assert_array_equal(s.fc_link, a.fc_link)


def test_stack_refuses_differing_index_arrays():
    a = Controls.rolling(4, 1.0, 1.8)
    b = a.with_(joint_mover=np.array([1, 2, 3]))
    with pytest.raises(ValueError, match="joint_mover"):
        Controls.stack([a, b])


def test_with_replaces_only_the_named_arrays():
    a = Controls.rolling(3, 1.0, 1.8)
    b = a.with_(speed_sp_mps=[0.0, 0.0, 0.0])
    np.testing.assert_array_equal(b.speed_sp_mps, [0.0, 0.0, 0.0])
    np.testing.assert_array_equal(a.speed_sp_mps, [1.8, 1.8, 1.8])  # the original is unchanged
    assert b.motor_on is a.motor_on


def test_no_direct_torque_by_default_and_stacking_keeps_it():
    c = Controls.rolling(3, np.ones(3), np.full(3, 1.0))
    np.testing.assert_array_equal(c.torque_active, 0.0)
    np.testing.assert_array_equal(c.torque_cmd_Nm, 0.0)
    d = c.with_(torque_active=np.array([1.0, 0.0, 0.0]), torque_cmd_Nm=np.array([5.0, 0.0, 0.0]))
    s = Controls.stack([c, d])
    assert s.torque_cmd_Nm.shape == (2, 3) and s.torque_cmd_Nm[1, 0] == 5.0
