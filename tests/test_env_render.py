"""The environments' render_mode="rgb_array" (issue 34): the animation's drawing of the current state."""

import copy
import pickle

import numpy as np
import pytest

from snoworm import load_scenario
from tests.conftest import SCENARIOS

gymnasium = pytest.importorskip("gymnasium")
from gymnasium.error import ResetNeeded  # noqa: E402

from snoworm.env import ENV_ID, SnowormEnv, SnowormVectorEnv  # noqa: E402


@pytest.fixture(scope="module")
def short6():
    return load_scenario(SCENARIOS / "tow6_uniform.yaml").with_({"simulation.duration_s": 1.0})


def chassis_centres(renderer):
    """The s coordinates of the drawn chassis' centres (the segments' reference points)."""
    ax = renderer._canvas[1]
    return np.array([p.vertices[:4, 0].mean() for p in ax._snoworm_chain.chassis.get_paths()])


def test_single_env_renders_its_state_as_an_rgb_array(short6):
    env = SnowormEnv(short6, render_mode="rgb_array")
    assert env.metadata["render_modes"] == ["rgb_array"] and env.metadata["render_fps"] == pytest.approx(10.0)
    with pytest.raises(ResetNeeded, match="reset"):
        env.render()
    env.reset(seed=0)
    first, x0 = env.render(), env.observation.x_m.copy()
    assert first.ndim == 3 and first.shape[2] == 3 and first.dtype == np.uint8
    np.testing.assert_allclose(chassis_centres(env.renderer), env.observation.x_m, atol=1e-12)
    for _ in range(4):
        env.step(np.full(6, 0.8, np.float32))
    later = env.render()
    assert later.shape == first.shape and not np.array_equal(later, first)
    # drawn where the chain is now (level ground: a chassis centred on its segment's position)
    np.testing.assert_allclose(chassis_centres(env.renderer), env.observation.x_m, atol=1e-12)
    assert np.all(env.observation.x_m - x0 > 0.01)  # the chain moved
    # a copy renders the same picture (the figure is not copied: the copy makes its own)
    twin = copy.deepcopy(env)
    np.testing.assert_array_equal(twin.render(), later)
    assert pickle.loads(pickle.dumps(env)).render().shape == later.shape
    env.close()


def test_gymnasium_checker_renders_it(short6):
    from gymnasium.utils.env_checker import check_env

    env = gymnasium.make(ENV_ID, scenario=short6, render_mode="rgb_array")
    check_env(env.unwrapped)  # the render check included
    env.reset(seed=0)
    assert env.render().dtype == np.uint8


def test_render_modes_other_than_rgb_array_are_refused(short6):
    with pytest.raises(ValueError, match="render_mode: the environment renders 'rgb_array'"):
        SnowormEnv(short6, render_mode="human")
    with pytest.raises(ValueError, match="render_mode"):
        SnowormVectorEnv(2, short6, render_mode="human")
    env = SnowormEnv(short6)
    env.reset()
    with pytest.warns(UserWarning, match="no render_mode"):
        assert env.render() is None


def test_vector_env_renders_member_0(short6):
    envs = SnowormVectorEnv(3, short6, render_mode="rgb_array")
    with pytest.raises(ResetNeeded):
        envs.render()
    envs.reset(seed=0)
    actions = np.array([[0.9] * 6, [-1.0] * 6, [-1.0] * 6], np.float32)  # member 0 drives, the others stand
    for _ in range(4):
        envs.step(actions)
    img = envs.render()
    assert img.ndim == 3 and img.shape[2] == 3 and img.dtype == np.uint8
    x = envs.model.field(envs.model.unpack(envs._y), "x_m")  # (B, N)
    assert x[0, 0] - x[1, 0] > 0.01  # member 0 moved away from the others
    np.testing.assert_allclose(chassis_centres(envs.renderer), x[0], atol=1e-12)
    envs.close()
