"""Resolving ``--policy``: built-in names, SB3 archives (algorithm detection, residual
composition), objects."""

from __future__ import annotations

import json
import zipfile

import gymnasium as gym
import pytest
from stable_baselines3 import PPO, SAC

from slipenv.evaluation.evaluator import evaluate
from slipenv.evaluation.policies import (
    BUILTIN_POLICIES,
    PolicySource,
    detect_algo,
    resolve_policy,
    saved_composition,
)

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


@pytest.fixture(scope="module")
def residual_run(tmp_path_factory):
    """A residual PPO trained briefly on the short slope circle, in a run folder."""
    from slipenv.agents.train import train

    out = tmp_path_factory.mktemp("residual") / "run"
    train(TRACKED, "ppo", total_timesteps=64, seed=0, n_envs=1, residual=True, out=out,
          algo_kwargs={"n_steps": 64, "batch_size": 32}, checkpoint_freq=0, **SHORT)
    return out


def test_a_residual_model_scores_the_same_from_its_run_a_bare_copy_and_sb3s_load(
        residual_run, tmp_path, slipenv_eval):
    bare = tmp_path / "elsewhere" / "agent.zip"  # no config.json anywhere near it
    bare.parent.mkdir()
    bare.write_bytes((residual_run / "model.zip").read_bytes())
    loaded = PPO.load(bare, device="cpu")

    def score(policy):
        return evaluate(policy, TRACKED, [0], SHORT, max_steps=40).per_episode

    from_run = score(str(residual_run / "model.zip"))
    assert score(str(bare)) == from_run
    assert score(loaded) == from_run
    assert slipenv_eval(loaded, TRACKED, seeds=[0], max_steps=40, **SHORT).per_episode == from_run
    assert slipenv_eval(str(bare), TRACKED, seeds=[0], max_steps=40,
                        **SHORT).per_episode == from_run
    # Read as a plain agent (its residual taken for the whole action) it scores otherwise.
    plain = resolve_policy(str(bare))
    plain = PolicySource(plain.label, plain.kind, "plain-reading", model_path=plain.model_path,
                         algo=plain.algo)
    assert score(plain) != from_run


def test_the_residual_composition_is_read_from_the_archive_itself(residual_run):
    assert saved_composition(residual_run / "model.zip") == {"controller": "yamauchi",
                                                             "scale": 0.3}
    assert resolve_policy(str(residual_run / "model.zip")).residual["scale"] == 0.3


def test_a_plain_model_stays_plain(saved):
    assert saved_composition(saved["ppo"]) is None
    assert resolve_policy(str(saved["ppo"])).residual is None
    assert resolve_policy(PPO.load(saved["ppo"], device="cpu")).residual is None


def test_an_archive_marked_residual_without_its_composition_is_refused(residual_run, tmp_path):
    damaged = tmp_path / "model.zip"
    with zipfile.ZipFile(residual_run / "model.zip") as src, \
            zipfile.ZipFile(damaged, "w") as dst:
        for item in src.infolist():
            payload = src.read(item)
            if item.filename == "data":
                data = json.loads(payload)
                del data["action_space"]["residual_controller"]
                payload = json.dumps(data).encode()
            dst.writestr(item, payload)
    with pytest.raises(ValueError, match="holds a residual agent but not its composition"):
        resolve_policy(str(damaged))


def test_a_model_trained_on_another_env_is_refused_not_scored():
    pendulum = gym.make("Pendulum-v1")
    model = PPO("MlpPolicy", pendulum, n_steps=64, batch_size=32, device="cpu")
    pendulum.close()
    with pytest.raises(ValueError, match=r"observation_space of shape \(3,\).*another env"):
        evaluate(model, TRACKED, [0], SHORT, max_steps=5)
