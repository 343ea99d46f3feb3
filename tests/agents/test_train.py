"""``slipenv train``: run folder, hyperparameter files (rl-zoo3 layout), residual policies."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
import yaml

from slipenv.agents.residual import ResidualActionWrapper, ResidualPolicy
from slipenv.agents.train import ALGORITHMS, load_policy, make_env, resolve_config, train
from slipenv.agents.zoo import HYPERPARAMS_DIR, hyperparams_path, parse, read_entry
from slipenv.cli import main
from slipenv.controllers.baseline import baseline_controller

ENV = "slipenv/HuskySand-v0"
SHORT = {"max_episode_s": 4.0}


@pytest.fixture(scope="module")
def ppo_run(tmp_path_factory):
    """PPO trained for ~300 steps through the command line."""
    out = tmp_path_factory.mktemp("train") / "run"
    code = main(["train", ENV, "--algo", "ppo", "--timesteps", "300", "--n-envs", "1",
                 "--seed", "3", "--out", str(out), "--episodes", "1", "--quiet"])
    assert code == 0
    return out


def test_a_training_run_writes_model_config_checkpoints_and_logs(ppo_run):
    assert (ppo_run / "model.zip").stat().st_size > 1000
    assert sorted(p.name for p in (ppo_run / "checkpoints").glob("model_*_steps.zip"))
    csv = (ppo_run / "logs" / "progress.csv").read_text().splitlines()
    assert "time/total_timesteps" in csv[0] and len(csv) >= 2
    assert list((ppo_run / "logs").glob("events.out.tfevents.*"))  # TensorBoard
    config = json.loads((ppo_run / "config.json").read_text())
    assert config["env_id"] == ENV and config["algo"] == "ppo" and config["seed"] == 3
    assert config["residual"] is True and config["n_envs"] == 1
    assert config["total_timesteps"] == 300 and config["timesteps_done"] >= 300
    assert config["hyperparameters"]["n_steps"] == 256  # from the shipped ppo.yml
    assert config["slipenv_version"] and config["hyperparams_file"].endswith("ppo.yml")
    assert isinstance(config["env_kwargs"], dict)


def test_a_saved_residual_run_drives_the_plain_env_like_the_wrapper(ppo_run):
    policy, config = load_policy(ppo_run)
    assert isinstance(policy, ResidualPolicy) and config["residual"]
    plain = make_env(ENV, **SHORT)
    wrapped = make_env(ENV, residual=True, **SHORT)
    try:
        obs_p, _ = plain.reset(seed=5)
        obs_w, _ = wrapped.reset(seed=5)
        policy.reset()
        for _ in range(20):
            residual, _ = policy.model.predict(obs_w, deterministic=True)
            obs_w, *_ = wrapped.step(residual)
            obs_p, *_ = plain.step(policy.act(obs_p))
        np.testing.assert_array_equal(obs_p, obs_w)
    finally:
        plain.close()
        wrapped.close()


def test_training_twice_with_the_same_seed_gives_the_same_policy(tmp_path):
    models = [train(ENV, "ppo", total_timesteps=128, seed=1, n_envs=1,
                    algo_kwargs={"n_steps": 64}, **SHORT) for _ in range(2)]
    for a, b in zip(models[0].policy.parameters(), models[1].policy.parameters(), strict=True):
        assert np.array_equal(a.detach().numpy(), b.detach().numpy())


@pytest.mark.parametrize("algo", ["sac", "td3"])
def test_off_policy_algorithms_train_and_update(algo, tmp_path):
    model = train(ENV, algo, total_timesteps=120, seed=0, n_envs=1, out=tmp_path,
                  algo_kwargs={"learning_starts": 40, "batch_size": 32}, **SHORT)
    assert model._n_updates > 0  # gradient steps happened past learning_starts
    assert (tmp_path / "model.zip").exists()
    if algo == "td3":
        assert json.loads((tmp_path / "config.json").read_text())["action_noise"] == [
            "normal", 0.1]


def test_more_than_one_env_trains_in_subprocesses(tmp_path):
    from stable_baselines3.common.vec_env import SubprocVecEnv

    model = train(ENV, "ppo", total_timesteps=128, seed=0, n_envs=2,
                  algo_kwargs={"n_steps": 64}, **SHORT)
    assert model.n_envs == 2
    assert isinstance(model.get_env(), SubprocVecEnv)


def test_every_registered_env_has_hyperparameters_for_every_algorithm():
    ids = [e for e in gym.registry if e.startswith("slipenv/")]
    for algo, cls in ALGORITHMS.items():
        path = hyperparams_path(algo)
        assert path.parent == HYPERPARAMS_DIR
        data = yaml.safe_load(path.read_text())
        for env_id in ids:
            hp = parse(data[env_id], cls, f"{path} [{env_id}]")
            assert hp.policy == "MlpPolicy" and hp.n_timesteps >= 10_000 and hp.residual


def test_a_typo_in_a_hyperparameter_file_is_a_clear_error(tmp_path):
    bad = tmp_path / "ppo.yml"
    bad.write_text(f"{ENV}:\n  n_timesteps: 1000\n  policy: MlpPolicy\n  n_step: 64\n")
    with pytest.raises(ValueError, match=r"'n_step' is not a PPO argument; did you mean 'n_steps'"):
        resolve_config(ENV, "ppo", hyperparams=bad)
    bad.write_text(f"{ENV}:\n  n_timesteps: 1000\n  normalize: true\n")
    with pytest.raises(ValueError, match="normalize.*not supported"):
        resolve_config(ENV, "ppo", hyperparams=bad)
    bad.write_text("slipenv/HuskySand-v1:\n  n_timesteps: 1000\n")
    with pytest.raises(ValueError, match="no entry 'slipenv/HuskySand-v0'.*did you mean"):
        read_entry(ENV, bad)
    bad.write_text(f"{ENV}: [unclosed\n")
    with pytest.raises(ValueError, match="not valid YAML"):
        read_entry(ENV, bad)


def test_bad_training_arguments_fail_before_any_env_is_built():
    for kwargs, match in (({"algo": "dqn"}, "unknown algorithm"),
                          ({"total_timesteps": 0}, "total_timesteps must be >= 1"),
                          ({"n_envs": 0}, "n_envs must be >= 1"),
                          ({"seed": -1}, "seed must be >= 0")):
        with pytest.raises(ValueError, match=match):
            resolve_config(ENV, **kwargs)
    with pytest.raises(ValueError, match="unknown env id"):
        resolve_config("slipenv/Nope-v0")


def test_the_residual_policy_needs_a_model_with_predict():
    env = gym.make(ENV)
    try:
        with pytest.raises(TypeError, match="predict"):
            ResidualPolicy(object(), baseline_controller(env))
        with pytest.raises(ValueError, match="scale"):
            ResidualActionWrapper(env, scale=0.0)
    finally:
        env.close()


def test_load_policy_rejects_a_folder_that_is_not_a_run(tmp_path):
    with pytest.raises(ValueError, match="not a slipenv training run"):
        load_policy(tmp_path)


@pytest.mark.slow
def test_rl_zoo3_trains_with_the_shipped_hyperparameter_file(tmp_path):
    pytest.importorskip("rl_zoo3")
    cmd = [sys.executable, "-m", "rl_zoo3.train", "--gym-packages", "slipenv", "--env", ENV,
           "--algo", "ppo", "-n", "300", "--conf-file", str(hyperparams_path("ppo")),
           "-f", str(tmp_path), "--seed", "0", "--eval-freq", "-1", "--device", "cpu"]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PYTHONWARNINGS": "ignore"})
    assert done.returncode == 0, done.stderr[-2000:]
    saved = list(tmp_path.rglob("*.zip"))
    assert saved, done.stdout[-2000:]
    config = next(tmp_path.rglob("config.yml")).read_text()
    assert "ResidualActionWrapper" in config and "n_steps" in config
