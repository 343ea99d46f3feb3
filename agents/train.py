"""Train and evaluate stable-baselines3 agents on slipenv tasks, next to the baseline.

:func:`train` reads the env's hyperparameters (rl-zoo3 YAML, :mod:`slipenv.agents.zoo`), builds
``n_envs`` envs (``SubprocVecEnv`` when more than one; wrapped for residual RL on the baseline
path follower if asked), and trains PPO, SAC or TD3 with a seeded setup. Everything lands in one
run folder::

    OUT/config.json          the exact configuration (env id and kwargs, algorithm,
                             hyperparameters, seed, versions) and, at the end, the wall time
    OUT/model.zip            the final model (a residual model's zip records its composition)
    OUT/interrupted.zip      the model so far, if the run was interrupted (Ctrl-C); then
                             config.json says ``"interrupted": true`` and ``timesteps_done``
    OUT/checkpoints/         model_<steps>_steps.zip along the run
    OUT/logs/progress.csv    SB3's training log; TensorBoard events beside it

:func:`evaluate` runs any policy with SB3's ``predict`` (an SB3 model, a slipenv controller, a
:class:`~slipenv.agents.residual.ResidualPolicy`) through the one rollout loop over distinct
seeds and reports the true cross-track error, so agents and the baseline are compared by the
same code. :func:`load_policy` turns a run folder back into a policy for the plain env.

SB3 trains whole rollouts: PPO collects ``n_steps × n_envs`` steps between updates, SAC and TD3
``train_freq × n_envs``, and ``learn`` stops at the first rollout that reaches the total. The
run's ``total_timesteps`` is therefore the request rounded up to whole rollouts
(:func:`planned_timesteps`), so what is printed and recorded is what runs; the request is kept
as ``requested_timesteps``. Rounding ``n_steps`` down instead would change the algorithm (its
advantage horizon and minibatch split) with the run length.
"""

from __future__ import annotations

import inspect
import json
import math
import os
import signal
import time
import warnings
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
from slipenv.envs.compiled import kernels_used, warm_up
from slipenv.pybullet_quiet import import_pybullet
from slipenv.rollout import TrajectoryRecorder, rollout

from .residual import ResidualActionWrapper, ResidualPolicy, residual_composition
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
    requested_timesteps: int
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


def planned_timesteps(algo: str, requested: int, n_envs: int, hyperparameters: dict) -> int:
    """Env steps SB3 will run for a request: rounded up to whole rollouts.

    PPO stops after the first rollout of ``n_steps × n_envs`` steps that reaches the total,
    SAC and TD3 after the first of ``train_freq × n_envs`` (a ``train_freq`` counted in
    episodes has no fixed length: the request is returned).
    """
    params = inspect.signature(ALGORITHMS[algo]).parameters
    if algo == "ppo":
        per_env = hyperparameters.get("n_steps", params["n_steps"].default)
    else:
        freq = hyperparameters.get("train_freq", params["train_freq"].default)
        if isinstance(freq, list | tuple):
            if len(freq) != 2 or str(freq[1]) != "step":
                return int(requested)
            freq = freq[0]
        per_env = freq
    rollout = int(per_env) * int(n_envs)
    return math.ceil(int(requested) / rollout) * rollout


