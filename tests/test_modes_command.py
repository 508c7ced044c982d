"""The controller contract (snoworm.modes.command): observations and held commands."""

import numpy as np
import pytest

from snoworm.drivetrain import motor_envelope
from snoworm.model.quantities import output_series
from snoworm.modes.command import COMMAND_KEYS, CommandState, observe
from tests.conftest import SCENARIOS, model_for, random_state


@pytest.fixture
def fixed6():
    return model_for(SCENARIOS / "tow6_uniform.yaml")


@pytest.fixture
def prismatic2():
    return model_for(SCENARIOS / "inchworm2.yaml")


def test_initially_motors_off_and_joints_holding(prismatic2):
    c = CommandState(prismatic2).controls
    np.testing.assert_array_equal(c.motor_on, 0.0)
    np.testing.assert_array_equal(c.joint_active, 0.0)
    np.testing.assert_array_equal(c.torque_active, 0.0)


@pytest.mark.parametrize(
    "command, words",
    [
        ({"wheel_speed": [1.0] * 6}, ["'wheel_speed'", "unknown", "wheel_speed_mps"]),
        ({"wheel_speed_mps": [1.0] * 5}, ["'wheel_speed_mps'", "expected 6 values"]),
        ({"wheel_speed_mps": [1.0] * 5 + [np.nan]}, ["'wheel_speed_mps'", "finite"]),
        ({"wheel_torque_Nm": [1.0] * 5 + [np.inf]}, ["'wheel_torque_Nm'", "finite"]),
        ({"wheel_lock": [0.5] * 6}, ["'wheel_lock'", "true/false"]),
        ({"wheel_speed_mps": ["fast"] * 6}, ["'wheel_speed_mps'", "expected 6 numbers"]),
        ({"wheel_speed_mps": np.full(6, 1.0 + 1j)}, ["'wheel_speed_mps'", "6 real numbers", "complex"]),
        ({"wheel_torque_Nm": [1.0 + 0j] * 6}, ["'wheel_torque_Nm'", "6 real numbers", "complex"]),
        ({"wheel_lock": np.ones(6, complex)}, ["'wheel_lock'", "real numbers", "complex"]),
        ({"joint_force_N": [1.0] * 5}, ["'joint_force_N'", "no prismatic joints"]),
        ({"wheel_speed_mps": [1.0] * 6, "wheel_torque_Nm": [1.0] * 6}, ["not both"]),
        ([1.0] * 6, ["mapping"]),
    ],
)
def test_bad_commands_raise_naming_the_key_and_change_nothing(fixed6, command, words):
    cs = CommandState(fixed6)
    before = cs.apply({"wheel_speed_mps": [1.2] * 6})
    with pytest.raises(ValueError) as err:
        cs.apply(command)
    for w in words:
        assert w in str(err.value)
    assert cs.controls is before
    np.testing.assert_array_equal(cs.speed, 1.2)


def test_keys_left_out_keep_their_values(fixed6):
    cs = CommandState(fixed6)
    c1 = cs.apply({"wheel_speed_mps": np.linspace(1, 2, 6)})
    assert cs.apply({}) is c1 and cs.apply(None) is c1
    c2 = cs.apply({"wheel_lock": [True] + [False] * 5})
    np.testing.assert_array_equal(c2.speed_sp_mps, np.r_[0.0, np.linspace(1, 2, 6)[1:]])
    np.testing.assert_array_equal(c2.motor_on, 1.0)
    c3 = cs.apply({"wheel_lock": [False] * 6})
    np.testing.assert_array_equal(c3.speed_sp_mps, np.linspace(1, 2, 6))


def test_torque_command_and_lock_override(fixed6):
    cs = CommandState(fixed6)
    c = cs.apply({"wheel_torque_Nm": np.arange(6.0), "wheel_lock": [False] * 5 + [True]})
    np.testing.assert_array_equal(c.torque_active, [1, 1, 1, 1, 1, 0])
    np.testing.assert_array_equal(c.torque_cmd_Nm, [0, 1, 2, 3, 4, 0])
    np.testing.assert_array_equal(c.speed_sp_mps, 0.0)
    c = cs.apply({"wheel_speed_mps": [1.5] * 6})  # the latest wheel key acts
    np.testing.assert_array_equal(c.torque_active, 0.0)


def test_direct_torque_is_clipped_to_the_motor_envelope(fixed6):
    y = random_state(fixed6, np.random.default_rng(4))
    cs = CommandState(fixed6)
    ctl = cs.apply({"wheel_torque_Nm": [1e4, -1e4, 5.0, 5.0, 5.0, 5.0]})
    obs = observe(fixed6, y, ctl, 0.0)
    w = fixed6.unpack(y)[:, fixed6.layout.omega]
    lo, hi = motor_envelope(w, fixed6._slope, fixed6._wnl, fixed6._Tmax)
    assert obs.motor_torque_Nm[0] == pytest.approx(hi[0].mean(), rel=1e-12)
    assert obs.motor_torque_Nm[1] == pytest.approx(lo[1].mean(), rel=1e-12)
    assert np.all(np.abs(obs.motor_torque_Nm[2:] - np.clip(5.0, lo[2:], hi[2:]).mean(-1)) < 1e-12)


