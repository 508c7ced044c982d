"""The mode contract and the open registry (snoworm.modes.base): a user's own mode runs like a built-in."""

from dataclasses import dataclass

import numpy as np
import pytest

import snoworm
from snoworm import Mode, ModeConfig, ScenarioError, register_mode, scenario_from_dict, simulate
from snoworm.config import mode_registry
from snoworm.config.scenario import apply_overrides, read_yaml
from snoworm.config.schema import field
from snoworm.model.inputs import Controls
from snoworm.modes.base import MODES, Interval
from snoworm.simulation.driver import chain_model
from tests.conftest import SCENARIOS


@dataclass(frozen=True)
class ConstantSpeedConfig(ModeConfig):
    """``mode: {type: constant_speed, speed_mps: ...}``: every motor on from t = 0."""

    type: str = field(choices=("constant_speed",), doc="mode name")
    speed_mps: float = field(ge=0, unit="m/s", doc="wheel-speed set-point of every segment")


class ConstantSpeedMode(Mode):
    name = "constant_speed"
    config_class = ConstantSpeedConfig

    def interval(self, t, y):
        return Interval(np.inf, Controls.rolling(self.model.n, 1.0, self.cfg.speed_mps), [], "constant")

    def summary(self, result):
        return {"constant_speed": {"speed_mps": self.cfg.speed_mps}}


@pytest.fixture
def user_mode():
    """Register the user mode for one test, and remove it again."""
    register_mode(ConstantSpeedMode)
    yield ConstantSpeedMode
    MODES.unregister(ConstantSpeedMode.name)


def raw_with_mode(mode, duration_s=8.0):
    return apply_overrides(
        read_yaml(SCENARIOS / "tow6_uniform.yaml"), [("mode", mode), ("simulation.duration_s", duration_s)]
    )


def test_user_mode_validates_and_runs(user_mode):
    sc = scenario_from_dict(raw_with_mode({"type": "constant_speed", "speed_mps": 1.8}))
    assert isinstance(sc.mode, ConstantSpeedConfig) and sc.mode.speed_mps == 1.8
    res = simulate(sc)
    # the same controls as the built-in uniform mode with every motor on at t = 0: the same run
    ref = simulate(scenario_from_dict(raw_with_mode({"type": "uniform", "speed_mps": 1.8, "start_time_s": 0.0})))
    np.testing.assert_allclose(res.segments["v_mps"], ref.segments["v_mps"], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.links["force_N"], ref.links["force_N"], rtol=1e-12, atol=1e-9)
    assert res.summary()["constant_speed"] == {"speed_mps": 1.8}  # the mode's summary hook
    assert [p["label"] for p in res.phases] == ["constant"]


def test_user_mode_config_is_validated(user_mode):
    with pytest.raises(ScenarioError, match=r"^mode\.speed_mps: must be at least 0"):
        scenario_from_dict(raw_with_mode({"type": "constant_speed", "speed_mps": -1.0}))
    with pytest.raises(ScenarioError, match=r"^mode\.sped_mps: unknown key\. Did you mean 'speed_mps'"):
        scenario_from_dict(raw_with_mode({"type": "constant_speed", "sped_mps": 1.0}))


def test_unknown_mode_lists_known_modes():
    with pytest.raises(ScenarioError) as exc:
        scenario_from_dict(raw_with_mode({"type": "crawl", "speed_mps": 1.0}))
    msg = str(exc.value)
    assert msg.startswith("mode.type: unknown mode 'crawl'")
    for name in ("uniform", "force_control", "inchworm", "supervisor"):
        assert name in msg.split("Known modes:")[1]


def test_registering_a_non_mode_raises_type_error():
    with pytest.raises(TypeError, match="Mode subclass"):
        register_mode(object)
    with pytest.raises(TypeError, match="Mode subclass"):
        register_mode(object.__new__(ConstantSpeedMode))  # an instance, not a class

    class Nameless(Mode):
        pass

    with pytest.raises(TypeError, match="with a name"):
        register_mode(Nameless)

    class BadConfig(Mode):
        name = "bad_config"
        config_class = dict

    with pytest.raises(TypeError, match="ModeConfig"):
        register_mode(BadConfig)
    assert "bad_config" not in MODES


def test_base_hooks_defaults():
    sc = snoworm.load_scenario(SCENARIOS / "tow6_uniform.yaml")
    m = Mode(sc.mode, sc, chain_model(sc))
    np.testing.assert_array_equal(m.initial_state(), chain_model(sc).initial_state())
    assert m.summary(None) == {} and m.log == []
    with pytest.raises(NotImplementedError, match="must implement interval"):
        m.interval(0.0, m.initial_state())


def test_validation_and_the_driver_read_one_registry(user_mode):
    assert snoworm.modes.MODES is MODES is mode_registry.MODES
    sc = scenario_from_dict(raw_with_mode({"type": "constant_speed", "speed_mps": 1.0}))
    assert mode_registry.MODES.config_class("constant_speed") is type(sc.mode) is ConstantSpeedConfig
    assert snoworm.modes.mode_class(sc.mode) is ConstantSpeedMode
