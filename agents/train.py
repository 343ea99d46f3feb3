"""Train and evaluate stable-baselines3 agents on slipenv tasks, next to the baseline.

:func:`train` reads the env's hyperparameters (rl-zoo3 YAML, :mod:`slipenv.agents.zoo`), builds
``n_envs`` envs (``SubprocVecEnv`` when more than one; wrapped for residual RL on the baseline
path follower if asked), and trains PPO, SAC or TD3 with a seeded setup. Everything lands in one
run folder::

    OUT/config.json          the exact configuration (env id and kwargs, algorithm,
                             hyperparameters, seed, versions) and, at the end, the wall time
    OUT/model.zip            the final model
    OUT/checkpoints/         model_<steps>_steps.zip along the run
    OUT/logs/progress.csv    SB3's training log; TensorBoard events beside it

:func:`evaluate` runs any policy with SB3's ``predict`` (an SB3 model, a slipenv controller, a
:class:`~slipenv.agents.residual.ResidualPolicy`) through the one rollout loop over distinct
seeds and reports the true cross-track error, so agents and the baseline are compared by the
same code. :func:`load_policy` turns a run folder back into a policy for the plain env.
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3 import PPO, SAC, TD3
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import BaseCallback, CheckpointCallback
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.logger import configure
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

from slipenv.controllers.baseline import baseline_controller
from slipenv.estimators.lindgren.ekf import warm_up
from slipenv.pybullet_quiet import import_pybullet
from slipenv.rollout import TrajectoryRecorder, rollout

from .residual import ResidualActionWrapper, ResidualPolicy
from .zoo import Hyperparams, algo_kwargs_for_sb3, hyperparams_path, parse, read_entry

ALGORITHMS: dict[str, type[BaseAlgorithm]] = {"ppo": PPO, "sac": SAC, "td3": TD3}
LOG_FORMATS = ("stdout", "csv", "tensorboard")


@dataclass(frozen=True)
class Evaluation:
    """Mean and spread of the episode return, and the true cross-track error.

    Attributes
    ----------
    mean_return, std_return : float
    mean_abs_cross_track_m : float
        Mean over all steps of all episodes of |true cross-track error| [m].
    episodes : int
    success_rate : float
        Share of episodes that completed the path (judged on the true pose).
    seeds : tuple of int
        Reset seed of each episode.
    returns : tuple of float
        Return of each episode.
    """

    mean_return: float
    std_return: float
    mean_abs_cross_track_m: float
    episodes: int
    success_rate: float = float("nan")
    seeds: tuple[int, ...] = ()
    returns: tuple[float, ...] = ()


def make_env(env_id: str, residual: bool = False, residual_scale: float = 0.3,
             **env_kwargs: Any) -> gym.Env:
    """One env, wrapped for residual RL if asked (PyBullet's banner silenced, also in
    ``SubprocVecEnv`` workers)."""
    import_pybullet()
    env = gym.make(env_id, **env_kwargs)
    return ResidualActionWrapper(env, scale=residual_scale) if residual else env


class TqdmProgress(BaseCallback):
    """A tqdm progress bar over env steps (SB3's own bar needs ``rich``; tqdm is enough)."""

    def __init__(self, total_timesteps: int) -> None:
        super().__init__()
        self.total = total_timesteps
        self.bar = None

    def _on_training_start(self) -> None:
        from tqdm import tqdm

        self.bar = tqdm(total=self.total, unit="step", desc="train", dynamic_ncols=True)

    def _on_step(self) -> bool:
        if self.bar is not None:  # the last rollout may overshoot the total: stop at 100 %
            self.bar.update(min(self.training_env.num_envs, self.total - self.bar.n))
        return True

    def _on_training_end(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


@dataclass(frozen=True)
class TrainConfig:
    """The exact configuration of a run, saved as ``config.json``."""

    env_id: str
    algo: str
    total_timesteps: int
    seed: int
    n_envs: int
    residual: bool
    residual_scale: float
    policy: str
    env_kwargs: dict
    hyperparameters: dict
    action_noise: list | None
    hyperparams_file: str
    slipenv_version: str
    stable_baselines3_version: str


def resolve_config(env_id: str, algo: str = "ppo", total_timesteps: int | None = None,
                   seed: int = 0, n_envs: int | None = None, residual: bool | None = None,
                   hyperparams: str | Path | None = None, algo_kwargs: dict | None = None,
                   **env_kwargs: Any) -> tuple[TrainConfig, Hyperparams]:
    """Everything a run will use, validated before any env is built.

    Explicit arguments override the hyperparameter file; ``None`` takes the file's value.

    Raises
    ------
    ValueError
        Unknown env id or algorithm, bad numbers, or a bad hyperparameter file.
    """
    from importlib.metadata import version

    if algo not in ALGORITHMS:
        raise ValueError(f"unknown algorithm {algo!r}; known: {sorted(ALGORITHMS)}")
    if env_id not in gym.registry:
        raise ValueError(f"unknown env id {env_id!r}")
    for name, value in (("total_timesteps", total_timesteps), ("n_envs", n_envs)):
        if value is not None and int(value) < 1:
            raise ValueError(f"{name} must be >= 1, got {value}")
    if int(seed) < 0:
        raise ValueError(f"seed must be >= 0, got {seed}")
    source = Path(hyperparams) if hyperparams is not None else hyperparams_path(algo)
    entry = {**read_entry(env_id, source), **(algo_kwargs or {})}
    hp = parse(entry, ALGORITHMS[algo], f"{source} [{env_id}]")
    config = TrainConfig(
        env_id=env_id, algo=algo,
        total_timesteps=int(total_timesteps or hp.n_timesteps), seed=int(seed),
        n_envs=int(n_envs or hp.n_envs), residual=hp.residual if residual is None else residual,
        residual_scale=hp.residual_scale, policy=hp.policy,
        env_kwargs={**hp.env_kwargs, **env_kwargs}, hyperparameters=hp.algo_kwargs,
        action_noise=list(hp.noise) if hp.noise else None, hyperparams_file=str(source),
        slipenv_version=version("slipenv"),
        stable_baselines3_version=version("stable_baselines3"),
    )
    return config, hp


def train(env_id: str, algo: str = "ppo", total_timesteps: int | None = None, seed: int = 0,
          n_envs: int | None = None, residual: bool | None = None, out: str | Path | None = None,
          progress: bool = False, algo_kwargs: dict | None = None,
          hyperparams: str | Path | None = None, checkpoint_freq: int | None = None,
          log_formats: tuple[str, ...] = ("csv", "tensorboard"), **env_kwargs: Any):
    """Train an agent; returns the SB3 model.

    Parameters
    ----------
    env_id : str
        A registered id.
    algo : {"ppo", "sac", "td3"}
    total_timesteps, n_envs : int, optional
        Default: the hyperparameter file's ``n_timesteps`` and ``n_envs``.
    seed : int
        Seeds the algorithm and the envs (env k gets ``seed + k``).
    residual : bool, optional
        Learn a residual on the baseline (default: the file's ``env_wrapper``).
    out : path, optional
        Run folder (see the module docstring); ``None`` saves nothing.
    progress : bool
        tqdm progress bar.
    algo_kwargs : dict, optional
        Overrides of the file's algorithm keys.
    hyperparams : path, optional
        An rl-zoo3 YAML file (default: the shipped ``hyperparams/<algo>.yml``).
    checkpoint_freq : int, optional
        Env steps between checkpoints (default: a quarter of the run); 0 disables them.
    log_formats : tuple of str
        SB3 logger outputs written to ``OUT/logs`` (add ``"stdout"`` for its tables).
    **env_kwargs
        ``gymnasium.make`` keyword arguments (override the file's ``env_kwargs``).
    """
    config, hp = resolve_config(env_id, algo, total_timesteps, seed, n_envs, residual,
                                hyperparams, algo_kwargs, **env_kwargs)
    run_dir = Path(out) if out is not None else None
    if run_dir is not None:
        run_dir.mkdir(parents=True, exist_ok=True)
        (run_dir / "config.json").write_text(json.dumps(asdict(config), indent=2) + "\n")
    t0 = time.perf_counter()

    def env_fn() -> gym.Env:
        return make_env(config.env_id, config.residual, config.residual_scale,
                        **config.env_kwargs)

    vec_cls = SubprocVecEnv if config.n_envs > 1 else DummyVecEnv
    if config.n_envs > 1:
        warm_up()  # the Lindgren EKF compiled once here, not by every worker on a cold cache
    vec = make_vec_env(env_fn, n_envs=config.n_envs, seed=config.seed, vec_env_cls=vec_cls)
    try:
        action_space = vec.action_space
        if not isinstance(action_space, gym.spaces.Box):
            raise TypeError(f"{config.env_id}: {algo} needs a Box action space, got "
                            f"{action_space}")
        kwargs = algo_kwargs_for_sb3(config.hyperparameters, action_space.shape[0], hp.noise)
        model = ALGORITHMS[algo](config.policy, vec, seed=config.seed, verbose=0, device="cpu",
                                 **kwargs)
        callbacks: list[BaseCallback] = []
        if run_dir is not None:
            model.set_logger(configure(str(run_dir / "logs"), list(log_formats)))
            freq = (max(config.total_timesteps // 4, 1) if checkpoint_freq is None
                    else int(checkpoint_freq))
            if freq > 0:
                callbacks.append(CheckpointCallback(max(freq // config.n_envs, 1),
                                                    str(run_dir / "checkpoints"), "model"))
        if progress:
            callbacks.append(TqdmProgress(config.total_timesteps))
        model.learn(total_timesteps=config.total_timesteps, callback=callbacks)
    finally:
        vec.close()
        if run_dir is not None and "model" in locals():
            model.logger.close()  # flush and close progress.csv and the TensorBoard writer
    if run_dir is not None:
        model.save(run_dir / "model")
        record = {**asdict(config), "wall_time_s": round(time.perf_counter() - t0, 2),
                  "timesteps_done": int(model.num_timesteps)}
        (run_dir / "config.json").write_text(json.dumps(record, indent=2) + "\n")
    return model


def load_policy(run: str | Path, env: gym.Env | None = None):
    """A trained run as a policy for the *plain* env (the residual composed with the baseline).

    Parameters
    ----------
    run : path
        A run folder (with ``config.json`` and ``model.zip``) or the ``.zip`` inside one.
    env : gymnasium.Env, optional
        The env the policy will drive: the baseline's gains come from its vehicle and path
        (needed for a residual run; default: ``gym.make`` of the run's env id and kwargs).

    Returns
    -------
    (policy, config) : (object with ``predict``, dict)
    """
    path = Path(run)
    folder = path.parent if path.suffix == ".zip" else path
    model_file = path if path.suffix == ".zip" else folder / "model.zip"
    config_file = folder / "config.json"
    if not model_file.is_file() or not config_file.is_file():
        raise ValueError(f"{run}: not a slipenv training run (needs model.zip and config.json)")
    config = json.loads(config_file.read_text())
    model = ALGORITHMS[config["algo"]].load(model_file, device="cpu")
    if not config.get("residual"):
        return model, config
    own = env is None
    env = env or make_env(config["env_id"], **config.get("env_kwargs", {}))
    try:
        baseline = baseline_controller(env)
    finally:
        if own:
            env.close()
    return ResidualPolicy(model, baseline, config.get("residual_scale", 0.3)), config


def evaluate(policy, env_id: str, n_episodes: int = 3, seed: int = 100,
             residual: bool = False, **env_kwargs: Any) -> Evaluation:
    """Evaluate ``policy`` (anything with SB3's ``predict``) over seeds ``seed .. seed+n-1``.

    ``policy="baseline"`` evaluates the baseline path follower itself. ``residual=True`` wraps
    the env for a model trained on the residual (its action is the residual).
    """
    if n_episodes < 1:
        raise ValueError(f"n_episodes must be >= 1, got {n_episodes}")
    env = make_env(env_id, residual, **env_kwargs)
    try:
        if isinstance(policy, str) and policy == "baseline":
            policy = baseline_controller(env)
        seeds = tuple(seed + k for k in range(n_episodes))
        returns, successes, abs_ct = [], [], []
        for s in seeds:
            traj = TrajectoryRecorder()
            result = rollout(env, policy, seed=s, recorders=[traj])
            returns.append(result.episode_return)
            successes.append(result.success)
            abs_ct.append(np.abs(traj.trajectory().cross_track_true_m))
    finally:
        env.close()
    steps = np.concatenate(abs_ct) if abs_ct else np.array([])
    return Evaluation(float(np.mean(returns)), float(np.std(returns)),
                      float(np.mean(steps)) if steps.size else float("nan"), n_episodes,
                      success_rate=float(np.mean(successes)), seeds=seeds,
                      returns=tuple(float(r) for r in returns))
