"""Every registered env: Gymnasium's checker, sensor noise per seed, vectorisation, bad input."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import slipenv  # noqa: F401

ENV_IDS = sorted(e for e in gym.registry if e.startswith("slipenv/"))
ACTION = np.array([0.6, 0.15], dtype=np.float32)


def test_the_four_required_tasks_and_a_configurable_env_are_registered():
    assert {"slipenv/FarmField-v0", "slipenv/TrackedSlopeCircle-v0", "slipenv/RoverMounds-v0",
            "slipenv/Configurable-v0"} <= set(ENV_IDS)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_gymnasium_env_checker_passes(env_id):
    env = gym.make(env_id)
    try:
        check_env(env.unwrapped, skip_render_check=True)
    finally:
        env.close()


def test_different_seeds_give_different_sensor_noise():
    env = gym.make("slipenv/HuskySand-v0")
    try:
        env.reset(seed=1)
        frames_1 = [env.step(ACTION)[4]["sensors"].gyro_z_rad_s for _ in range(5)]
        env.reset(seed=2)
        frames_2 = [env.step(ACTION)[4]["sensors"].gyro_z_rad_s for _ in range(5)]
        assert frames_1 != frames_2
    finally:
        env.close()


def test_observation_comes_from_the_estimator_and_truth_goes_in_info():
    env = gym.make("slipenv/HuskySand-v0")
    try:
        env.reset(seed=0)
        for _ in range(100):
            obs, _, _, _, info = env.step(ACTION)
        # Dead reckoning on loose sand: the estimate has drifted from the truth.
        assert np.hypot(*(obs[:2] - info["true_pose"][:2])) > 0.1
        np.testing.assert_allclose(obs[:2], info["estimated_pose"][:2], rtol=1e-6)
        for key in ("wheel_slip", "wheel_slip_angle_rad", "wheel_load_n", "wheel_force_n"):
            assert info[key].shape[0] == 4
        assert np.all(info["wheel_load_n"] > 0)
        assert np.all(info["wheel_slip"] > 0.05)  # loose sand: real slip
    finally:
        env.close()


def test_vector_env_steps_several_copies():
    envs = gym.make_vec("slipenv/HuskySand-v0", num_envs=2, vectorization_mode="sync")
    try:
        obs, _ = envs.reset(seed=[0, 1])
        assert obs.shape == (2, 12)
        obs, reward, terminated, truncated, _ = envs.step(np.stack([ACTION, ACTION]))
        assert obs.shape == (2, 12) and reward.shape == (2,)
        assert terminated.dtype == bool and truncated.dtype == bool
    finally:
        envs.close()


def test_rgb_array_render_returns_an_image():
    env = gym.make("slipenv/HuskySand-v0", render_mode="rgb_array")
    try:
        env.reset(seed=0)
        env.step(ACTION)
        frame = env.render()
        assert frame.shape == (480, 640, 3) and frame.dtype == np.uint8
        assert frame.std() > 5  # not a blank image
    finally:
        env.close()


@pytest.mark.parametrize(
    "kwargs,message",
    [
        ({"soil": "quicksand"}, "unknown soil"),
        ({"vehicle": "tractor"}, "unknown vehicle"),
        ({"force_model": "magic"}, "unknown force model"),
        ({"estimator": "oracle9"}, "unknown estimator"),
        ({"path_kwargs": {"radius_m": -1.0}}, "radius_m"),
        ({"path_kwargs": {"speed_mps": 0.0}}, "speed_mps"),
        ({"sol": "loose_sand"}, "did you mean 'soil'"),
        ({"terrain": {"kind": "slope", "slope_deg": 60.0}}, "slope_deg"),
        ({"reward_weights": {"speed": 1.0}}, "unknown reward term"),
        ({"control_hz": 7.0}, "multiple of control_hz"),
    ],
)
def test_bad_configuration_is_a_value_error_naming_the_problem(kwargs, message):
    with pytest.raises(ValueError, match=message):
        gym.make("slipenv/Configurable-v0", **kwargs)


def test_a_negative_wheel_radius_is_rejected():
    from slipenv.vehicles.spec import WheelSpec

    with pytest.raises(ValueError, match="radius_m"):
        WheelSpec("w", (0.0, 0.1, 0.0), -0.1, 0.1, 1.0, "left")


@pytest.mark.parametrize("bad", [[np.nan, 0.0], [0.0, np.inf], [0.5]])
def test_nan_or_malformed_actions_are_a_value_error(bad):
    env = gym.make("slipenv/HuskySand-v0", disable_env_checker=True)
    try:
        env.reset(seed=0)
        with pytest.raises(ValueError, match="action"):
            env.unwrapped.step(np.array(bad, dtype=np.float32))
    finally:
        env.close()


class ExplodingForceModel:
    """A force law that goes berserk after a while: the physics must blow up."""

    def __init__(self, geometry):
        self.calls = 0

    def __call__(self, slip, tan_beta, load_n, soil):
        self.calls += 1
        gain = 1e9 if self.calls > 200 else 0.0
        return gain * np.ones_like(slip), np.zeros_like(slip)

    def resistance_n(self, load_n, soil):
        return np.zeros_like(load_n)


def test_a_physics_blow_up_truncates_the_episode_with_a_reason_not_a_nan():
    env = gym.make("slipenv/Configurable-v0", force_model=ExplodingForceModel,
                   disable_env_checker=True)
    try:
        env.reset(seed=0)
        for _ in range(50):
            obs, reward, terminated, truncated, info = env.step(ACTION)
            assert np.all(np.isfinite(obs)) and np.isfinite(reward)
            if truncated:
                break
        assert truncated and not terminated
        assert "blow-up" in info["truncation_reason"]
    finally:
        env.close()


def test_reward_terms_are_reported_and_weighted_by_config():
    env = gym.make("slipenv/HuskySand-v0", reward_weights={"progress": 0.0, "effort": 0.0,
                                                           "heading": 0.0, "cross_track": 2.0})
    try:
        env.reset(seed=0)
        _, reward, _, _, info = env.step(ACTION)
        assert set(info["reward_terms"]) == {"cross_track", "heading", "progress", "effort"}
        assert reward == pytest.approx(2.0 * info["reward_terms"]["cross_track"])
    finally:
        env.close()


def test_human_rendering_without_a_display_is_a_clear_error(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    with pytest.raises(RuntimeError, match="rgb_array"):
        gym.make("slipenv/HuskySand-v0", render_mode="human")