def timesteps_note(config: TrainConfig) -> str | None:
    """One line saying why the run is longer than requested, or None if it is not."""
    if config.total_timesteps == config.requested_timesteps:
        return None
    unit = "n_steps" if config.algo == "ppo" else "train_freq"
    return (f"{config.requested_timesteps} steps requested; {config.algo} trains whole rollouts "
            f"of {unit} × n_envs, so {config.total_timesteps} will run")


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
    requested, envs = int(total_timesteps or hp.n_timesteps), int(n_envs or hp.n_envs)
    config = TrainConfig(
        env_id=env_id, algo=algo,
        total_timesteps=planned_timesteps(algo, requested, envs, hp.algo_kwargs),
        requested_timesteps=requested, seed=int(seed),
        n_envs=envs, residual=hp.residual if residual is None else residual,
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
          log_formats: tuple[str, ...] = ("csv", "tensorboard"),
          callbacks: list[BaseCallback] | None = None, **env_kwargs: Any):
    """Train an agent; returns the SB3 model.

    Parameters
    ----------
    env_id : str
        A registered id.
    algo : {"ppo", "sac", "td3"}
    total_timesteps, n_envs : int, optional
        Default: the hyperparameter file's ``n_timesteps`` and ``n_envs``. The steps run are
        ``total_timesteps`` rounded up to whole rollouts (:func:`planned_timesteps`).
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
    callbacks : list of SB3 callbacks, optional
        Run along the built-in ones.
    **env_kwargs
        ``gymnasium.make`` keyword arguments (override the file's ``env_kwargs``).

    Raises
    ------
    KeyboardInterrupt
        On Ctrl-C, after saving the model so far as ``OUT/interrupted.zip`` (see the module
        docstring).
    ValueError
        On bad arguments or hyperparameters (before any env is built where possible).

    Warns
    -----
    UserWarning
        When ``n_envs`` exceeds the CPU cores (the envs then share cores and run slower).
    """
    config, hp = resolve_config(env_id, algo, total_timesteps, seed, n_envs, residual,
                                hyperparams, algo_kwargs, **env_kwargs)
    run_dir = Path(out) if out is not None else None
    if run_dir is not None:
        run_dir.mkdir(parents=True, exist_ok=True)
        (run_dir / "interrupted.zip").unlink(missing_ok=True)  # an earlier run's, not this one's
        (run_dir / "config.json").write_text(json.dumps(asdict(config), indent=2) + "\n")
    t0 = time.perf_counter()

    def env_fn() -> gym.Env:
        return make_env(config.env_id, config.residual, config.residual_scale,
                        **config.env_kwargs)

    cores = os.cpu_count() or 1
    if config.n_envs > cores:
        warnings.warn(f"n_envs={config.n_envs} exceeds the {cores} CPU cores: the envs share "
                      f"them and train slower than n_envs={cores}", stacklevel=2)
    vec_cls = SubprocVecEnv if config.n_envs > 1 else DummyVecEnv
    if config.n_envs > 1:
        # the kernels this env uses compiled once here, not by every worker on a cold cache
        probe = env_fn()
        try:
            warm_up(kernels_used(probe))
        finally:
            probe.close()
    vec = make_vec_env(_IgnoringSigint(env_fn) if config.n_envs > 1 else env_fn,
                       n_envs=config.n_envs, seed=config.seed, vec_env_cls=vec_cls)
    interrupted = False
    try:
        action_space = vec.action_space
        if not isinstance(action_space, gym.spaces.Box):
            raise TypeError(f"{config.env_id}: {algo} needs a Box action space, got "
                            f"{action_space}")
        kwargs = algo_kwargs_for_sb3(config.hyperparameters, action_space.shape[0], hp.noise)
        try:
            model = ALGORITHMS[algo](config.policy, vec, seed=config.seed, verbose=0,
                                     device="cpu", **kwargs)
        except AssertionError as exc:  # SB3 checks some combinations only here
            raise ValueError(f"{hp.source}: {algo} rejects these hyperparameters: "
                             f"{str(exc).strip() or 'assertion failed'}") from None
        all_callbacks: list[BaseCallback] = []
        if run_dir is not None:
            model.set_logger(configure(str(run_dir / "logs"), list(log_formats)))
            freq = (max(config.total_timesteps // 4, 1) if checkpoint_freq is None
                    else int(checkpoint_freq))
            if freq > 0:
                all_callbacks.append(CheckpointCallback(max(freq // config.n_envs, 1),
                                                        str(run_dir / "checkpoints"), "model"))
        if progress:
            all_callbacks.append(TqdmProgress(config.total_timesteps))
        all_callbacks.extend(callbacks or [])
        try:
            model.learn(total_timesteps=config.total_timesteps, callback=all_callbacks)
        except KeyboardInterrupt:
            interrupted = True
            if run_dir is not None:  # the model so far, whatever step Ctrl-C hit
                model.save(run_dir / "interrupted")
                _write_record(run_dir, config, t0, model, interrupted=True)
            raise
    finally:
        _close(vec, quietly=interrupted)
        if run_dir is not None and "model" in locals():
            model.logger.close()  # flush and close progress.csv and the TensorBoard writer
    if run_dir is not None:
        model.save(run_dir / "model")
        _write_record(run_dir, config, t0, model)
    return model


def _write_record(run_dir: Path, config: TrainConfig, t0: float, model: BaseAlgorithm,
                  interrupted: bool = False) -> None:
    """``config.json`` completed with the wall time and the steps done."""
    record = {**asdict(config), "wall_time_s": round(time.perf_counter() - t0, 2),
              "timesteps_done": int(model.num_timesteps)}
    if interrupted:
        record["interrupted"] = True
    (run_dir / "config.json").write_text(json.dumps(record, indent=2) + "\n")


class _IgnoringSigint:
    """An env factory for ``SubprocVecEnv`` workers that leaves Ctrl-C to the main process.

    A terminal's Ctrl-C reaches every process of the group: workers that died of it would
    leave the main process nothing to save the model with, and print one traceback each.
    """

    def __init__(self, env_fn: Any) -> None:
        self.env_fn = env_fn

    def __call__(self) -> gym.Env:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        return self.env_fn()


def _close(vec: Any, quietly: bool) -> None:
    """Close the envs; after Ctrl-C a worker may already be gone, which must not hide it."""
    try:
        vec.close()
    except (EOFError, OSError):  # a broken pipe or a reset connection
        if not quietly:
            raise


def load_policy(run: str | Path, env: gym.Env | None = None):
    """A trained model as a policy for the *plain* env (a residual composed with its baseline).

    Parameters
    ----------
    run : path
        A run folder (with ``config.json`` and ``model.zip``), or a ``.zip`` -- inside a run
        folder or anywhere (the zip records a residual composition; without ``config.json``
        pass ``env``).
    env : gymnasium.Env, optional
        The env the policy will drive: the baseline's gains come from its vehicle and path
        (needed for a residual model; default: ``gym.make`` of the run's env id and kwargs).

    Returns
    -------
    (policy, config) : (object with ``predict``, dict)
        ``config`` is the run's ``config.json`` (``{"algo": ...}`` for a bare zip).

    Raises
    ------
    ValueError
        If ``run`` is not a model or run folder, or a residual model has no env to drive.
    """
    from slipenv.evaluation.policies import detect_algo

    path = Path(run)
    folder = path.parent if path.suffix == ".zip" else path
    model_file = path if path.suffix == ".zip" else folder / "model.zip"
    config_file = folder / "config.json"
    if not model_file.is_file() or (path.suffix != ".zip" and not config_file.is_file()):
        raise ValueError(f"{run}: not a slipenv training run (needs model.zip and config.json)")
    config = json.loads(config_file.read_text()) if config_file.is_file() else {}
    algo = config.get("algo") or detect_algo(model_file)
    config.setdefault("algo", algo)
    model = ALGORITHMS[algo].load(model_file, device="cpu")
    options = residual_composition(model)
    if options is None and config.get("residual"):  # saved before zips recorded it
        options = {"controller": "yamauchi", "scale": config.get("residual_scale", 0.3)}
    if options is None:
        return model, config
    if env is None and "env_id" not in config:
        raise ValueError(f"{run}: a residual model adds to a baseline whose gains come from "
                         "the env: pass env=")
    own = env is None
    env = env or make_env(config["env_id"], **config.get("env_kwargs", {}))
    try:
        scale, controller = options.pop("scale"), options.pop("controller")
        baseline = baseline_controller(env, controller, **options)
    finally:
        if own:
            env.close()
    return ResidualPolicy(model, baseline, scale), config


def evaluate(policy, env_id: str, n_episodes: int = 3, seed: int = 100,
             residual: bool = False, **env_kwargs: Any) -> Evaluation:
    """Evaluate ``policy`` (anything with SB3's ``predict``) over seeds ``seed .. seed+n-1``.

    ``policy="baseline"`` evaluates the baseline path follower itself. A model trained on the
    residual wrapper acts through it, with the composition its action space records;
    ``residual=True`` wraps the env (default scale) for one that records none.
    """
    if n_episodes < 1:
        raise ValueError(f"n_episodes must be >= 1, got {n_episodes}")
    options = None if isinstance(policy, str) else residual_composition(policy)
    env: gym.Env
    if options is not None:
        env = ResidualActionWrapper(make_env(env_id, **env_kwargs), **options)
    else:
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
