"""What the environments share (snoworm.env.core): the action map, the observation scales, the energy."""

import numpy as np
import pytest

from snoworm import load_scenario
from tests.conftest import SCENARIOS

pytest.importorskip("gymnasium")
from snoworm.env.core import OBS_LIMIT, OBSERVATION_FIELDS, EnvCore  # noqa: E402


@pytest.fixture
def core6():
    return EnvCore(load_scenario(SCENARIOS / "tow6_uniform.yaml"))


def test_actions_map_linearly_onto_the_vehicle_range(core6):
    seg = core6.model.seg
    vnl = seg.no_load_speed_radps * seg.wheel_radius_m
    cmd = core6.physical_action(np.array([-1, -0.5, 0, 0.5, 1, 7], np.float32))
    np.testing.assert_allclose(cmd["wheel_speed_mps"], np.array([0, 0.25, 0.5, 0.75, 1, 1]) * vnl, rtol=1e-7)
    batch = core6.physical_action(np.zeros((3, 6)), batch=3)["wheel_speed_mps"]
    assert batch.shape == (3, 6)
    np.testing.assert_allclose(batch, np.broadcast_to(vnl / 2, (3, 6)), rtol=1e-12)
    inching = EnvCore(load_scenario(SCENARIOS / "inchworm2.yaml"), action_keys=("wheel_torque_Nm", "joint_length_m"))
    links = inching.model.links
    cmd = inching.physical_action(np.array([1, -1, -1], np.float32))
    np.testing.assert_allclose(
        cmd["wheel_torque_Nm"],
        [inching.model.seg.torque_limit_Nm[0], -inching.model.seg.torque_limit_Nm[1]],
        rtol=1e-12,
    )
    np.testing.assert_allclose(cmd["joint_length_m"], links.stroke_min_m, rtol=1e-12)


def test_observation_is_scaled_by_the_vehicle_and_clipped(core6):
    n = core6.model.n
    sc = core6.scales()
    assert sc["speed"] == pytest.approx(
        float(np.max(core6.model.seg.no_load_speed_radps * core6.model.seg.wheel_radius_m))
    )
    assert sc["distance"] == pytest.approx(sc["speed"] * 20.0)
    fields = {f: np.ones(n - 1 if f.startswith(("link_", "joint_")) else n) for f in OBSERVATION_FIELDS}
    fields["v_mps"] = np.full(n, sc["speed"])  # one no-load speed: 1 scale
    fields["link_force_N"] = np.full(n - 1, 1e9)  # far beyond the box: clipped
    obs = core6.normalised(fields, 10.0)
    assert obs.dtype == np.float32 and obs.shape == core6.single_observation_space.shape
    np.testing.assert_allclose(obs[n : 2 * n], 1.0, rtol=1e-6)
    assert np.all(obs[7 * n : 8 * n - 1] == OBS_LIMIT) and obs[-1] == pytest.approx(0.5)


def test_energy_is_the_trapezoid_of_the_power(core6):
    ts = np.array([0.0, 0.05, 0.1])
    power = np.array([[100.0] * 6, [160.0] * 6, [220.0] * 6])  # W per segment, linear in time
    e = core6.energy_J(ts, {"motor_electrical_power_W": power})
    assert e == pytest.approx(6 * 160.0 * 0.1, rel=1e-12)  # exact for a linear power
    batched = core6.energy_J(ts, {"motor_electrical_power_W": np.stack([power, 2 * power], axis=1)})
    np.testing.assert_allclose(batched, [96.0, 192.0], rtol=1e-12)


@pytest.mark.parametrize("action", [["a"] * 6, [object()] * 6, [[1.0, "x"]] * 3])
def test_an_action_that_is_not_numbers_is_refused_naming_the_action(core6, action):
    with pytest.raises(ValueError, match=r"^action: expected numbers in \[-1, 1\] of shape \(6,\)"):
        core6.physical_action(action)


@pytest.mark.parametrize(
    "action, batch",
    [(np.full(6, 0.5 + 1j), None), ([0.5 + 1j] * 6, None), (np.full(6, 0.5 + 0j), None), (np.full((2, 6), 1j), 2)],
)
def test_a_complex_action_is_refused_naming_the_action(core6, action, batch):
    """Issue 30: a complex NumPy action was cast to its real part (a ComplexWarning) and stepped."""
    with pytest.raises(ValueError, match=r"^action: expected real numbers .* got complex values"):
        core6.physical_action(action, batch=batch)
