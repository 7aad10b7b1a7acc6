"""The RL environments' contract: spaces, reset/step, determinism for a seed, the time limit, several in one
process, the camera variant."""

import numpy as np
import pytest

import uavsim
from uavsim import spaces


@pytest.fixture(scope="module")
def env():
    e = uavsim.HoverEnv(max_episode_s=1.0, action_period_s=0.1)
    yield e
    e.close()


def rollout(env, seed, actions):
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for a in actions:
        obs, reward, terminated, truncated, info = env.step(a)
        out.append(obs)
    return np.array(out)


def test_spaces(env):
    assert env.observation_space.shape == (9,) and env.observation_space.dtype == np.float32
    assert env.action_space.shape == (3,) and env.action_space.dtype == np.float32
    assert np.all(env.action_space.low == -1) and np.all(env.action_space.high == 1)
    a = env.action_space.sample()
    assert env.action_space.contains(a)


def test_reset_and_step_contract(env):
    obs, info = env.reset(seed=1)
    assert obs.shape == (9,) and obs.dtype == np.float32 and env.observation_space.contains(obs)
    assert isinstance(info, dict) and info["step"] == 0
    # after take-off to 3 m the target (0, 0, 3) is near
    assert np.linalg.norm(obs[:3]) < 1.0
    obs, reward, terminated, truncated, info = env.step(np.zeros(3, np.float32))
    assert obs.shape == (9,) and obs.dtype == np.float32
    assert isinstance(reward, float) and reward <= 0
    assert terminated is False and truncated is False
    assert info["time_s"] == pytest.approx(info["time_s"])
    with pytest.raises(ValueError):
        env.step([0.0, 0.0])
    with pytest.raises(ValueError):
        env.step([np.nan, 0.0, 0.0])


def test_truncated_at_the_time_limit(env):
    env.reset(seed=2)
    t0 = env.server.now()
    for i in range(10):
        obs, reward, terminated, truncated, info = env.step([0.2, 0.0, 0.0])
        assert not terminated
        assert truncated == (i == 9)
    assert env.server.now() - t0 == pytest.approx(1.0, abs=1e-9)


def test_a_seed_gives_the_same_trajectory(env):
    actions = np.random.default_rng(0).uniform(-1, 1, (8, 3))
    a = rollout(env, 5, actions)
    b = rollout(env, 5, actions)
    np.testing.assert_array_equal(a, b)
    # a different action sequence goes elsewhere
    c = rollout(env, 5, -actions)
    assert not np.array_equal(a, c)


def test_waypoint_targets_follow_the_seed():
    e = uavsim.HoverEnv(target_spread_m=5.0, max_episode_s=0.5)
    try:
        e.reset(seed=11)
        t1 = e.target_enu_m.copy()
        e.reset(seed=11)
        np.testing.assert_array_equal(t1, e.target_enu_m)
        e.reset(seed=12)
        assert not np.array_equal(t1, e.target_enu_m) and e.target_enu_m[2] >= 1.0
    finally:
        e.close()


def test_several_envs_in_one_process():
    envs = [uavsim.HoverEnv(max_episode_s=0.5) for _ in range(2)]
    try:
        obs = [e.reset(seed=3)[0] for e in envs]
        for _ in range(3):
            obs = [e.step([0.5, 0.0, 0.0])[0] for e in envs]
        np.testing.assert_array_equal(obs[0], obs[1])  # same seed and actions, separate servers
        assert envs[0].server.pid != envs[1].server.pid
    finally:
        for e in envs:
            e.close()


def test_camera_observations():
    e = uavsim.CameraHoverEnv(width=32, height=24, max_episode_s=0.5)
    try:
        assert e.observation_space.shape == (24, 32, 3) and e.observation_space.dtype == np.uint8
        obs, info = e.reset(seed=1)
        assert obs.shape == (24, 32, 3) and obs.dtype == np.uint8 and obs.std() > 0
        assert info["state"].shape == (9,)
        obs2, *_ = e.step([0.0, 0.0, 0.5])
        assert obs2.shape == (24, 32, 3)
        assert e.observation_space.contains(obs2)
    finally:
        e.close()


def test_constructor_refuses_bad_options():
    for kwargs in ({"action_period_s": 0}, {"max_speed_m_s": -1}, {"takeoff_alt_m": 0.1},
                   {"lockstep_period_s": 1.0}, {"max_episode_s": 0}):
        with pytest.raises(ValueError):
            uavsim.HoverEnv(**kwargs)
    with pytest.raises(RuntimeError):
        uavsim.HoverEnv().step([0, 0, 0])


def test_own_box_space_without_gymnasium():
    b = spaces.Box(-1.0, 1.0, (3,), np.float32, seed=4)
    x = b.sample()
    assert x.shape == (3,) and x.dtype == np.float32 and b.contains(x)
    assert not b.contains(np.array([2.0, 0.0, 0.0]))
    img = spaces.Box(0, 255, (2, 2, 3), np.uint8, seed=1)
    assert img.sample().dtype == np.uint8
    with pytest.raises(ValueError):
        spaces.Box(1.0, -1.0, (2,))


def test_gymnasium_registration_when_importable():
    gym = pytest.importorskip("gymnasium")
    assert "uavsim/Hover-v0" in gym.envs.registry
