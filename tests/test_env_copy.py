"""Pickling and deep-copying the environments (issue 30): a copy made mid-episode steps on to the same
observations, rewards and flags as the original (same code path, same state: within 1e-12)."""

import copy
import pickle

import numpy as np
import pytest

from snoworm import load_scenario
from tests.conftest import SCENARIOS

gymnasium = pytest.importorskip("gymnasium")
from snoworm.env import ENV_ID, SnowormEnv  # noqa: E402
from snoworm.env.vector import SnowormVectorEnv  # noqa: E402
from snoworm.modes.command import Observation  # noqa: E402

COPIES = {"pickle": lambda env: pickle.loads(pickle.dumps(env)), "deepcopy": copy.deepcopy}


@pytest.fixture
def short6():
    return load_scenario(SCENARIOS / "tow6_uniform.yaml").with_({"simulation.duration_s": 2.0})


def _envs(short6):
    return {
        "single": lambda: SnowormEnv(short6),
        "single, LSODA, recorded": lambda: SnowormEnv(short6, method="LSODA", record=True),
        "made (wrappers)": lambda: gymnasium.make(ENV_ID, scenario=short6),
        "vector": lambda: SnowormVectorEnv(3, short6),
    }


def _steps(env, actions):
    out = []
    for a in actions:
        obs, reward, terminated, truncated, _ = env.step(a)
        out.append(np.concatenate([np.ravel(obs), np.ravel(reward), np.ravel(terminated), np.ravel(truncated)]))
    return np.array(out, float)


@pytest.mark.parametrize("how", sorted(COPIES))
@pytest.mark.parametrize("kind", ["single", "single, LSODA, recorded", "made (wrappers)", "vector"])
def test_a_copy_steps_on_as_the_original(short6, kind, how):
    env = _envs(short6)[kind]()
    env.reset(seed=0)
    rng = np.random.default_rng(5)
    actions = [rng.uniform(-1, 1, env.action_space.shape).astype(np.float32) for _ in range(6)]
    actions[4] = actions[3]  # a held command: VODE's history carries on in the copy too
    for a in actions[:3]:
        env.step(a)
    twin = COPIES[how](env)
    assert twin is not env
    after_copy = _steps(twin, actions[3:])
    original = _steps(env, actions[3:])
    np.testing.assert_allclose(after_copy, original, rtol=0, atol=1e-12)
    assert np.ptp(original[:, 0]) > 0  # the chain moved: the comparison is not of constants


@pytest.mark.parametrize("how", sorted(COPIES))
def test_an_environment_copies_before_its_first_reset(short6, how):
    twin = COPIES[how](SnowormEnv(short6))
    obs, _ = twin.reset(seed=0)
    assert obs.shape == twin.observation_space.shape


def test_an_observation_pickles_with_its_values_read_only(short6):
    env = SnowormEnv(short6)
    env.reset(seed=0)
    env.step(np.full(6, 0.5, np.float32))
    obs = env.observation
    back = pickle.loads(pickle.dumps(obs))
    assert isinstance(back, Observation) and back.t_s == obs.t_s
    for field in Observation.FIELDS[1:]:
        np.testing.assert_array_equal(getattr(back, field), getattr(obs, field))
        assert not getattr(back, field).flags.writeable
    with pytest.raises(AttributeError, match="read-only"):
        back.t_s = 1.0
