"""The one rollout loop (``slipenv.rollout``) and its trajectory recorder."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import slipenv  # noqa: F401  (registers the envs)
from slipenv.controllers.baseline import baseline_controller
from slipenv.rollout import TrajectoryRecorder, end_reason, rollout

ENV = "slipenv/HuskySand-v0"


@pytest.fixture(scope="module")
def env():
    e = gym.make(ENV, max_episode_s=3.0)
    yield e
    e.close()


def test_the_trajectory_recorder_keeps_the_truth_the_estimate_and_the_actions(env):
    rec = TrajectoryRecorder()
    policy = baseline_controller(env)
    result = rollout(env, policy, seed=1, recorders=[rec])
    traj = rec.trajectory()
    n = result.steps
    assert len(traj) == n == env.unwrapped.max_steps and result.truncated
    assert traj.true_pose.shape == traj.est_pose.shape == (n, 3)
    assert traj.actions.shape == (n, 2) and traj.wheel_slip.shape == (n, 4)
    assert traj.wheel_roles == ("driven",) * 4 and len(traj.driven()) == 4
    np.testing.assert_allclose(np.diff(traj.t_s), env.unwrapped.control_dt_s, rtol=1e-9)
    assert result.episode_return == pytest.approx(traj.rewards.sum())
    assert np.all(np.diff(traj.progress_true) >= 0) and 0 < traj.progress_true[-1] < 1
    assert result.end_reason == "time limit" and not result.success


def test_a_recorder_starts_afresh_at_each_reset_and_seeds_reproduce(env):
    rec = TrajectoryRecorder()
    first = rollout(env, baseline_controller(env), seed=4, max_steps=15, recorders=[rec])
    a = rec.trajectory()
    rollout(env, baseline_controller(env), seed=4, max_steps=15, recorders=[rec])
    b = rec.trajectory()
    assert first.steps == len(a) == len(b) == 15 and first.end_reason == "step limit"
    np.testing.assert_array_equal(a.true_pose, b.true_pose)


def test_max_steps_must_be_positive_and_policies_need_predict_or_call(env):
    with pytest.raises(ValueError, match="max_steps must be >= 1"):
        rollout(env, lambda obs: np.zeros(2), max_steps=0)
    with pytest.raises(TypeError, match="predict"):
        rollout(env, object(), max_steps=1)


def test_the_end_reason_prefers_success_then_the_envs_own_reason():
    assert end_reason({"is_success": True}, True, False) == "path complete"
    assert end_reason({"termination_reason": "left the path corridor"}, True, False) \
        == "left the path corridor"
    assert end_reason({}, False, False) == "step limit"
