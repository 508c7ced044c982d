"""The single Gymnasium environment (snoworm.env.single, registered by snoworm.env): registration,
normalised spaces, gymnasium's checkers (without warnings: pytest turns warnings into errors),
seeding, bounded memory, the API's errors."""

import subprocess
import sys
import tracemalloc

import numpy as np
import pytest

from snoworm import load_scenario
from tests.conftest import SCENARIOS

gymnasium = pytest.importorskip("gymnasium")
from gymnasium.error import ResetNeeded  # noqa: E402

from snoworm.env import ENV_ID, OBS_LIMIT, OBSERVATION_FIELDS, SnowormEnv  # noqa: E402


@pytest.fixture
def short6():
    return load_scenario(SCENARIOS / "tow6_uniform.yaml").with_({"simulation.duration_s": 1.0})


def test_registered_and_made_with_a_scenario_name_path_or_object(short6):
    assert ENV_ID in gymnasium.registry
    env = gymnasium.make(ENV_ID)  # default: the shipped tow6_uniform, dt 0.1 s
    assert env.spec.max_episode_steps == 200 and isinstance(env.unwrapped, SnowormEnv)
    env = gymnasium.make(ENV_ID, scenario=str(SCENARIOS / "inchworm2.yaml"), dt_s=0.25)
    assert env.unwrapped.scenario.name == "inchworm2"
    assert env.spec.max_episode_steps == int(np.ceil(env.unwrapped.scenario.simulation.duration_s / 0.25))
    env = gymnasium.make(ENV_ID, scenario=short6, dt_s=0.3)  # 1 s in steps of 0.3 s: the 4th reaches it
    assert env.spec.max_episode_steps == 4
    env.reset(seed=0)
    flags = [env.step(env.action_space.sample())[3] for _ in range(4)]
    assert flags == [False, False, False, True]
    vec = gymnasium.make_vec(ENV_ID, num_envs=3, scenario=short6)
    assert type(vec).__name__ == "SnowormVectorEnv" and vec.num_envs == 3


