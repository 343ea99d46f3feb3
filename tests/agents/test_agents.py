"""Agents and the baseline are trained and evaluated through the same SB3 entry points."""

from __future__ import annotations

import numpy as np
import pytest

from slipenv.agents.residual import ResidualActionWrapper
from slipenv.agents.train import evaluate, make_env, train

ENV = "slipenv/HuskySand-v0"
SHORT = {"max_episode_s": 6.0}


def test_a_zero_residual_drives_exactly_like_the_baseline():
    from slipenv.controllers.baseline import baseline_controller

    wrapped = make_env(ENV, residual=True, **SHORT)
    plain = make_env(ENV, **SHORT)
    policy = baseline_controller(plain)
    obs_w, _ = wrapped.reset(seed=4)
    obs_p, _ = plain.reset(seed=4)
    policy.reset()
    for _ in range(30):
        obs_w, *_ = wrapped.step(np.zeros(2, dtype=np.float32))
        obs_p, *_ = plain.step(policy.act(obs_p))
    np.testing.assert_array_equal(obs_w, obs_p)
    wrapped.close()
    plain.close()


def test_the_residual_scale_must_be_a_fraction():
    env = make_env(ENV, **SHORT)
    with pytest.raises(ValueError, match="scale"):
        ResidualActionWrapper(env, scale=2.0)
    env.close()


def test_baseline_and_a_trained_agent_are_evaluated_by_the_same_code(tmp_path):
    model = train(ENV, total_timesteps=512, n_envs=2, seed=0, residual=True,
                  out=str(tmp_path / "ppo"), **SHORT)
    assert (tmp_path / "ppo" / "model.zip").exists()  # OUT is now a run folder
    agent = evaluate(model, ENV, n_episodes=1, residual=True, **SHORT)
    baseline = evaluate("baseline", ENV, n_episodes=1, **SHORT)
    for result in (agent, baseline):
        assert np.isfinite(result.mean_return)
        assert 0.0 <= result.mean_abs_cross_track_m < 2.0
    # The baseline path follower keeps the true cross-track error small on this task.
    assert baseline.mean_abs_cross_track_m < 0.5


def test_unknown_algorithm_is_a_value_error():
    with pytest.raises(ValueError, match="unknown algorithm"):
        train(ENV, algo="dqn", total_timesteps=10)
