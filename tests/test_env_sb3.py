"""The stable-baselines3 adapter of the native vector environment (snoworm.env.sb3): the VecEnv
protocol (spaces, seeded reset, same-step reset with ``terminal_observation``, per-member infos,
the shared environment's attributes).  Skipped where stable-baselines3 is not installed (it needs
torch, which the test extra does not pull)."""

import numpy as np
import pytest

from snoworm import load_scenario
from tests.conftest import SCENARIOS

pytest.importorskip("gymnasium")
vec_env = pytest.importorskip("stable_baselines3.common.vec_env")

from snoworm.env.sb3 import SB3VecEnv  # noqa: E402
from snoworm.env.vector import SnowormVectorEnv  # noqa: E402


@pytest.fixture
def short6():
    return load_scenario(SCENARIOS / "tow6_uniform.yaml").with_({"simulation.duration_s": 1.0})


def test_the_vecenv_protocol_with_a_same_step_reset(short6):
    B = 3
    env = SB3VecEnv.make(B, scenario=short6, rtol=None)  # the scenario's rtol (1e-5): see the last check
    native = SnowormVectorEnv(B, short6, rtol=None)
    assert isinstance(env, vec_env.VecEnv) and env.num_envs == B and env.render_mode is None
    assert env.observation_space == native.single_observation_space
    assert env.action_space == native.single_action_space
    env.seed(7)
    obs0 = env.reset()
    first, _ = native.reset(seed=7)
    np.testing.assert_array_equal(obs0, first)
    assert [i["t_s"] for i in env.reset_infos] == [0.0] * B
    rng = np.random.default_rng(0)
    acts = rng.uniform(-1, 1, (11, B, 6)).astype(np.float32)
    for k in range(10):  # 1 s of 0.1 s steps: the 10th truncates every member
        obs, rew, done, infos = env.step(acts[k])
        o, r, term, trunc, _ = native.step(acts[k])
        assert obs.shape == (B, 58) and rew.dtype == np.float32 and done.dtype == bool and len(infos) == B
        np.testing.assert_allclose(rew, r, rtol=1e-6, atol=1e-9)  # float32 of the same rewards
        assert np.all(done == (term | trunc))
        for b in range(B):
            assert infos[b]["t_s"] == pytest.approx(0.1 * (k + 1)) and infos[b]["motor_energy_J"] > 0
            assert not infos[b]["solver_failure"]
        if k < 9:
            np.testing.assert_array_equal(obs, o)
            assert not done.any() and not any("terminal_observation" in i for i in infos)
    assert done.all()
    for b in range(B):  # the last observation is in the info; the step returned the next episode's first
        np.testing.assert_array_equal(infos[b]["terminal_observation"], o[b])
        assert infos[b]["TimeLimit.truncated"] is True
    np.testing.assert_array_equal(obs, first)
    # the next episode's first step is the first episode's first step again (same start, same actions),
    # within 100 x rtol (its period starts at t = 1 s, so VODE takes other steps: test_env_vector's TOL)
    again, *_ = env.step(acts[0])
    fresh = SnowormVectorEnv(B, short6, rtol=None)
    fresh.reset(seed=7)
    np.testing.assert_allclose(again, fresh.step(acts[0])[0], rtol=0, atol=100 * 1e-5)


def test_the_members_share_one_environment(short6):
    env = SB3VecEnv.make(2, scenario=short6)
    assert env.get_attr("dt_s") == [0.1, 0.1] and env.get_attr("dt_s", indices=1) == [0.1]
    assert env.env_is_wrapped(object) == [False, False]
    env.set_attr("max_episode_steps", 5)
    assert env.venv.max_episode_steps == 5
    with pytest.raises(ValueError, match="one vector environment; give indices=None"):
        env.set_attr("max_episode_steps", 5, indices=[0])
    with pytest.raises(ValueError, match="SnowormVectorEnv"):
        SB3VecEnv(object())