def test_import_snoworm_stays_light_and_the_module_form_registers():
    code = (
        "import sys, snoworm\n"
        "assert 'gymnasium' not in sys.modules and 'numpy' not in sys.modules, sorted(sys.modules)\n"
        "import gymnasium\n"
        "env = gymnasium.make('snoworm.env:snoworm/Snoworm-v0', scenario='tow6_uniform')\n"
        "print(env.spec.id, env.spec.max_episode_steps)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["snoworm/Snoworm-v0", "200"]


def test_import_snoworm_after_gymnasium_registers_the_id():
    """The usual order of a training script: gymnasium first, then snoworm, then make by id."""
    code = (
        "import gymnasium, snoworm\n"
        "env = gymnasium.make('snoworm/Snoworm-v0', scenario='tow6_uniform')\n"
        "print(env.spec.id, env.spec.max_episode_steps)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["snoworm/Snoworm-v0", "200"]


def test_gymnasium_checkers_pass_without_warnings(short6):
    from gymnasium.utils.env_checker import check_env

    check_env(gymnasium.make(ENV_ID, scenario=short6).unwrapped)  # with a spec: render and close checks too
    check_env(SnowormEnv(short6), skip_render_check=True)  # no spec, no render modes to check
    env = gymnasium.make(ENV_ID, scenario=short6)  # the passive checker wraps it
    env.reset(seed=1)
    done = False
    while not done:
        obs, r, term, trunc, info = env.step(env.action_space.sample())
        done = term or trunc
    assert trunc


def test_spaces_are_normalised_and_map_onto_the_vehicle(short6):
    env = SnowormEnv(short6, action_keys=("wheel_torque_Nm",))
    sp = env.action_space
    assert sp.dtype == np.float32 and sp.shape == (6,) and np.all(sp.low == -1) and np.all(sp.high == 1)
    ob = env.observation_space
    assert ob.dtype == np.float32 and np.all(ob.low == -OBS_LIMIT) and np.all(ob.high == OBS_LIMIT)
    assert ob.shape == (7 * 6 + 3 * 5 + 1,) and len(OBSERVATION_FIELDS) == 10
    obs, info = env.reset(seed=3)
    assert obs.dtype == np.float32 and ob.contains(obs) and info["t_s"] == 0.0
    m = env.sim.model
    a = np.array([-1, -0.5, 0, 0.5, 1, 3], np.float32)  # 3 is clipped to 1
    env.step(a)
    lim = m.seg.torque_limit_Nm
    np.testing.assert_allclose(env.sim.commands.torque, np.array([-1, -0.5, 0, 0.5, 1, 1]) * lim, rtol=1e-12)
    speed = SnowormEnv(short6)
    speed.reset()
    speed.step(np.array([-1, 1, 0, 0, 0, 0], np.float32))
    vnl = m.seg.no_load_speed_radps * m.seg.wheel_radius_m
    np.testing.assert_allclose(speed.sim.commands.speed, [0, vnl[1], *(vnl[2:] / 2)], rtol=1e-12)


def test_observation_is_the_physical_observation_scaled(short6):
    env = SnowormEnv(short6)
    env.reset(seed=0)
    obs, *_ = env.step(np.full(6, 0.2, np.float32))
    phys = env.observation
    vec = np.concatenate([getattr(phys, f) for f in OBSERVATION_FIELDS]) / env.core.scale
    np.testing.assert_allclose(obs[:-1], vec, rtol=1e-6, atol=1e-7)  # float32 rounding
    assert obs[-1] == pytest.approx(0.1 / 1.0)  # t / duration
    assert phys.t_s == pytest.approx(0.1) and np.all(np.isfinite(vec))


def test_reward_progress_truncation_and_record(short6):
    env = SnowormEnv(short6, dt_s=0.1, record=True)
    env.reset(seed=0)
    total, steps, truncated = 0.0, 0, False
    while not truncated:
        obs, r, terminated, truncated, info = env.step(np.full(6, 0.5, np.float32))
        total, steps = total + r, steps + 1
        assert info["motor_energy_J"] > 0 and not terminated
    assert steps == 10
    assert env.sim.result().summary()["distance_m"] > 0.5
    custom = SnowormEnv(short6, reward=lambda prev, o, i: float(o.t_s - prev.t_s))
    custom.reset()
    assert custom.step(np.full(6, 0.0, np.float32))[1] == pytest.approx(0.1)
    with pytest.raises(ValueError, match="record=False"):
        SnowormEnv(short6).sim.result()


def test_terminated_when_immobilised_and_stepping_on_needs_a_reset(short6):
    env = SnowormEnv(short6.with_({"simulation.duration_s": 10.0}), dt_s=0.25, stall_time_s=1.0)
    with pytest.raises(ResetNeeded, match="reset"):
        env.step(np.zeros(6, np.float32))
    env.reset()
    for _ in range(8):
        obs, r, terminated, truncated, info = env.step(-np.ones(6, np.float32))  # wheels held at zero speed
        if terminated:
            break
    assert terminated and info["t_s"] == pytest.approx(1.0)
    with pytest.raises(ResetNeeded, match="terminated or truncated"):
        env.step(np.zeros(6, np.float32))
    env.reset()
    env.step(np.zeros(6, np.float32))  # a reset makes it usable again


def test_reset_seed_seeds_the_action_space_and_reproduces_episodes(short6):
    def episode(seed):
        env = SnowormEnv(short6)
        obs, _ = env.reset(seed=seed)
        out = [obs]
        for _ in range(5):
            out.append(env.step(env.action_space.sample())[0])
        return np.array(out)

    a, b, c = episode(7), episode(7), episode(8)
    np.testing.assert_array_equal(a, b)  # same code path, same inputs: the same numbers
    assert not np.array_equal(a[1:], c[1:])  # another seed samples other actions


def test_bad_actions_and_options_are_refused(short6):
    env = SnowormEnv(short6)
    env.reset()
    for bad, msg in ((0.5, r"shape \(6,\)"), (np.zeros(5), r"shape \(6,\)"), (np.full(6, np.nan), "finite")):
        with pytest.raises(ValueError, match=msg):
            env.step(bad)
    for kw, msg in (
        ({"dt_s": float("nan")}, "dt_s"),
        ({"dt_s": -0.1}, "dt_s"),
        ({"dt_s": 1e-9}, r"dt_s: must be a number of seconds >= 1e-06"),  # issue 30: below any step
        ({"dt_s": True}, "dt_s"),
        ({"energy_weight": -1.0}, "energy_weight"),
        ({"stall_time_s": 0.0}, "stall_time_s"),
        ({"stall_speed_mps": float("inf")}, "stall_speed_mps"),
        ({"action_keys": ("joint_force_N",)}, "prismatic"),
        ({"action_keys": ("wheel_speed_mps", "wheel_torque_Nm")}, "same actuator"),
        ({"action_keys": ("wheel_sped",)}, "cannot be an action"),
        ({"render_mode": "human"}, "render"),
        ({"scenario": 3}, "scenario"),
    ):
        with pytest.raises(ValueError, match=msg):
            SnowormEnv(**({"scenario": short6} | kw))


def test_memory_per_episode_is_bounded(short6):
    """2 000 steps of one episode: the traced memory grows by less than 256 kB (main's environment
    kept every step, about 15 kB each: 30 MB)."""
    env = SnowormEnv(short6.with_({"simulation.duration_s": 300.0}), dt_s=0.1)
    env.reset(seed=0)
    action = np.full(6, 0.3, np.float32)
    for _ in range(50):  # past the start-up transient and the caches' first fill
        env.step(action)
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        for _ in range(2000):
            env.step(action)
        grown = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert grown < 256_000, f"memory grew by {grown} bytes over 2000 steps"


def test_observation_carries_the_grade_under_each_segment(short6):
    """On a grade the observation holds grade_deg per segment, scaled by 90 deg (docs/model.md section 7)."""
    env = SnowormEnv(short6.with_({"terrain.grade_deg": 6.0}))
    obs, _ = env.reset(seed=0)
    j = OBSERVATION_FIELDS.index("grade_deg") * 6
    np.testing.assert_allclose(obs[j : j + 6], 6.0 / 90.0, rtol=1e-6)  # float32
    np.testing.assert_allclose(env.observation.grade_deg, 6.0, rtol=1e-12)


def _episode(env, action):
    """One episode under a constant action: (return, progress of the mean position [m], energy [J])."""
    env.reset(seed=0)
    x0 = float(np.mean(env.observation.x_m))
    total, energy, done = 0.0, 0.0, False
    while not done:
        _, r, terminated, truncated, info = env.step(action)
        total, energy, done = total + r, energy + info["motor_energy_J"], terminated or truncated
    return total, float(np.mean(env.observation.x_m)) - x0, energy


def test_the_default_reward_pays_driving_more_than_standing_still():
    """Issue 34: with the former default reward (progress - 1e-3 x energy) standing still won on
    tow6; the default preset "efficiency" charges the energy over the chain's weight m g (the height
    it would lift the chain), so driving at the paper's 1.8 m/s over a 20 s episode returns more
    than standing still, while the former weight still ranks standing still first."""
    sc = load_scenario(SCENARIOS / "tow6_uniform.yaml")
    env = SnowormEnv(sc)
    weight_N = 6 * 90.0 * 9.81  # six FrostyBoy segments of 90 kg (the parameter set's mass)
    assert env.core.energy_weight == pytest.approx(1.0 / weight_N, rel=1e-12)
    still = np.full(6, -1.0, np.float32)  # set-point 0 m/s
    drive = np.full(6, 2 * 1.8 / env.core.high[0] - 1, np.float32)  # 1.8 m/s on [-1, 1]
    r_still, d_still, e_still = _episode(env, still)
    r_drive, d_drive, e_drive = _episode(env, drive)
    # the return is the progress minus the weight times the energy, step by step (by hand here)
    assert r_drive == pytest.approx(d_drive - e_drive / weight_N, rel=1e-9, abs=1e-9)
    assert r_still == pytest.approx(d_still - e_still / weight_N, rel=1e-9, abs=1e-9)
    assert abs(r_still) < 0.05 and d_drive > 20.0  # standing still goes nowhere; 1.8 m/s for ~19 s
    assert r_drive > r_still + 10.0
    # the former default weight (1e-3 per J): standing still would have paid best
    assert d_still - 1e-3 * e_still > d_drive - 1e-3 * e_drive
    old = SnowormEnv(sc, energy_weight=1e-3)
    assert _episode(old, still)[0] > _episode(old, drive)[0]
    # "distance": progress only
    dist = SnowormEnv(sc.with_({"simulation.duration_s": 1.0}), reward="distance")
    r, d, e = _episode(dist, drive)
    assert dist.core.energy_weight == 0.0 and e > 0 and r == pytest.approx(d, rel=1e-9, abs=1e-12)


def test_reward_presets_and_their_errors(short6):
    for kw, msg in (
        ({"reward": "speed"}, "reward: expected one of the presets 'efficiency', 'distance'"),
        ({"reward": 5}, "reward: expected one of the presets"),
        ({"reward": "distance", "energy_weight": 1e-3}, 'energy_weight: reward="distance" does not charge'),
        ({"energy_weight": float("nan")}, "energy_weight"),
    ):
        with pytest.raises(ValueError, match=msg):
            SnowormEnv(**({"scenario": short6} | kw))
