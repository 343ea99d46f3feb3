"""The tracked slope env with Yamauchi's controllers used as policies (``predict`` on the env).

Both controllers are the Yamauchi §3 law with the gains the baseline uses for 5 cm/s
(``slipenv.controllers.baseline_controller``): Eq. 10 with the observation's β̂ (feed-forward) and
Eq. 9 with β = 0 (feedback), on the env's default observation (slip-compensated odometry).
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import slipenv  # noqa: F401
from slipenv.contracts.observation import OBS_SLIP_ANGLE
from slipenv.controllers import baseline_controller
from slipenv.controllers.yamauchi import YamauchiController
from slipenv.envs.registration import yamauchi_observation
from slipenv.experiments.yamauchi import Settings, circle_episode

ENV_ID = "slipenv/TrackedSlopeCircle-v0"
FLAT_RIGID = dict(terrain="flat", soil="concrete")
# Stated bounds on flat rigid ground, r = 0.25 m at 5 cm/s: mean |cross-track| under 5 cm
# (a fifth of the radius), and never more than 20 cm.
FLAT_MEAN_BOUND_M = 0.05
FLAT_MAX_BOUND_M = 0.20
WHOLE_LAP_M = 1.0  # [m] a corridor wide enough that no lap on the slope ends early


def lap(feedforward: bool, seed: int, **env_kwargs) -> dict:
    """One lap of the circle; true cross-track statistics and how it ended."""
    env = gym.make(ENV_ID, **env_kwargs)
    policy = baseline_controller(env, use_feedforward=feedforward)
    obs, _ = env.reset(seed=seed)
    policy.reset()
    errors = []
    while True:
        action, _ = policy.predict(obs, deterministic=True)
        obs, _, terminated, truncated, info = env.step(action)
        errors.append(abs(info["cross_track_true_m"]))
        if terminated or truncated:
            break
    env.close()
    return {"mean": float(np.mean(errors)), "max": float(np.max(errors)),
            "success": bool(info.get("is_success"))}


def test_the_default_observation_is_slip_compensated_odometry_with_beta_hat():
    env = gym.make(ENV_ID)
    assert env.unwrapped.config.estimator == "slip_compensated"
    obs, _ = env.reset(seed=0)
    turn = np.array([0.05 / 0.3, math.radians(20.0) / math.radians(45.0)], dtype=np.float32)
    for _ in range(40):
        obs, _, _, _, info = env.step(turn)
    env.close()
    extras = info["estimator_extras"]
    assert {"roll_rad", "angular_displacement_rad", "rotation_radius_m"} <= set(extras)
    assert abs(extras["roll_rad"]) > math.radians(5.0)  # on the 15° side slope
    assert obs[OBS_SLIP_ANGLE] != 0.0 and abs(obs[OBS_SLIP_ANGLE]) < 1.0


@pytest.mark.parametrize("feedforward", [
    pytest.param(False, id="feedback", marks=pytest.mark.xfail(strict=True, reason=(
        "the env observes slip-compensated odometry with the Eq. 9 fit of the sand's "
        "rotation runs (the shipped model), which on concrete adds a slip angle rigid ground "
        "does not have: Eq. 9 without the feed-forward follows that odometry off the circle "
        "(whole lap on seed 0: mean 5.9 cm, max 17.8 cm; it leaves the 0.1 m corridor at "
        "0.1008 m), while Eq. 10, fed the same β̂, cancels it (mean 3.8 cm, max 6.8 cm)"))),
    pytest.param(True, id="feedforward"),
])
def test_on_flat_rigid_ground_both_controllers_stay_within_the_stated_bound(feedforward):
    result = lap(feedforward, seed=0, **FLAT_RIGID)
    assert result["success"]
    assert result["mean"] < FLAT_MEAN_BOUND_M
    assert result["max"] < FLAT_MAX_BOUND_M


@pytest.mark.xfail(strict=True, reason=(
    "the Wong-Chiang track model on toyoura_sand slides off Yamauchi's r = 0.25 m circle on "
    "the 15° slope: over a whole lap its true cross-track reaches 0.35-0.37 m with Eq. 9 and "
    "0.37-0.47 m with Eq. 10 (seeds 0-2, measured in a 1 m corridor), beyond the env's 0.1 m "
    "corridor (0.4 r); steered on the true pose and β the reproduction's lap still reaches "
    "0.22 m (slipenv reproduce yamauchi, metrics.limits.path_following.truth)"))
@pytest.mark.parametrize("feedforward", [False, True], ids=["feedback", "feedforward"])
def test_on_the_15_degree_slope_both_controllers_complete_the_lap(feedforward):
    """Inside the env's corridor, 0.4 of the radius, all the way round."""
    result = lap(feedforward, seed=0)
    assert result["success"]


