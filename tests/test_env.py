"""The Gymnasium environment (snoworm.env.SnowormEnv), checked with gymnasium's own checker."""
import warnings

import numpy as np
import pytest

from snoworm import load_scenario
from tests.conftest import SCENARIOS

gymnasium = pytest.importorskip("gymnasium")


@pytest.fixture
def short6():
    return load_scenario(SCENARIOS / "tow6_uniform.yaml").with_({"simulation.duration_s": 1.0})


def test_gymnasium_env_checker_passes(short6):
    from gymnasium.utils.env_checker import check_env

    from snoworm.env import SnowormEnv
    env = SnowormEnv(short6)
    assert isinstance(env, gymnasium.Env)
    with warnings.catch_warnings():
        # advice, not failures: physical units rather than [-1, 1] boxes; no render modes
        warnings.filterwarnings("ignore", message=".*(symmetric and normalized|infinity|render).*")
        check_env(env, skip_render_check=True)


def test_spaces_follow_the_contract(short6):
    from snoworm.env import OBSERVATION_FIELDS, SnowormEnv
    env = SnowormEnv(short6, action_keys=("wheel_speed_mps", "wheel_torque_Nm"))
    assert env.action_space.shape == (12,)
    m = env.sim.model
    np.testing.assert_allclose(env.action_space.high[:6], m.seg.no_load_speed_radps * m.seg.wheel_radius_m)
    np.testing.assert_allclose(env.action_space.high[6:], m.seg.torque_limit_Nm)
    obs, info = env.reset(seed=3)
    assert obs.shape == (7 * 6 + 3 * 5,) and obs.dtype == np.float64 and info["t_s"] == 0.0
    assert len(OBSERVATION_FIELDS) == 10
    with pytest.raises(ValueError, match="joint_force_N"):
        SnowormEnv(short6, action_keys=("joint_force_N",))


def test_reward_progress_and_truncation(short6):
    from snoworm.env import SnowormEnv
    env = SnowormEnv(short6, dt_s=0.1)
    env.reset(seed=0)
    total, steps, truncated = 0.0, 0, False
    while not truncated:
        obs, r, terminated, truncated, info = env.step(np.full(6, 1.8))
        total, steps = total + r, steps + 1
        assert info["motor_energy_J"] >= 0 and not terminated
    assert steps == 10
    assert env.sim.result().summary()["distance_m"] > 0.5
    custom = SnowormEnv(short6, reward=lambda prev, o, i: float(o.t_s))
    custom.reset()
    assert custom.step(np.full(6, 1.0))[1] == pytest.approx(0.1)


def test_terminated_when_immobilised(short6):
    from snoworm.env import SnowormEnv
    env = SnowormEnv(short6.with_({"simulation.duration_s": 10.0}), dt_s=0.25, stall_time_s=1.0)
    env.reset()
    for _ in range(8):
        obs, r, terminated, truncated, info = env.step(np.zeros(6))    # wheels held at zero speed
        if terminated:
            break
    assert terminated and info["t_s"] == pytest.approx(1.0)


def test_observation_carries_the_grade_under_each_segment(short6):
    """On a grade the env's observation holds grade_deg per segment (docs/model.md section 7)."""
    from snoworm.env import OBSERVATION_FIELDS, SnowormEnv
    env = SnowormEnv(short6.with_({"terrain.grade_deg": 6.0}))
    obs, _ = env.reset(seed=0)
    j = OBSERVATION_FIELDS.index("grade_deg") * 6
    np.testing.assert_allclose(obs[j:j + 6], 6.0, rtol=1e-12)


def test_misuse_is_refused_with_clear_errors(short6):
    """Issue 24: a scalar action, NaN/negative arguments, step before reset or after the episode ended."""
    import gymnasium

    from snoworm.env import SnowormEnv
    for kw in ({"dt_s": float("nan")}, {"dt_s": -0.1}, {"energy_weight": float("nan")}, {"energy_weight": -1.0},
               {"stall_speed_mps": -0.01}, {"stall_time_s": float("inf")}):
        with pytest.raises(ValueError, match=next(iter(kw))):
            SnowormEnv(short6, **kw)
    env = SnowormEnv(short6, dt_s=0.5)
    with pytest.raises(gymnasium.error.ResetNeeded, match="reset"):
        env.step(np.full(6, 1.0))
    env.reset()
    with pytest.raises(ValueError, match="expected 6 values, got 1"):
        env.step(1.0)
    truncated = False
    while not truncated:
        truncated = env.step(np.full(6, 1.0))[3]
    with pytest.raises(gymnasium.error.ResetNeeded, match="ended"):
        env.step(np.full(6, 1.0))
    env.reset()
    env.step(np.full(6, 1.0))                                   # a new episode steps again
