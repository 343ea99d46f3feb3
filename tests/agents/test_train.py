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
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.env_util import make_vec_env

from slipenv.agents.residual import ResidualActionWrapper, ResidualPolicy, residual_composition
from slipenv.agents.train import (
    ALGORITHMS,
    load_policy,
    make_env,
    planned_timesteps,
    resolve_config,
    timesteps_note,
    train,
)
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
    # 300 requested; PPO runs whole rollouts of n_steps (256) x 1 env: 512 planned and run.
    assert config["requested_timesteps"] == 300
    assert config["total_timesteps"] == config["timesteps_done"] == 512
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


def test_more_than_one_env_trains_in_subprocesses_and_warns_beyond_the_cores(monkeypatch):
    from stable_baselines3.common.vec_env import SubprocVecEnv

    monkeypatch.setattr("slipenv.agents.train.os.cpu_count", lambda: 1)
    with pytest.warns(UserWarning, match="n_envs=2 exceeds the 1 CPU cores"):
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


def test_a_residual_models_zip_alone_rebuilds_its_policy(ppo_run, tmp_path):
    bare = tmp_path / "agent.zip"
    bare.write_bytes((ppo_run / "model.zip").read_bytes())
    env = make_env(ENV, **SHORT)
    try:
        policy, config = load_policy(bare, env=env)
        assert isinstance(policy, ResidualPolicy) and policy.scale == 0.3
        assert config == {"algo": "ppo"}
        with pytest.raises(ValueError, match="pass env="):
            load_policy(bare)
        # PPO.load users: from_model composes the same policy for the plain env.
        direct = ResidualPolicy.from_model(PPO.load(bare, device="cpu"), env)
        obs, _ = env.reset(seed=2)
        policy.reset()
        direct.reset()
        np.testing.assert_array_equal(direct.act(obs), policy.act(obs))
    finally:
        env.close()


def test_a_plain_model_is_not_taken_for_a_residual_one():
    env = make_env(ENV, **SHORT)
    try:
        model = PPO("MlpPolicy", env, n_steps=64, batch_size=32, device="cpu")
        assert residual_composition(model) is None
        with pytest.raises(ValueError, match="records no residual composition"):
            ResidualPolicy.from_model(model, env)
    finally:
        env.close()


def test_a_model_trained_on_the_wrapper_by_sb3_alone_records_its_composition(tmp_path):
    # rl-zoo3 builds its envs this way from the YAML's env_wrapper.
    vec = make_vec_env(ENV, n_envs=1, env_kwargs=SHORT, wrapper_class=ResidualActionWrapper,
                       wrapper_kwargs={"scale": 0.2, "controller": "stanley"})
    model = PPO("MlpPolicy", vec, n_steps=32, batch_size=32, device="cpu")
    model.save(tmp_path / "zoo.zip")
    vec.close()
    loaded = PPO.load(tmp_path / "zoo.zip", device="cpu")
    assert residual_composition(loaded) == {"controller": "stanley", "scale": 0.2}


@pytest.mark.parametrize(("algo", "requested", "n_envs", "hyper", "planned"), [
    ("ppo", 300, 1, {"n_steps": 256}, 512),
    ("ppo", 512, 2, {"n_steps": 256}, 512),
    ("ppo", 513, 2, {"n_steps": 256}, 1024),
    ("sac", 10, 3, {}, 12),
    ("td3", 10, 1, {"train_freq": [4, "step"]}, 12),
    ("sac", 10, 1, {"train_freq": [2, "episode"]}, 10),
])
def test_the_planned_timesteps_are_the_request_rounded_up_to_whole_rollouts(
        algo, requested, n_envs, hyper, planned):
    assert planned_timesteps(algo, requested, n_envs, hyper) == planned


def test_the_config_says_how_many_steps_will_run_and_why():
    config, _ = resolve_config(ENV, "ppo", total_timesteps=300, n_envs=1)
    assert (config.requested_timesteps, config.total_timesteps) == (300, 512)
    assert timesteps_note(config) == ("300 steps requested; ppo trains whole rollouts of "
                                      "n_steps × n_envs, so 512 will run")
    exact, _ = resolve_config(ENV, "ppo", total_timesteps=512, n_envs=1)
    assert timesteps_note(exact) is None


def test_an_offpolicy_run_does_exactly_the_planned_steps():
    model = train(ENV, "sac", total_timesteps=7, seed=0, n_envs=1,
                  algo_kwargs={"learning_starts": 100, "train_freq": [3, "step"]}, **SHORT)
    assert model.num_timesteps == planned_timesteps("sac", 7, 1, {"train_freq": [3, "step"]})