@pytest.mark.xfail(strict=True, reason=(
    "on the env's slip-compensated odometry the feed-forward is worse on every seed (whole-lap "
    "mean 14.1 / 13.6 / 12.0 cm against 11.3 / 12.1 / 11.8 cm with Eq. 9, seeds 0-2): the "
    "odometry, not the law, limits the lap; its slip-compensated position is 0.67 of "
    "gyrodometry's error on held-out rotation runs, 0.54 even with the true β, because Eq. 8 "
    "fits the 15° slips with R² 0.34 (slipenv reproduce yamauchi, full run). With the true "
    "pose and β the feed-forward does beat feedback (next test)."))
def test_on_the_15_degree_slope_feedforward_beats_feedback_on_every_seed():
    # The whole lap is compared: a corridor of 1 m (four radii) ends no lap early.
    for seed in (0, 1, 2):
        assert (lap(True, seed, max_cross_track_m=WHOLE_LAP_M)["mean"]
                < lap(False, seed, max_cross_track_m=WHOLE_LAP_M)["mean"])


def truth_lap(feedforward: bool, pole_rps: float) -> float:
    """Mean |cross-track| [m] of a lap steered on the *true* pose, speed and slip angle.

    One seed: steering on the truth, the sensor noise that seeds draw plays no part.
    """
    kwargs = yamauchi_observation()["estimator_kwargs"]
    lap = circle_episode(Settings(), pole_rps, feedforward, "slip_compensated", kwargs, 0,
                         15.0, steer_on="truth")
    return lap["mean_error_m"]


def test_with_the_true_pose_and_slip_angle_the_feedforward_about_halves_the_circle_error():
    """The law itself works on the slope: Eq. 10 fed the true β (and steering on the true
    pose) against Eq. 9 with the same gains (measured 1.9 against 4.9 cm on the Wong-Chiang
    track model on toyoura_sand)."""
    feedback, feedforward = truth_lap(False, 0.6), truth_lap(True, 0.6)
    assert feedforward < 0.55 * feedback
    assert feedforward < 0.035


@pytest.mark.parametrize("path_kwargs", [
    {"radius_m": -0.25, "speed_mps": 0.05},
    {"radius_m": 0.25, "speed_mps": 0.0},
], ids=["negative radius", "zero speed"])
def test_a_path_that_makes_no_sense_is_a_clear_error(path_kwargs):
    with pytest.raises(ValueError, match="radius_m|speed_mps"):
        gym.make(ENV_ID, path_kwargs=path_kwargs)


@pytest.mark.parametrize("gains", [
    {"k_eta": -1.0}, {"k_phi": 0.0}, {"k_omega": float("nan")},
], ids=["negative k_eta", "zero k_phi", "nan k_omega"])
def test_gains_that_make_no_sense_are_a_clear_error(gains):
    with pytest.raises(ValueError, match=next(iter(gains))):
        YamauchiController(v_max_mps=0.3, omega_max_rps=0.8, dt_s=0.05, **gains)


@pytest.mark.parametrize("args", [(0.0, 0.05), (0.3, 0.0), (0.3, -0.05)],
                         ids=["zero pole", "zero speed", "negative speed"])
def test_pole_placement_rejects_a_non_positive_pole_or_speed(args):
    with pytest.raises(ValueError, match="pole_rps|speed_mps"):
        YamauchiController.from_poles(*args, v_max_mps=0.3, omega_max_rps=0.8, dt_s=0.05)


def test_a_circle_episode_steering_on_an_unknown_source_is_a_clear_error():
    with pytest.raises(ValueError, match="steer_on must be one of"):
        circle_episode(Settings(), 0.6, True, "slip_compensated", {}, 0, 15.0, steer_on="gps")
