"""Resolving ``--policy``: built-in names, SB3 archives (algorithm detection), objects."""

from __future__ import annotations

import json

import gymnasium as gym
import pytest
from stable_baselines3 import PPO, SAC

from slipenv.evaluation.evaluator import evaluate
from slipenv.evaluation.policies import BUILTIN_POLICIES, detect_algo, resolve_policy

from .conftest import SHORT, TRACKED


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """An untrained PPO and SAC saved as SB3 archives (no config.json)."""
    folder = tmp_path_factory.mktemp("models")
    env = gym.make(TRACKED, **SHORT)
    paths = {}
    for name, cls in (("ppo", PPO), ("sac", SAC)):
        model = cls("MlpPolicy", env, seed=0, device="cpu")
        (folder / name).mkdir()
        model.save(folder / name / "model.zip")
        paths[name] = folder / name / "model.zip"
    env.close()
    return paths


def test_builtin_names_resolve_without_a_file():
    for name in BUILTIN_POLICIES:
        source = resolve_policy(name)
        assert source.kind == "builtin" and source.key == name


def test_the_run_commands_controller_names_resolve_to_the_same_policies():
    assert resolve_policy("yamauchi").label == "baseline"
    assert resolve_policy("yamauchi_feedback").label == "feedback"


def test_unknown_name_lists_the_builtin_policies():
    with pytest.raises(ValueError, match="unknown policy 'pure-pursuit'.*pure_pursuit"):
        resolve_policy("pure-pursuit")


def test_algorithm_is_detected_from_the_saved_archive(saved):
    assert detect_algo(saved["ppo"]) == "ppo"
    assert detect_algo(saved["sac"]) == "sac"


def test_config_json_next_to_the_model_names_the_algorithm_and_residual(saved, tmp_path):
    model = tmp_path / "model.zip"
    model.write_bytes(saved["ppo"].read_bytes())
    (tmp_path / "config.json").write_text(json.dumps(
        {"algo": "ppo", "residual": True, "residual_scale": 0.2}))
    source = resolve_policy(str(model))
    assert source.algo == "ppo" and source.residual == {"scale": 0.2}
    env = source.wrap_env(gym.make(TRACKED, **SHORT))
    assert type(env).__name__ == "ResidualActionWrapper" and env.scale == 0.2
    env.close()


def test_a_file_that_is_not_an_sb3_archive_is_rejected(tmp_path):
    bad = tmp_path / "model.zip"
    bad.write_text("not a zip")
    with pytest.raises(ValueError, match="not a stable-baselines3 model archive"):
        resolve_policy(str(bad))


def test_a_saved_model_is_loaded_and_evaluated_deterministically(saved):
    first = evaluate(str(saved["ppo"]), TRACKED, [0], SHORT, max_steps=30)
    again = evaluate(str(saved["ppo"]), TRACKED, [0], SHORT, max_steps=30)
    assert first.per_episode == again.per_episode
    assert first.per_episode[0]["steps"] <= 30
