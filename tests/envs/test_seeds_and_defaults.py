"""Seeds make different episodes, the same seed the same one; defaults that work."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import slipenv  # noqa: F401
from slipenv.controllers.baseline import baseline_controller
from slipenv.envs.render import ESTIMATE_RGB, PATH_RGB, TRUE_RGB
from slipenv.envs.slip_env import render_modes

ENV_IDS = sorted(e for e in gym.registry if e.startswith("slipenv/"))


def episode(env, seed: int, steps: int = 8) -> np.ndarray:
    obs, info = env.reset(seed=seed)
    out = [obs, info["true_pose"]]
    for _ in range(steps):
        obs, reward, *_ = env.step(np.array([0.6, 0.1]))
        out += [obs, [reward]]
    return np.concatenate(out)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_different_seeds_give_different_episodes_and_one_seed_the_same(env_id):
    env = gym.make(env_id)
    try:
        a, b, a_again = episode(env, 1), episode(env, 2), episode(env, 1)
    finally:
        env.close()
    assert not np.array_equal(a, b)
    np.testing.assert_array_equal(a, a_again)  # bit for bit


def test_the_start_jitter_stays_within_its_documented_range():
    env = gym.make("slipenv/HuskySand-v0", start_jitter=(0.05, 2.0)).unwrapped
    x0, y0, yaw0 = env.path.start_pose()
    try:
        for seed in range(20):
            env.reset(seed=seed)
            x, y, yaw = env._jittered_start()
            assert np.hypot(x - x0, y - y0) <= 0.05
            assert abs(yaw - yaw0) <= np.radians(2.0) + 1e-12
    finally:
        env.close()


def test_no_jitter_and_no_noise_make_seeds_irrelevant_for_the_truth():
    from slipenv.sensors.noise import SensorNoise

    env = gym.make("slipenv/HuskySand-v0", start_jitter=(0.0, 0.0),
                   sensor_noise=SensorNoise.perfect())
    try:
        _, info1 = env.reset(seed=1)
        _, info2 = env.reset(seed=2)
    finally:
        env.close()
    np.testing.assert_array_equal(info1["true_pose"], info2["true_pose"])


@pytest.mark.xfail(strict=True, reason=(
    "gyrodometry on loose sand: the baseline follows its estimate within 3 cm, but the true "
    "Husky drifts up to 1.54-1.57 m off the 3 m circle over a lap (seeds 0-2, measured in a "
    "2 m corridor), so it leaves the 1.2 m corridor (0.4 r) at 27 % of the lap"))
def test_the_configurable_defaults_complete_their_path_with_the_baseline_controller():
    env = gym.make("slipenv/Configurable-v0")
    try:
        policy = baseline_controller(env)
        policy.reset()
        obs, info = env.reset(seed=0)
        terminated = truncated = False
        while not (terminated or truncated):
            obs, _, terminated, truncated, info = env.step(policy.act(obs))
    finally:
        env.close()
    assert info["is_success"], info.get("termination_reason")


def test_check_env_passes_with_default_arguments_headless(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    assert render_modes() == ["rgb_array"]  # human is not advertised without a display
    env = gym.make("slipenv/HuskySand-v0")
    try:
        check_env(env.unwrapped)
    finally:
        env.close()


def test_the_rgb_frame_draws_the_path_and_both_traces():
    env = gym.make("slipenv/HuskySand-v0", render_mode="rgb_array")
    try:
        env.reset(seed=0)
        for _ in range(60):
            env.step(np.array([0.8, 0.0]))
        frame = env.render()
    finally:
        env.close()
    assert frame.shape == (480, 640, 3) and frame.dtype == np.uint8

    def pixels(rgb):
        return int(np.all(frame == np.array(rgb, dtype=np.uint8), axis=2).sum())

    # The 14 m s-curve spans most of the 640 px width, 3 px wide.
    assert pixels(PATH_RGB) > 600
    assert pixels(TRUE_RGB) > 50  # ~2.5 m of true trace
    assert pixels(ESTIMATE_RGB) + pixels(TRUE_RGB) > 50