def test_joint_commands_map_to_the_actuator(prismatic2):
    cs = CommandState(prismatic2)
    L = prismatic2.links
    c = cs.apply({"joint_force_N": [150.0]})  # tension: the joint pulls
    assert (c.joint_active[0], c.joint_length_mode[0], c.joint_dir[0], c.joint_ff_N[0]) == (1, 0, -1, 150)
    assert c.joint_limit_N[0] == L.force_max_N[0]
    c = cs.apply({"joint_force_N": [-80.0]})  # compression: it pushes
    assert (c.joint_dir[0], c.joint_ff_N[0]) == (1, 80)
    c = cs.apply({"joint_length_m": [0.2]})
    assert (c.joint_length_mode[0], c.joint_sref_m[0], c.joint_vtarget_mps[0]) == (1, 0.2, L.rate_max_mps[0])


def test_observation_is_read_only_and_matches_the_outputs(prismatic2):
    y = random_state(prismatic2, np.random.default_rng(5))
    ctl = CommandState(prismatic2).apply({"wheel_speed_mps": [0.5, 0.5]})
    obs = observe(prismatic2, y, ctl, 1.25)
    seg, lk = output_series(prismatic2, y[None], ctl)
    assert obs.t_s == 1.25
    np.testing.assert_array_equal(obs.slip, seg["slip"][0])
    np.testing.assert_array_equal(obs.joint_extension_m, lk["extension_m"][0])
    with pytest.raises(ValueError):
        obs.slip[0] = 1.0
    with pytest.raises(AttributeError):
        obs.t_s = 2.0
    d = obs.as_dict()
    assert set(d) == {
        "t_s",
        "x_m",
        "v_mps",
        "wheel_speed_mps",
        "slip",
        "motor_torque_Nm",
        "xt",
        "grade_deg",
        "link_force_N",
        "link_length_m",
        "joint_extension_m",
    }
    d["slip"][0] = 9.0  # a copy
    assert obs.slip[0] != 9.0


def test_command_keys_documented():
    assert set(COMMAND_KEYS) == {"wheel_speed_mps", "wheel_torque_Nm", "wheel_lock", "joint_force_N", "joint_length_m"}


def test_observation_from_values_for_unit_tests():
    from snoworm.modes import Observation

    obs = Observation(
        t_s=1.0,
        x_m=[0.0, -1.5],
        v_mps=[1.0, 1.0],
        wheel_speed_mps=[1.1, 1.1],
        slip=[0.1, 0.1],
        motor_torque_Nm=[5.0, 5.0],
        xt=[0.9, 0.9],
        link_force_N=[3.0],
        link_length_m=[1.5],
        joint_extension_m=[0.0],
    )
    assert obs.link_force_N[0] == 3.0 and obs.x_m.dtype == float
    with pytest.raises(ValueError):
        obs.x_m[0] = 2.0
    with pytest.raises(TypeError, match="missing"):
        Observation(t_s=0.0, x_m=[0.0])


def test_observation_keeps_the_state_it_was_made_from(fixed6):
    """Computed when first read, but from a copy of the state and controls at observation time."""
    y = random_state(fixed6, np.random.default_rng(6))
    ctl = CommandState(fixed6).apply({"wheel_speed_mps": [1.0] * 6})
    expected = output_series(fixed6, y[None], ctl)[0]["v_mps"][0].copy()
    obs = observe(fixed6, y, ctl, 0.5)
    y[:] = 0.0  # the caller's array changes afterwards
    np.testing.assert_array_equal(obs.v_mps, expected)


def test_batched_commands_give_the_stacked_controls(fixed6):
    from snoworm.model.inputs import Controls

    rng = np.random.default_rng(0)
    speeds = rng.uniform(0, 3, (4, 6))
    batched = CommandState(fixed6, batch=4).apply({"wheel_speed_mps": speeds})
    alone = []
    for b in range(4):
        alone.append(CommandState(fixed6).apply({"wheel_speed_mps": speeds[b]}))
    stacked = Controls.stack(alone)
    for name in Controls.__dataclass_fields__:
        np.testing.assert_array_equal(
            np.broadcast_to(getattr(batched, name), np.shape(getattr(stacked, name))),
            getattr(stacked, name),
            err_msg=name,
        )
    with pytest.raises(ValueError, match=r"shape \(6,\) \(batch 4\)"):
        CommandState(fixed6, batch=4).apply({"wheel_speed_mps": speeds[0]})
