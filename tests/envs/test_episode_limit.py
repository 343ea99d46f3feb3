"""The episode's step limit follows the make kwargs ``max_episode_s`` and ``control_hz``.

No id registers a fixed ``max_episode_steps``: Gymnasium's ``TimeLimit`` would otherwise cut
every episode at the preset's count, whatever time limit or control rate the kwargs ask for.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import slipenv  # noqa: F401
from slipenv.envs.registration import PRESETS, preset_config
from slipenv.envs.slip_env import episode_steps

HUSKY = "slipenv/HuskySand-v0"
STOP = np.zeros(2, dtype=np.float32)  # parked at the path's start: never terminates


def run_to_truncation(env: gym.Env) -> tuple[int, float]:
    """Steps from ``reset`` until the episode ends, which must be a time-limit truncation, and
    the simulated time then [s]."""
    env.reset(seed=0)
    steps = 0
    while True:
        steps += 1
        _, _, terminated, truncated, info = env.step(STOP)
        if terminated or truncated:
            assert truncated and not terminated, info
            assert info.get("truncation_reason", "time limit") == "time limit"
            return steps, info["t_s"]


@pytest.mark.parametrize("env_id", sorted(PRESETS))
def test_no_id_registers_a_fixed_step_count(env_id):
    assert gym.spec(env_id).max_episode_steps is None
    env = gym.make(env_id)
    try:
        assert env.spec is not None and env.spec.max_episode_steps is None
        wrappers = []
        layer = env
        while isinstance(layer, gym.Wrapper):
            wrappers.append(type(layer).__name__)
            layer = layer.env
        assert "TimeLimit" not in wrappers
        cfg = preset_config(env_id)
        assert env.unwrapped.max_steps == round(cfg.max_episode_s * cfg.control_hz)
    finally:
        env.close()


def test_twice_the_presets_time_runs_twice_the_presets_steps():
    preset_s = preset_config(HUSKY).max_episode_s
    preset_steps = episode_steps(preset_s, 20.0)
    assert preset_steps == 800
    env = gym.make(HUSKY, max_episode_s=2 * preset_s)
    try:
        assert run_to_truncation(env)[0] == 2 * preset_steps
    finally:
        env.close()


@pytest.mark.parametrize(("max_episode_s", "control_hz"), [(1.0, 20.0), (1.0, 40.0),
                                                            (2.0, 40.0), (0.5, 10.0)])
def test_the_episode_runs_max_episode_s_times_control_hz_steps(max_episode_s, control_hz):
    env = gym.make(HUSKY, max_episode_s=max_episode_s, control_hz=control_hz)
    try:
        steps, t_s = run_to_truncation(env)
        assert steps == round(max_episode_s * control_hz)
        assert t_s == pytest.approx(max_episode_s, abs=1e-9)  # max_episode_s simulated
    finally:
        env.close()


def test_an_explicit_max_episode_steps_still_adds_gymnasiums_time_limit():
    env = gym.make(HUSKY, max_episode_s=1.0, max_episode_steps=5)
    try:
        assert env.spec.max_episode_steps == 5
        assert run_to_truncation(env)[0] == 5
    finally:
        env.close()


@pytest.mark.parametrize(("seconds", "hz", "steps"), [
    (40.0, 20.0, 800), (0.1, 30.0, 3), (0.07, 20.0, 2), (170.0, 20.0, 3400), (1e-3, 20.0, 1),
])
def test_a_time_limit_is_rounded_up_to_a_whole_step(seconds, hz, steps):
    assert episode_steps(seconds, hz) == steps
