"""The visual rover env: sComp odometry with FTrace's slip angle from the rear trace camera."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import slipenv  # noqa: F401  (registers the envs)

VISUAL_ID = "slipenv/RoverMoundsVisual-v0"
FORWARD = np.array([0.27, 0.0], np.float32)  # 8 cm/s on rover_4ws (v_max 0.3 m/s)
SIDE_SLOPE = dict(vehicle="rover_4ws", soil="lunar_simulant", force_model="reina",
                  terrain={"kind": "slope", "slope_deg": 12.0, "downhill_azimuth_deg": -90.0},
                  path="straight", path_kwargs={"length_m": 5.0, "speed_mps": 0.08},
                  estimator="scomp", max_episode_s=60.0, start_jitter=(0.0, 0.0))


def test_visual_rover_passes_the_env_checker():
    env = gym.make(VISUAL_ID, render_mode="rgb_array")
    check_env(env.unwrapped, skip_render_check=False)
    env.close()


def test_observation_carries_the_ftrace_slip_angle_and_scomp_odometry():
    env = gym.make(VISUAL_ID, camera_in_info=True)
    obs, info = env.reset(seed=1)
    assert "trace_frame" in info and "trace_detection" in info
    frames = 0
    for _ in range(80):
        obs, _, _, _, info = env.step(FORWARD)
        frame = info["trace_frame"]
        if frame is not None:
            frames += 1
            assert frame.image.shape == (240, 320) and frame.image.dtype == np.uint8
        det = info["trace_detection"]
        if det is not None and det.found:
            # The observation's slip-angle slot is FTrace's β (held between frames).
            assert obs[6] == pytest.approx(det.slip_angle_rad, abs=1e-6)
        assert info["estimator_extras"]["ftrace_status"] in ("none", "detected", "held")
    assert frames == 20  # 5 Hz over 4 s of 20 Hz steps
    assert info["trace_detection"].found
    est = info["estimated_pose"]
    assert np.hypot(*(est[:2] - info["true_pose"][:2])) < 0.05
    env.close()


def test_camera_frames_stay_out_of_info_by_default_and_render_shows_them():
    env = gym.make(VISUAL_ID, render_mode="rgb_array")
    _, info = env.reset(seed=0)
    assert "trace_frame" not in info
    for _ in range(8):
        env.step(FORWARD)
    image = env.render()
    assert image.shape == (480, 1280, 3) and image.dtype == np.uint8
    panel = image[:, 640:]
    assert panel.std() > 5.0  # a camera frame, not the blank panel
    assert env.unwrapped.trace_frame.image.shape == (240, 320)
    env.close()


def test_rover_mounds_keeps_its_fast_odometry():
    env = gym.make("slipenv/RoverMounds-v0")
    _, info = env.reset(seed=0)
    assert "trace_detection" not in info and env.unwrapped.trace_frame is None
    env.close()


def test_same_seed_gives_the_same_visual_episode():
    def run(seed):
        env = gym.make(VISUAL_ID)
        obs, _ = env.reset(seed=seed)
        out = [obs]
        for _ in range(12):
            out.append(env.step(FORWARD)[0])
        env.close()
        return np.array(out)

    a, b = run(3), run(3)
    np.testing.assert_array_equal(a, b)


def test_ftrace_slip_angle_follows_the_drift_on_a_side_slope():
    """Across a 12° side slope the rover crabs downhill; FTrace's β̂ must follow the truth."""
    env = gym.make("slipenv/Configurable-v0", **SIDE_SLOPE)
    env.reset(seed=0)
    est, true = [], []
    for k in range(240):  # 12 s: the trace must first fill the 60 cm footprint
        obs, _, term, trunc, info = env.step(FORWARD)
        if k >= 160:
            est.append(obs[6])
            true.append(info["true_slip_angle_rad"])
        if term or trunc:
            break
    env.close()
    est_deg, true_deg = np.degrees(np.mean(est)), np.degrees(np.mean(true))
    assert true_deg < -1.0  # the drift is downhill (to the right of travel)
    assert est_deg == pytest.approx(true_deg, abs=2.0)


@pytest.mark.parametrize("kwargs, word", [
    ({"slip_model": {"s_x": 0.1}}, "slip_model"),
    ({"camera": {"rate_hz": -1.0}}, "rate_hz"),
    ({"ftrace": {"hough": 3}}, "ftrace"),
    ({"wheel": "middle_left"}, "middle_left"),
])
def test_bad_scomp_options_fail_at_make_time(kwargs, word):
    with pytest.raises(ValueError, match=word):
        gym.make(VISUAL_ID, estimator_kwargs=kwargs)


def test_camera_in_info_must_be_a_bool():
    with pytest.raises(ValueError, match="camera_in_info"):
        gym.make(VISUAL_ID, camera_in_info="yes")


def test_slip_angle_is_finite_before_any_trace():
    env = gym.make(VISUAL_ID)
    obs, _ = env.reset(seed=0)
    assert math.isfinite(obs[6]) and obs[6] == 0.0
    env.close()