@pytest.mark.parametrize(("line", "message"), [
    ("n_steps: -64", "n_steps must be >= 1, got -64"),
    ("n_steps: lots", "n_steps must be an integer, got 'lots'"),
    ("n_epochs: 2.5", "n_epochs must be an integer, got 2.5"),
    ("gamma: 1.5", r"gamma must be in \(0, 1\], got 1.5"),
    ("learning_rate: lin_fast", "learning_rate: 'fast' is not a number"),
    ("clip_range: 0", r"clip_range must be in \(0, inf\), got 0"),
    ("ent_coef: -0.1", r"ent_coef must be in \[0, inf\), got -0.1"),
    ("batch_size: 1", "batch_size must be >= 2 for PPO"),
    ("use_sde: 1", "use_sde must be true or false, got 1"),
    ("policy: Mlp", "policy must be one of"),
    ("policy_kwargs: 'dict(net_arch=[64,'", "policy_kwargs .* is not a dict"),
    ("env_kwargs: [1, 2]", "env_kwargs must be a mapping"),
    ("seed: 3", "seed: set by slipenv train itself"),
    ("n_envs: 0", "n_envs must be >= 1, got 0"),
    ("env_wrapper: {slipenv.agents.residual.ResidualActionWrapper: {scale: 2}}",
     r"env_wrapper scale must be in \(0, 1\], got 2.0"),
])
def test_a_bad_hyperparameter_value_is_one_line_naming_the_file_and_key(tmp_path, line,
                                                                       message):
    bad = tmp_path / "mine.yml"
    bad.write_text(f"{ENV}:\n  n_timesteps: 1000\n  {line}\n")
    with pytest.raises(ValueError, match=rf"mine.yml \[{ENV}\]: {message}") as info:
        resolve_config(ENV, "ppo", hyperparams=bad)
    assert "\n" not in str(info.value)


def test_a_combination_sb3_rejects_is_a_value_error_not_an_assertion(tmp_path):
    with pytest.raises(ValueError, match=r"ppo rejects these hyperparameters: .*n_steps"):
        train(ENV, "ppo", total_timesteps=10, n_envs=1,
              algo_kwargs={"n_steps": 1, "batch_size": 2}, **SHORT)


class _CtrlC(BaseCallback):
    """Raises KeyboardInterrupt, as Ctrl-C does, after ``after`` calls."""

    def __init__(self, after: int) -> None:
        super().__init__()
        self.after = after

    def _on_step(self) -> bool:
        if self.n_calls >= self.after:
            raise KeyboardInterrupt
        return True


def test_ctrl_c_saves_the_model_so_far_and_reraises(tmp_path):
    with pytest.raises(KeyboardInterrupt):
        train(ENV, "ppo", total_timesteps=256, seed=0, n_envs=1, out=tmp_path,
              algo_kwargs={"n_steps": 64, "batch_size": 32}, checkpoint_freq=0,
              callbacks=[_CtrlC(after=100)], **SHORT)
    assert not (tmp_path / "model.zip").exists()
    config = json.loads((tmp_path / "config.json").read_text())
    assert config["interrupted"] is True and config["timesteps_done"] == 100
    policy, _ = load_policy(tmp_path / "interrupted.zip")
    assert isinstance(policy, ResidualPolicy)


CTRL_C_SCRIPT = """
import sys
from slipenv.agents.train import train

if __name__ == "__main__":
    try:
        train("slipenv/HuskySand-v0", "ppo", total_timesteps=100_000, n_envs=2, out=sys.argv[1],
              algo_kwargs={"n_steps": 64}, checkpoint_freq=0, max_episode_s=4.0)
    except KeyboardInterrupt:
        print("interrupted")
        sys.exit(130)
"""


@pytest.mark.slow
def test_a_terminals_ctrl_c_reaching_the_workers_too_still_saves_the_model(tmp_path):
    import signal
    import time

    script, out = tmp_path / "run.py", tmp_path / "run"
    script.write_text(CTRL_C_SCRIPT)
    proc = subprocess.Popen([sys.executable, str(script), str(out)], start_new_session=True,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    progress = out / "logs" / "progress.csv"
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline and proc.poll() is None:
        if progress.is_file() and len(progress.read_text().splitlines()) >= 2:
            break  # one update done: the workers are stepping
        time.sleep(0.5)
    os.killpg(proc.pid, signal.SIGINT)  # what a terminal does: every process of the group
    # generous: saving the model and closing the workers share two cores with the other tests
    output, _ = proc.communicate(timeout=300)
    assert proc.returncode == 130, output[-2000:]
    assert output.strip() == "interrupted"  # no worker tracebacks
    assert (out / "interrupted.zip").is_file()
    assert json.loads((out / "config.json").read_text())["interrupted"] is True
